"""The event-time LP of a network cyclogram (paper 004, problem (1)): published and derived values,
duals against finite differences, the LP certificate, DPP re-solves and the hard cases on the
loom's scenes (the engine's on networks of its own: tests/cyclogram/test_event_time.py).

Published: a(3,7) = -0.003 t(3,7) + 0.208 mm and the +-0.1 mm transfer accuracy (Podgorny et al.
2018, Results and discussion; Research methodology), so t(3,7) >= (0.208 - 0.1) / 0.003 = 36 deg."""
import dataclasses

import networkx as nx
import numpy as np
import pytest
from longest_path import longest_path

from mechopt import registry
from mechopt.kit.cache import clear as clear_caches
from mechopt.kit.result import Status
from mechopt.solvers.cyclogram import conflicts, lp_method, plan_cyclogram
from mechopt.solvers.cyclogram.net import Net

T_3_7_MIN_DEG = (0.208 - 0.1) / 0.003          # from the published law and limit


def scene_task(case):
    return registry.find(case).build()[0]


# ---------------------------------------------------------------- scenes

def test_group1_meets_the_published_amplitude_limit_exactly():
    r = plan_cyclogram(scene_task("loom/group1"))
    assert r.status is Status.SOLVED
    assert r.values["t_3_7_deg"] == pytest.approx(T_3_7_MIN_DEG, abs=1e-7)
    assert r.values["amplitude_3_7_mm"] == pytest.approx(0.1, abs=1e-10)
    assert r.values["span_deg"] == pytest.approx(longest_path(scene_task("loom/group1")), abs=1e-7)
    assert r.diagnostics["critical_chain"] == ["1", "3", "7", "8", "9", "10"]
    # the returner's cam sits on [sigma_H] = 800 MPa (assumed): sigma_max at the optimum is the limit
    assert r.values["sigma_9_10_MPa"] == pytest.approx(800.0)


def nx_longest_path_deg(task):
    """The minimal span, by networkx directly on the arcs weighted with their lower bounds."""
    g = nx.DiGraph()
    g.add_weighted_edges_from((x, y, w) for (x, y), w in zip(task.arcs, task.lower_bounds_deg()[0]))
    return nx.dag_longest_path_length(g)


def test_event_times_satisfy_every_operation_and_angles_are_time_differences():
    task = scene_task("loom/group1")
    r = plan_cyclogram(task)
    assert r.status is Status.SOLVED
    lb, _ = task.lower_bounds_deg()
    for (x, y), w in zip(task.arcs, lb):
        t = r.values[f"p_{y}_deg"] - r.values[f"p_{x}_deg"]
        assert t == pytest.approx(r.values[f"t_{x}_{y}_deg"]) and t >= w - 1e-7
    assert r.values["p_1_deg"] == 0.0
    # optimal, not only feasible: the span is the longest path, and the last event moved 1e-6 deg
    # earlier breaks an operation (no better times exist)
    assert r.values["span_deg"] == pytest.approx(nx_longest_path_deg(task), abs=1e-7)
    last = task.last_event
    earlier = r.values[f"p_{last}_deg"] - 1e-6
    assert any(earlier - r.values[f"p_{x}_deg"] < w - 1e-9 for (x, y), w in zip(task.arcs, lb) if y == last)


def test_float_is_latest_minus_earliest_minus_duration():
    r = plan_cyclogram(scene_task("loom/group1"))
    fl = r.diagnostics["float_deg"]
    # by hand: 1-2-6-8 needs 10 + 40 + 5 = 55 of the 66 deg to event 8; 3-4-5-8 needs 5 + 20 + 15 of 46
    assert fl["1->2"] == pytest.approx(11.0) and fl["2->6"] == pytest.approx(11.0)
    assert fl["3->4"] == pytest.approx(6.0) and fl["5->8"] == pytest.approx(6.0)
    assert set(r.diagnostics["critical_ops"]) == {"1->3", "3->7", "7->8", "8->9", "9->10"}


