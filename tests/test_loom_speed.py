"""The whole machine at its highest speed (issue 14, part 5): the LP in (p, n) against bisection on
n with LP feasibility, against the closed form along the critical chain, and the hard cases.

Independent references: the rebound's root in t at 420 rpm by brentq on eq. (2) (the chain's
closed form uses it once, the bisection at every speed), the stress bound in closed form, the
flight's 0.006 n T, and the longest path of the exact bounds just above and below the answer."""
import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from mechopt import registry
from mechopt.models.errors import ModelError
from mechopt.models.loom import Cyclogram, lever_stop
from mechopt.solvers.loom import max_machine_speed, plan_cyclogram
from mechopt.solvers.result import Status
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm

CHAIN_FIXED_DEG = 20 + 10 + 15 + 5 + 20 + 15 + 25     # [phi] along 1-3-7-8-9-10-10.1-10.2-11-12-13-24


@pytest.fixture(scope="module")
def task():
    return registry.find("loom/machine-speed").build()[0]


@pytest.fixture(scope="module")
def lp(task):
    return max_machine_speed(task, method="lp")


def root_deg(lever_table, speed_rpm, limit_mm=0.1):
    lever = lever_stop(lever_table)
    return brentq(lambda t: rebound_amplitude_mm(lever, speed_rpm, t) - limit_mm, 1.0, 300.0, xtol=1e-13)


def longest_path(task, lb):
    """First -> last over the arcs with bounds lb, by relaxing in repeated passes (no networkx)."""
    dist = {task.first_event: 0.0}
    for _ in range(len(task.arcs)):
        changed = False
        for (x, y), w in zip(task.arcs, lb):
            if x in dist and dist[x] + w > dist.get(y, -np.inf):
                dist[y], changed = dist[x] + w, True
        if not changed:
            break
    return dist[task.last_event]


def exact_bounds(task, n_rpm):
    """Each arc's exact lower bound at speed n, computed here from the laws directly."""
    lb = np.array([d["min_deg"] for _, _, d in task.graph.edges(data=True)])
    for k, (x, y) in enumerate(task.arcs):
        d = task.graph.edges[x, y]
        if d["min_ms"] is not None:
            lb[k] = max(lb[k], 360.0 * n_rpm / 60.0 * d["min_ms"] / 1000.0)
        if d["stress"] is not None:
            ref = task.stress_models[d["stress"]]
            lb[k] = max(lb[k], ref["sigma_ref_MPa"] * ref["t_ref_deg"] * n_rpm / (800.0 * 420.0))
        if d["amplitude"] is not None:
            lb[k] = max(lb[k], root_deg(task.lever, n_rpm))
    return lb


def test_lp_and_bisection_agree_with_the_closed_form_of_the_critical_chain(task, lp):
    bis = max_machine_speed(task, method="bisection", rtol=1e-8)
    assert lp.status is Status.SOLVED and bis.status is Status.SOLVED
    g_amp = root_deg(task.lever, 420.0) / 420.0          # a = h(n / t): the root grows as n
    closed = (360.0 - CHAIN_FIXED_DEG) / (g_amp + 900 * 30 / (800 * 420) + 0.006 * 60.0)
    assert lp.values["max_speed_rpm"] == pytest.approx(closed, rel=1e-9)
    assert bis.values["max_speed_rpm"] == pytest.approx(closed, rel=1e-7)
    assert bis.diagnostics["bisection_steps"] > 20


def test_the_answer_fits_the_cycle_and_a_hair_more_does_not(task, lp):
    n = lp.values["max_speed_rpm"]
    assert longest_path(task, exact_bounds(task, n * (1 - 1e-7))) <= 360.0
    assert longest_path(task, exact_bounds(task, n * (1 + 1e-6))) > 360.0


