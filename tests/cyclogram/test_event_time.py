"""The event-time LP of a network cyclogram (paper 004, problem (1)) on networks of its own: the
infeasible, unbounded and failed answers named, the cross-check against the longest path, the
compiled problem kept, and the hard cases (ties, zero and huge angles, an isolated event, 10^5 events)."""
import dataclasses

import cvxpy as cp
import numpy as np
import pytest
from longest_path import longest_path

from mechopt.benchmarks.loom import layered
from mechopt.kit.cache import clear as clear_caches
from mechopt.kit.errors import SolverError
from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import conflicts, lp_method, plan_cyclogram
from mechopt.solvers.cyclogram.graph import PositiveCycle


def net(edges, **kw):
    """A Cyclogram from (from, to, min_deg) triples."""
    names = dict.fromkeys(str(v) for e in edges for v in e[:2])
    return Cyclogram(events={v: {} for v in names} | kw.pop("extra_events", {}),
                     operations=[{"from": str(x), "to": str(y), "min_deg": float(w)} for x, y, w in edges], **kw)


# ---------------------------------------------------------------- infeasible, unbounded, failures

def test_an_amplitude_limit_the_cycle_cannot_hold_is_infeasible_and_says_so():
    task = net([(1, 2, 10), (2, 3, 20)], cycle_deg=60.0, amplitude_slope_mm_per_deg=-0.003,
               amplitude_intercept_mm=0.208, amplitude_limit_mm=0.01)
    task = dataclasses.replace(task, operations=[dict(task.operations[0], amplitude="linear"), task.operations[1]])
    r = plan_cyclogram(task)
    need = (0.208 - 0.01) / 0.003                          # 66 deg for the amplitude alone, cycle 60
    assert r.status is Status.INFEASIBLE and not r.values
    assert f"t(1->2) >= {need:.6g} deg (amplitude)" in r.message and "cycle p(3) - p(1) <= 60 deg" in r.message


def test_synchronised_events_and_a_window_shape_the_times():
    task = net([(1, 2, 10), (1, 3, 25), (2, 4, 10), (3, 4, 1)],
               syncs=[{"events": ["2", "3"]}], windows=[{"from": "1", "to": "4", "max_deg": 40.0}])
    r = plan_cyclogram(task)          # without the sync the span would be 26; with it 25 + 10
    assert r.values["p_2_deg"] == pytest.approx(r.values["p_3_deg"]) == pytest.approx(25.0)
    assert r.values["span_deg"] == pytest.approx(35.0) == r.values["longest_path_deg"]
    tight = plan_cyclogram(dataclasses.replace(task, windows=[{"from": "1", "to": "4", "max_deg": 30.0}]))
    assert tight.status is Status.INFEASIBLE and "sync p(3) = p(2)" in tight.message
    assert "window p(4) - p(1) <= 30 deg" in tight.message


def test_limiting_operation_without_a_cycle_is_unbounded_not_a_number():
    r = plan_cyclogram(net([(1, 2, 10), (2, 3, 20)], limiting_op=["2", "3"]))
    assert r.status is Status.UNBOUNDED and r.values == {} and "unbounded" in r.message


def test_cross_check_failure_is_inaccurate_not_solved(monkeypatch):
    monkeypatch.setattr(lp_method, "longest_certificate", lambda net: (-1.0, -1.0))
    r = plan_cyclogram(net([(1, 2, 10), (2, 3, 20)]), method="lp")
    assert r.status is Status.INACCURATE and r.values["span_deg"] == pytest.approx(30.0)
    assert r.message.startswith("cross-check failed: LP span_deg = 30.0 but the longest path on the graph "
                                "gives -1.0 (tolerance 1e-06 deg per degree above 1)")


def test_a_problem_that_would_recompile_is_refused(monkeypatch):
    clear_caches()
    monkeypatch.setattr(cp.Problem, "is_dpp", lambda self, *a, **k: False)
    with pytest.raises(SolverError, match=r"event-time LP is not DPP; what-if re-solves would recompile"):
        plan_cyclogram(net([(1, 2, 10), (2, 3, 20)]), method="lp")