def test_machine_gives_the_cycle_left_by_the_compressed_groups_to_the_limiting_operation():
    task = scene_task("loom/machine")
    r = plan_cyclogram(task)
    lb, _ = task.lower_bounds_deg()
    before = 20 + T_3_7_MIN_DEG + 10 + 15 + 900 * 30 / 800 + 5      # group 1 and the pick (scene's numbers)
    after = 20 + 15 + 25 + 0
    assert r.values["limiting_op_deg"] == pytest.approx(task.cycle_deg - before - after, abs=1e-7)
    assert r.values["span_group1_deg"] == pytest.approx(plan_cyclogram(scene_task("loom/group1")).values["span_deg"])
    assert r.values["span_deg"] == pytest.approx(360.0) and r.values["sens_cycle_deg_per_deg"] == pytest.approx(1.0)
    assert ["10.1", "10.2"] == r.diagnostics["critical_chain"][6:8]


def test_exact_and_linearised_stress_differ_by_the_tangent_gap_and_the_linear_optimum_is_overstressed():
    exact = plan_cyclogram(scene_task("loom/group1"), stress_form="exact")
    linear = plan_cyclogram(scene_task("loom/group1"), stress_form="linear")
    gap = 900 * 30 / 800 - 30 * (2 - 800 / 900)             # on the critical returner stroke (9, 10)
    assert exact.values["span_deg"] - linear.values["span_deg"] == pytest.approx(gap, abs=1e-7)
    assert linear.violated == ("contact_stress[9->10]",) and exact.violated == ()
    assert linear.values["sigma_9_10_MPa"] > 800.0 and "exceed [sigma_H]" in linear.message


@pytest.mark.parametrize("case", ["loom/group1", "loom/machine"])
def test_clarabel_agrees_with_highs(case):
    a = plan_cyclogram(scene_task(case), method="lp", backend="HIGHS")
    b = plan_cyclogram(scene_task(case), method="lp", backend="CLARABEL")
    key = "limiting_op_deg" if case.endswith("machine") else "span_deg"
    assert b.status is Status.SOLVED and b.values[key] == pytest.approx(a.values[key], abs=1e-6)


# ---------------------------------------------------------------- duals against finite differences

def _objective(task, **change):
    r = plan_cyclogram(dataclasses.replace(task, **change))
    assert r.status is Status.SOLVED
    return r.values.get("limiting_op_deg", r.values["span_deg"])


@pytest.mark.parametrize("case", ["loom/group1", "loom/machine"])
def test_sensitivities_match_a_finite_difference_re_solve(case):
    task = scene_task(case)
    r = plan_cyclogram(task)
    h = 1e-3
    for key, sens in (("sigma_H_limit_MPa", "sens_sigma_H_deg_per_MPa"),
                      ("amplitude_limit_mm", "sens_amplitude_limit_deg_per_mm")):
        base = getattr(task, key)
        h_key = h * base
        fd = (_objective(task, **{key: base + h_key}) - _objective(task, **{key: base - h_key})) / (2 * h_key)
        assert r.values[sens] == pytest.approx(fd, rel=1e-3), key
    # one degree more [phi] on the critical (7, 8) moves the objective by the dual (+1 span, -1 limiting op)
    ops = [dict(op, min_deg=op["min_deg"] + 1.0) if (op["from"], op["to"]) == ("7", "8") else op
           for op in task.operations]
    fd = _objective(task, operations=ops) - _objective(task)
    assert r.diagnostics["sens_min_deg"]["7->8"] == pytest.approx(fd, abs=1e-7) == (-1.0 if "machine" in case else 1.0)


def test_sign_convention_looser_limits_shorten_the_span():
    r = plan_cyclogram(scene_task("loom/group1"))
    assert r.values["sens_sigma_H_deg_per_MPa"] == pytest.approx(-900 * 30 / 800**2)     # d(K/sigma)/d(sigma)
    assert r.values["sens_amplitude_limit_deg_per_mm"] == pytest.approx(1 / -0.003)