def test_exact_laws_hold_at_the_highest_speed(task, lp):
    v, n = lp.values, lp.values["max_speed_rpm"]
    lever = lever_stop(task.lever)
    assert float(rebound_amplitude_mm(lever, n, v["t_3_7_deg"])) == pytest.approx(0.1, rel=1e-9)
    assert v["amplitude_3_7_mm"] == pytest.approx(0.1, rel=1e-9)
    assert v["sigma_9_10_MPa"] == pytest.approx(800.0, rel=1e-9)
    assert v["t_10.1_10.2_deg"] == pytest.approx(0.006 * 60.0 * n, rel=1e-9)
    assert v["cycle_time_ms"] == pytest.approx(60_000.0 / n)
    assert v["span_deg"] == pytest.approx(360.0, abs=1e-7)
    assert all(v[f"p_{x}_deg"] + v[f"t_{x}_{y}_deg"] == pytest.approx(v[f"p_{y}_deg"]) for x, y in task.arcs)


def test_limiting_group_constraint_and_cycle_sensitivity(task, lp):
    d = lp.diagnostics
    assert d["limiting_group"] == "flight" and d["limiting_constraint"] == "min_time[10.1->10.2]"
    assert {r["constraint"] for r in d["limiting"]} == {"amplitude[3->7]", "contact_stress[9->10]",
                                                         "min_time[10.1->10.2]"}
    wider = max_machine_speed(dataclasses.replace(task, cycle_deg=361.0))
    assert wider.values["max_speed_rpm"] - lp.values["max_speed_rpm"] == pytest.approx(
        d["sens_cycle_rpm_per_deg"], rel=1e-6)


def test_a_window_can_limit_the_speed_instead_of_the_cycle(task):
    windowed = dataclasses.replace(task, windows=[{"from": "1", "to": "10.1", "max_deg": 120.0}])
    lp, bis = (max_machine_speed(windowed, method=m) for m in ("lp", "bisection"))
    assert lp.status is Status.SOLVED and bis.status is Status.SOLVED
    assert lp.values["max_speed_rpm"] == pytest.approx(bis.values["max_speed_rpm"], rel=1e-6)
    g_amp = root_deg(task.lever, 420.0) / 420.0
    assert lp.values["max_speed_rpm"] == pytest.approx((120.0 - 50.0) / (g_amp + 900 * 30 / (800 * 420)), rel=1e-9)


def test_with_preload_the_rebound_is_not_proportional_and_the_lp_still_holds(task):
    """With the preload a(t, n) = h(n / t) is no longer h' r: the LP's r* comes from brentq on h."""
    lever = task.lever | {"effects": [*task.lever["effects"], "preload"], "preload_mm": 0.05}
    pre = dataclasses.replace(task, lever=lever)
    lp, bis = (max_machine_speed(pre, method=m, rtol=1e-8) for m in ("lp", "bisection"))
    assert lp.status is Status.SOLVED and bis.status is Status.SOLVED
    assert lp.values["max_speed_rpm"] == pytest.approx(bis.values["max_speed_rpm"], rel=1e-7)
    lever = lever_stop(lever)

    def a(n, t):
        return float(rebound_amplitude_mm(lever, n, t))
    assert abs(a(840.0, 40.0) / a(420.0, 40.0) - 2.0) > 1e-2      # not proportional to n / t: r* is a real root
    assert a(840.0, 80.0) == pytest.approx(a(420.0, 40.0), rel=1e-9)   # but a function of n / t alone


def test_a_machine_whose_groups_cannot_fit_any_speed_is_infeasible_naming_the_chain(task):
    small = dataclasses.replace(task, cycle_deg=100.0)
    for method in ("lp", "bisection"):
        r = max_machine_speed(small, method=method)
        assert r.status is Status.INFEASIBLE and r.values == {}
        assert r.message.startswith("no speed fits: conflicting chain")
        assert "cycle p(24) - p(1) <= 100 deg" in r.violated
        assert "needs 120 deg more" in r.message and "flight" in r.diagnostics["conflict_groups"]


def test_a_cycle_only_a_machine_at_rest_fits_is_infeasible():
    ops = [{"from": "a", "to": "b", "min_deg": 10.0}, {"from": "b", "to": "c", "min_deg": 0.0, "min_ms": 10.0}]
    task = Cyclogram(events={"a": {}, "b": {}, "c": {}}, operations=ops, speed_rpm=100.0, cycle_deg=10.0)
    for method in ("lp", "bisection"):
        r = max_machine_speed(task, method=method)
        assert r.status is Status.INFEASIBLE and r.message.startswith("no speed fits: conflicting chain t(a->b)")