def test_back_end_crash_is_failed_and_inaccurate_is_not_passed_on(monkeypatch):
    task = net([(1, 2, 10), (2, 3, 20)])
    plan_cyclogram(task, method="lp")

    def crash(self, *a, **k):
        raise cp.error.SolverError("HiGHS exploded")
    with monkeypatch.context() as m:
        m.setattr(cp.Problem, "solve", crash)
        r = plan_cyclogram(task, method="lp")
    assert r.status is Status.FAILED and r.values == {} and "HiGHS exploded" in r.message
    monkeypatch.setattr(lp_method, "from_cvxpy", lambda status: Status.INACCURATE)
    r = plan_cyclogram(task, method="lp")
    assert r.status is Status.INACCURATE and r.values == {}


# ---------------------------------------------------------------- hard cases

def test_degenerate_ties_mark_every_critical_chain():
    task = net([(1, 2, 10), (1, 3, 10), (2, 4, 20), (3, 4, 20), (1, 4, 5)])
    r = plan_cyclogram(task)
    assert r.values["span_deg"] == pytest.approx(30.0)
    assert set(r.diagnostics["critical_ops"]) == {"1->2", "1->3", "2->4", "3->4"}
    assert r.diagnostics["float_deg"]["1->4"] == pytest.approx(25.0)


def test_zero_angle_operations_give_zero_span():
    r = plan_cyclogram(net([(1, 2, 0), (2, 3, 0), (1, 3, 0)]))
    assert r.status is Status.SOLVED and r.values["span_deg"] == 0.0 and r.values["t_1_2_deg"] == 0.0


def test_huge_and_tiny_angles_in_one_network():
    edges = [(1, 2, 1e-6), (2, 4, 1e4), (1, 3, 1e4), (3, 4, 2e-6)]
    task = net(edges)
    r = plan_cyclogram(task)
    assert r.values["span_deg"] == pytest.approx(1e4 + 2e-6, rel=1e-12, abs=1e-9)
    assert r.values["span_deg"] == pytest.approx(longest_path(task), abs=1e-9)
    assert r.diagnostics["critical_chain"] == ["1", "3", "4"]


def test_an_isolated_event_is_reported_and_left_out():
    task = net([(1, 2, 10), (2, 3, 20)], extra_events={"spare": {}})
    r = plan_cyclogram(task)
    assert r.values["span_deg"] == pytest.approx(30.0)
    assert r.diagnostics["isolated_events"] == ["spare"] and "p_spare_deg" not in r.values


@pytest.mark.slow
def test_a_hundred_thousand_events_solve_once_to_the_longest_path():
    tails, heads, w = layered(100_000)
    task = Cyclogram(events={str(v): {} for v in range(100_000)},
                     operations=[{"from": str(a), "to": str(b), "min_deg": float(c)} for a, b, c in zip(tails, heads, w)])
    r = plan_cyclogram(task)
    # independent longest path in numpy, layer by layer (the arcs only go to the next layer or the sink)
    dist = np.full(100_000, -np.inf)
    dist[0] = 0.0
    order = np.argsort(heads, kind="stable")      # heads ascend with the layers
    for a, b, c in zip(tails[order], heads[order], w[order]):
        dist[b] = max(dist[b], dist[a] + c)
    assert r.status is Status.SOLVED and r.values["span_deg"] == pytest.approx(dist[-1], abs=1e-6)
    assert len(tails) > 250_000


def test_an_optimum_contradicting_a_positive_cycle_is_not_solved(monkeypatch):
    task = net([(1, 2, 10), (2, 3, 20)], windows=[{"from": "1", "to": "3", "max_deg": 40.0}])
    def cycle(net):
        raise PositiveCycle
    monkeypatch.setattr(lp_method, "longest_certificate", cycle)
    r = plan_cyclogram(task, method="lp")
    assert r.status is Status.INACCURATE and "longest_path_deg" not in r.values
    assert r.message.startswith("cross-check failed: the LP reports an optimum but the longest-path passes find a "
                                "positive cycle that the conflict search")


def test_positive_cycle_search_finds_tiny_cycles_and_ignores_round_off():
    arcs = [("a", "b", 0.1, "ab"), ("b", "c", 0.2, "bc"), ("c", "a", -0.3 + 1e-9, "ca")]
    cycle = conflicts.positive_cycle(arcs)
    assert sorted(label for *_, label in cycle) == ["ab", "bc", "ca"]
    zero = [("a", "b", 0.1, "ab"), ("b", "c", 0.2, "bc"), ("c", "a", -(0.1 + 0.2), "ca")]   # 0 up to round-off
    assert conflicts.positive_cycle(zero) == []