def test_lp_certificate_primal_feasible_dual_nonnegative_complementary():
    task = scene_task("loom/group1")
    clear_caches()
    r = plan_cyclogram(task, method="lp")
    [lp] = lp_method.LP_BUILDS.values()
    duals = {}
    for name in ("min_angle", "contact_stress", "amplitude"):
        con = lp.blocks[name]
        dual = duals[name] = np.asarray(con.dual_value).ravel()
        slack = np.abs(np.asarray(con.expr.value).ravel())     # cvxpy keeps each as expr <= 0 (or >= rearranged)
        assert (dual >= -1e-9).all(), name
        assert np.max(np.asarray(con.violation()).ravel()) <= 1e-7, name
        assert np.max(np.abs(dual * slack)) <= 1e-6, name
    # stationarity, the part that makes it optimal: the duals' flow into each event (incidence built
    # here from the task's arcs) is the objective's gradient, 1 at the last event, 0 elsewhere
    # (the first event's is the anchor's multiplier)
    names = task.event_names
    D = np.zeros((len(task.arcs), len(names)))
    for k, (x, y) in enumerate(task.arcs):
        D[k, names.index(y)], D[k, names.index(x)] = 1.0, -1.0
    flow = D.T @ duals["min_angle"] + D[task.stress_arcs()].T @ duals["contact_stress"]
    flow -= task.amplitude_slope_mm_per_deg * D[task.amplitude_arcs()].T @ duals["amplitude"]
    gradient = np.array([1.0 if v == task.last_event else 0.0 for v in names])
    keep = [i for i, v in enumerate(names) if v != task.first_event]
    assert np.allclose(flow[keep], gradient[keep], atol=1e-6)
    assert r.values["span_deg"] == pytest.approx(nx_longest_path_deg(task), abs=1e-7)


# ---------------------------------------------------------------- DPP re-solve

def test_a_limit_change_reuses_the_compiled_problem_and_gives_the_fresh_answer():
    task = scene_task("loom/group1")
    plan_cyclogram(task, method="lp")
    tighter = dataclasses.replace(task, amplitude_limit_mm=0.05)
    again = plan_cyclogram(tighter, method="lp")
    assert again.diagnostics["compiled_now"] is False      # re-solved, not rebuilt (speed is benched, not tested)
    assert again.values["t_3_7_deg"] == pytest.approx((0.208 - 0.05) / 0.003, abs=1e-7)
    clear_caches()
    fresh = plan_cyclogram(tighter, method="lp")
    assert fresh.diagnostics["compiled_now"] is True
    assert fresh.values["span_deg"] == pytest.approx(again.values["span_deg"], abs=1e-9)


def test_scene_override_of_a_limit_is_a_what_if():
    run = registry.run(registry.find("loom/group1"), {"amplitude_limit_mm": 0.13})
    # amplitude needs only 26 deg now; the lift cam's stress bound 700 * 36 / 800 = 31.5 deg takes over
    assert run.checks == [] and run.result.values["t_3_7_deg"] == pytest.approx(31.5, abs=1e-7)
    assert run.result.diagnostics["bound_source"]["3->7"] == "contact_stress"


# ---------------------------------------------------------------- infeasible, unbounded, failures

def test_window_conflict_names_the_positive_cycle():
    run = registry.run(registry.find("loom/group1-window-conflict"))
    r = run.result
    assert r.status is Status.INFEASIBLE and r.values == {} and run.ok
    assert "window p(8) - p(3) <= 40 deg" in r.message and "t(3->7) >= 36 deg (amplitude)" in r.message
    assert "t(7->8) >= 10 deg (min_angle)" in r.message and sorted(r.diagnostics["conflict_events"]) == ["3", "7", "8"]


# ---------------------------------------------------------------- hard cases


def test_gantt_figure_is_written_for_a_solved_scene_and_skipped_for_an_infeasible_one(tmp_path):
    from mechopt.figures import plot_run
    paths = plot_run(registry.run(registry.find("loom/group1")), tmp_path)
    assert [p.name for p in paths] == ["loom_group1_cyclogram.png"] and paths[0].stat().st_size > 10_000
    assert plot_run(registry.run(registry.find("loom/group1-window-conflict")), tmp_path) == []


def test_infeasible_without_a_positive_cycle_says_it_may_be_numerical(monkeypatch):
    monkeypatch.setattr(lp_method, "conflict_chain", lambda net: [])
    r = plan_cyclogram(scene_task("loom/group1-window-conflict"), method="lp")
    assert r.status is Status.INFEASIBLE and r.values == {}
    assert r.message == "HIGHS: infeasible (no positive cycle among the difference constraints: a numerical failure?)"