def test_no_limit_growing_with_speed_is_unbounded_or_a_search_limit(task):
    ops = [{k: v for k, v in op.items() if k not in ("stress", "amplitude", "min_ms")} for op in task.operations]
    free = dataclasses.replace(task, operations=ops)
    assert max_machine_speed(free, method="lp").status is Status.UNBOUNDED
    r = max_machine_speed(free, method="bisection")
    assert r.status is Status.LIMIT and "search bound" in r.message and r.values == {}


def test_speed_needs_a_cycle_and_a_time_needs_a_speed(task):
    with pytest.raises(ModelError, match="cycle_deg") as err:
        max_machine_speed(dataclasses.replace(task, cycle_deg=None))
    assert err.value.key == "cycle_deg"
    with pytest.raises(ModelError, match=r"operations\[10\.1->10\.2\]\.min_ms needs speed_rpm") as err:
        dataclasses.replace(task, speed_rpm=None).min_angles_deg()
    assert err.value.key == "speed_rpm"


def test_a_time_floor_is_an_angle_at_the_task_s_speed():
    ops = [{"from": "a", "to": "b", "min_deg": 10.0, "min_ms": 50.0}, {"from": "b", "to": "c", "min_deg": 5.0}]
    task = Cyclogram(events={"a": {}, "b": {}, "c": {}}, operations=ops, speed_rpm=300.0)
    r = plan_cyclogram(task)
    assert r.values["t_a_b_deg"] == pytest.approx(300 / 60 * 360 * 0.050)        # 90 deg in 50 ms
    assert r.diagnostics["bound_source"]["a->b"] == "min_time"
    with pytest.raises(ModelError, match=r"min_ms=-1\.0: a minimum duration must be in \[0"):
        Cyclogram(events={"a": {}, "b": {}}, operations=[{"from": "a", "to": "b", "min_deg": 1.0, "min_ms": -1.0}])


def test_held_highs_model_agrees_with_the_cvxpy_lp_and_says_infeasible():
    from mechopt.solvers.loom import HeldLP, _Net
    task = registry.find("loom/group1").build()[0]
    net = _Net(task, "exact")
    held = HeldLP(len(net.names), net.tails, net.heads, first=net.first, last=net.last, with_cycle=True)
    status, p = held.solve(net.lb, cycle_deg=360.0)
    assert status is Status.SOLVED
    assert p[net.last] - p[net.first] == pytest.approx(plan_cyclogram(task).values["span_deg"], abs=1e-9)
    status, p = held.solve(net.lb * 1.1, cycle_deg=360.0)            # a re-solve on changed bounds
    assert status is Status.SOLVED and p[net.last] == pytest.approx(1.1 * 114.75, abs=1e-9)
    status, p = held.solve(net.lb, cycle_deg=100.0)
    assert status is Status.INFEASIBLE and p is None


def test_at_its_highest_speed_the_machine_s_longest_flight_is_the_flight_time(task, lp):
    """The other question at a given n (loom.repair_cyclogram, exact laws): the longest limiting
    operation. At the highest speed it shrinks to the flight's own 60 ms; at 420 rpm it is the
    cycle minus the chain's exact bounds."""
    from mechopt.solvers.loom import repair_cyclogram
    n = lp.values["max_speed_rpm"]
    at_max = repair_cyclogram(dataclasses.replace(task, speed_rpm=n), stress_form="exact")
    assert at_max.status is Status.SOLVED
    assert at_max.values["limiting_op_deg"] == pytest.approx(0.006 * 60.0 * n, rel=1e-7)
    at_420 = repair_cyclogram(task, stress_form="exact")
    assert at_420.values["limiting_op_deg"] == pytest.approx(360.0 - CHAIN_FIXED_DEG - root_deg(task.lever, 420.0)
                                                            - 900 * 30 / 800, abs=1e-6)