# ---------------------------------------------------------------- certificates

def _chain_excess_deg(task, events):
    """Sum round the cycle `events` of the bounds p(v) - p(u) >= w it follows, from the scene's own
    data: an operation's lower bound, or minus the machine cycle on the arc last -> first."""
    lb = dict(zip(task.arcs, task.lower_bounds_deg()[0]))
    total = 0.0
    for u, v in zip(events, events[1:] + events[:1]):
        if (u, v) in lb:
            total += lb[u, v]
        else:
            assert (u, v) == (task.last_event, task.first_event), (u, v)
            total -= task.cycle_deg
    return total


def test_machine_made_infeasible_by_an_override_names_a_real_positive_cycle():
    run = registry.run(registry.find("loom/machine"), {"operations[from=12,to=13].min_deg": 300.0})
    r = run.result
    assert r.status is Status.INFEASIBLE and r.values == {}
    assert "numerical failure" not in r.message and r.message.startswith("infeasible: conflicting chain ")
    events = r.diagnostics["conflict_events"]
    excess = _chain_excess_deg(run.task, events)
    # independent: 1 -> 21 -> 10.1 -> 10.2 -> 11 -> 12 -> 13 -> 24 needs 60 + 100 + 20 + 15 + 300 = 495 of 360
    assert excess > 0 and excess == pytest.approx(r.diagnostics["conflict_excess_deg"], abs=1e-9)
    assert ("12", "13") in set(zip(events, events[1:])) and "t(12->13) >= 300 deg (min_angle)" in r.message
    assert "cycle p(24) - p(1) <= 360 deg" in r.message and len(r.violated) == len(events)


def test_networkx_negative_cycle_extraction_is_not_relied_on():
    # the machine's cycle made infeasible: networkx's find_negative_cycle detects but cannot extract it
    # from a root joined to every event (networkx issue #5916); our search must name it
    task = registry.find("loom/machine").build({"operations[from=12,to=13].min_deg": 300.0})[0]
    chain = conflicts.conflict_chain(Net(task, "exact"))
    assert chain and _chain_excess_deg(task, [v for v, _, _ in chain]) > 0


@pytest.mark.parametrize("backend", ["CLARABEL", "HIGHS"])
def test_a_cycle_1e7_deg_too_short_is_infeasible_whatever_the_back_end_says(backend):
    task = scene_task("loom/machine")
    lb = dict(zip(task.arcs, task.lower_bounds_deg()[0]))
    # independent: the longest chain through the flight at its 100 deg floor, by networkx directly
    g = nx.DiGraph()
    g.add_weighted_edges_from((x, y, w) for (x, y), w in lb.items())
    need = nx.dag_longest_path_length(g)
    assert need == pytest.approx(279.75)
    tight = dataclasses.replace(task, cycle_deg=need - 1e-7)
    short = plan_cyclogram(tight, method="lp", backend=backend)
    assert short.status is Status.INFEASIBLE and short.values == {}
    assert short.diagnostics["conflict_excess_deg"] == pytest.approx(1e-7, rel=1e-6)
    assert _chain_excess_deg(tight, short.diagnostics["conflict_events"]) == pytest.approx(1e-7, rel=1e-6)
    ok = plan_cyclogram(dataclasses.replace(task, cycle_deg=need + 1e-7), method="lp", backend=backend)
    assert ok.status is Status.SOLVED and ok.values["limiting_op_deg"] == pytest.approx(100.0 + 1e-7, abs=1e-6)


def test_clarabel_reporting_optimal_on_a_positive_cycle_is_overruled():
    task = dataclasses.replace(scene_task("loom/machine"), cycle_deg=279.75 - 1e-7)
    r = plan_cyclogram(task, method="lp", backend="CLARABEL")
    if r.diagnostics["solver_status"] == "optimal":          # what the audit saw; the certificate overrules it
        assert "CLARABEL reported optimal, the longest-path certificate overrules it" in r.message
    assert r.status is Status.INFEASIBLE


