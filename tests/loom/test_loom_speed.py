"""The whole machine at its highest speed: the graph (the default; its own tests in
test_loom_speed_graph.py) and the LP in (p, n) against bisection on n with LP feasibility, against
the closed form along the critical chain, and the hard cases on the loom's machine (on networks of
their own: tests/cyclogram/test_speed.py).

The scene's lever is the chain (cam -> approach velocity -> impact -> eq. (2)): a(t, n) = h(n / t),
wavy. Independent references: the chain's crossing T of 0.1 mm at 420 rpm by brentq in [38.6,
38.7] deg, with a <= 0.1 mm checked on a 0.5 deg grid above it and a > 0.1 mm at the wiggle's
minimum below; the stress bound in closed form; the flight's 0.006 n T; the longest path of the
exact bounds just above and below the answer. The bisection route (the general one, for laws not
of n / t) on the earlier fitted lever (tests/stop_impact_fitted.py) and on a law of n^2 / t."""
import dataclasses

import numpy as np
import pytest
from longest_path import longest_path
from scipy.optimize import brentq
from stop_impact_fitted import FREE, J_A_FITTED_KGM2, LEVER

import mechopt.solvers.loom.repair as loom_solver
from mechopt import clear_caches, registry
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.loom_limits import lever_stop
from mechopt.solvers.cyclogram import max_machine_speed, plan_cyclogram
from mechopt.solvers.loom import exact_amplitude_bound
from mechopt.solvers.stop_impact.law import RollerLeftCam, rebound_amplitude_mm

CHAIN_FIXED_DEG = 20 + 10 + 15 + 5 + 20 + 15 + 25     # [phi] along 1-3-7-8-9-10-10.1-10.2-11-12-13-24
STRESS_9_10_DEG_PER_RPM = 900 * 30 / (800 * 420)
FLIGHT_DEG_PER_RPM = 0.006 * 60.0
FITTED_LEVER = {k: v for k, v in LEVER.items() if k != "t_deg"} | {
    "inertia_A_kgm2": J_A_FITTED_KGM2, "damping_ratio": 0.05, "effects": list(FREE)}


@pytest.fixture(scope="module")
def task():
    return registry.find("loom/machine-speed").build()[0]


@pytest.fixture(scope="module")
def lp(task):
    return max_machine_speed(task)


@pytest.fixture(scope="module")
def chain_T(task):
    """The smallest t beyond which the chain keeps a <= 0.1 mm up to 60 deg at 420 rpm [deg]."""
    lever = lever_stop(task.lever)

    def a(t):
        return float(rebound_amplitude_mm(lever, 420.0, t))
    root = brentq(lambda t: a(t) - 0.1, 38.6, 38.7, xtol=1e-13)
    assert all(a(t) <= 0.1 for t in np.arange(38.7, 60.01, 0.5))
    assert a(36.4) > 0.1 and a(38.0) > 0.1          # the wiggle: over the limit below the root
    return root


def closed_form_rpm(g_amp_deg_per_rpm, span_deg=360.0 - CHAIN_FIXED_DEG):
    """n along the critical chain: [phi] plus n (g_amp + g_stress + g_flight) fills the cycle."""
    return span_deg / (g_amp_deg_per_rpm + STRESS_9_10_DEG_PER_RPM + FLIGHT_DEG_PER_RPM)


def exact_bounds(task, n_rpm, T_deg):
    """Each arc's exact lower bound at speed n, computed here from the laws directly (the
    rebound's: T n / 420, as a = h(n / t))."""
    lb = np.array([d["min_deg"] for _, _, d in task.graph.edges(data=True)])
    for k, (x, y) in enumerate(task.arcs):
        d = task.graph.edges[x, y]
        if d["min_ms"] is not None:
            lb[k] = max(lb[k], 360.0 * n_rpm / 60.0 * d["min_ms"] / 1000.0)
        if d["stress"] is not None:
            ref = task.stress_models[d["stress"]]
            lb[k] = max(lb[k], ref["sigma_ref_MPa"] * ref["t_ref_deg"] * n_rpm / (800.0 * 420.0))
        if d["amplitude"] is not None:
            lb[k] = max(lb[k], T_deg * n_rpm / 420.0)
    return lb


def test_auto_takes_the_graph_because_the_chain_is_a_function_of_n_over_t(task, lp):
    assert lp.status is Status.SOLVED and lp.diagnostics["method"] == "graph"
    assert lp.diagnostics["n_over_t_probe_rel"] <= 1e-9 and "every law a function of n / t" in lp.message
    lever = lever_stop(task.lever)                       # an independent point: (45 deg, 500 rpm) against half
    assert float(rebound_amplitude_mm(lever, 250.0, 22.5)) == pytest.approx(
        float(rebound_amplitude_mm(lever, 500.0, 45.0)), rel=1e-12)


def test_lp_agrees_with_the_closed_form_of_the_critical_chain(lp, chain_T):
    assert lp.values["max_speed_rpm"] == pytest.approx(closed_form_rpm(chain_T / 420.0), rel=1e-9)
    assert lp.values["t_3_7_deg"] == pytest.approx(chain_T * lp.values["max_speed_rpm"] / 420.0, rel=1e-9)


def test_the_answer_fits_the_cycle_and_a_hair_more_does_not(task, lp, chain_T):
    n = lp.values["max_speed_rpm"]
    assert longest_path(task, exact_bounds(task, n * (1 - 1e-7), chain_T)) <= 360.0
    assert longest_path(task, exact_bounds(task, n * (1 + 1e-6), chain_T)) > 360.0


def test_exact_laws_hold_at_the_highest_speed_on_the_stated_range(task, lp):
    v, n = lp.values, lp.values["max_speed_rpm"]
    lever = lever_stop(task.lever)
    assert float(rebound_amplitude_mm(lever, n, v["t_3_7_deg"])) == pytest.approx(0.1, rel=1e-9)
    assert v["amplitude_3_7_mm"] == pytest.approx(0.1, rel=1e-9)
    assert v["amplitude_holds_from_3_7_deg"] == pytest.approx(v["t_3_7_deg"], rel=1e-12)
    assert v["amplitude_holds_to_3_7_deg"] == pytest.approx(60.0 * n / 420.0, rel=1e-12)
    assert max(float(rebound_amplitude_mm(lever, n, t)) for t in (45.0, 50.0, 60.0)) <= 0.1
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


def test_the_roller_leaving_its_cam_bounds_the_angle_and_says_so(task):
    """With a 10 mm limit the rebound never binds: the walk down from 60 deg stops where the
    roller leaves its cam (about 420 / 14.36 rpm/deg = 29.2 deg, 1500 N closure)."""
    loose = dataclasses.replace(task, amplitude_limit_mm=10.0)
    b = exact_amplitude_bound(loose, 420.0, 20.0, 40.0, 1.0)
    assert b.why == "roller_left" and "roller_left" in b.statement()
    assert 28.0 < b.from_deg < 30.5
    lever = lever_stop(task.lever)
    with pytest.raises(RollerLeftCam):
        rebound_amplitude_mm(lever, 420.0, b.from_deg * (1 - 1e-6))
    assert float(rebound_amplitude_mm(lever, 420.0, b.from_deg * (1 + 1e-6))) < 10.0


def test_on_the_fitted_n_over_t_lever_lp_and_bisection_agree_with_the_closed_form(task):
    fitted = dataclasses.replace(task, lever=FITTED_LEVER)
    lp, bis = max_machine_speed(fitted, method="lp"), max_machine_speed(fitted, method="bisection", rtol=1e-8,
                                                                        scan_step_deg=2.0)
    assert lp.diagnostics["method"] == "lp" and bis.status is Status.SOLVED
    root = brentq(lambda t: float(rebound_amplitude_mm(lever_stop(FITTED_LEVER), 420.0, t)) - 0.1, 1.0, 300.0,
                  xtol=1e-13)
    assert lp.values["max_speed_rpm"] == pytest.approx(closed_form_rpm(root / 420.0), rel=1e-9)
    assert bis.values["max_speed_rpm"] == pytest.approx(closed_form_rpm(root / 420.0), rel=1e-7)
    assert bis.diagnostics["bisection_steps"] > 20
    windowed = dataclasses.replace(fitted, windows=[{"from": "1", "to": "10.1", "max_deg": 120.0}])
    lp, bis = (max_machine_speed(windowed, method=m, scan_step_deg=2.0) for m in ("lp", "bisection"))
    assert lp.values["max_speed_rpm"] == pytest.approx(bis.values["max_speed_rpm"], rel=1e-6)
    assert lp.values["max_speed_rpm"] == pytest.approx((120.0 - 50.0) / (root / 420.0 + STRESS_9_10_DEG_PER_RPM),
                                                       rel=1e-9)


def test_a_law_not_of_n_over_t_is_solved_by_bisection_and_the_lp_would_be_wrong(task, monkeypatch):
    """a = 0.1 (n / 420)^2 (40 / t): the bound 40 (n / 420)^2 deg grows as n^2, so along the
    chain 250 = 40 n^2 / 420^2 + (g_stress + g_flight) n, a quadratic."""
    def squared(lever, speed_rpm, t_deg, lost=None):
        return 0.1 * (np.asarray(speed_rpm, float) / 420.0) ** 2 * 40.0 / np.asarray(t_deg, float)
    monkeypatch.setattr(loom_solver, "rebound_amplitude_mm", squared)
    clear_caches()
    auto, forced = max_machine_speed(task, rtol=1e-9), max_machine_speed(task, method="lp")
    clear_caches()
    qa, qb = 40.0 / 420.0**2, STRESS_9_10_DEG_PER_RPM + FLIGHT_DEG_PER_RPM
    exact = (-qb + np.sqrt(qb * qb + 4 * qa * 250.0)) / (2 * qa)
    assert auto.diagnostics["method"] == "bisection" and "not a function of n / t" in auto.message
    assert auto.diagnostics["n_over_t_probe_rel"] > 0.1
    assert auto.values["max_speed_rpm"] == pytest.approx(exact, rel=1e-7)
    assert auto.values["t_3_7_deg"] == pytest.approx(40.0 * (exact / 420.0) ** 2, rel=1e-6)
    assert abs(forced.values["max_speed_rpm"] / exact - 1) > 1e-3          # the (p, n) LP assumes n / t


def test_a_machine_whose_groups_cannot_fit_any_speed_is_infeasible_naming_the_chain(task):
    small = dataclasses.replace(task, cycle_deg=100.0)
    for method in ("graph", "lp", "bisection"):
        r = max_machine_speed(small, method=method)
        assert r.status is Status.INFEASIBLE and r.values == {}
        assert r.message.startswith("no speed fits: conflicting chain")
        assert "cycle p(24) - p(1) <= 100 deg" in r.violated
        assert "needs 120 deg more" in r.message and "flight" in r.diagnostics["conflict_groups"]


def test_no_limit_growing_with_speed_is_unbounded_or_a_search_limit(task):
    ops = [{k: v for k, v in op.items() if k not in ("stress", "amplitude", "min_ms")} for op in task.operations]
    free = dataclasses.replace(task, operations=ops)
    assert max_machine_speed(free, method="lp").status is Status.UNBOUNDED
    assert max_machine_speed(free, method="graph").status is Status.UNBOUNDED
    r = max_machine_speed(free, method="bisection")
    assert r.status is Status.LIMIT and "search bound" in r.message and r.values == {}


def test_speed_needs_a_cycle_and_a_time_needs_a_speed(task):
    with pytest.raises(ModelError, match="cycle_deg") as err:
        max_machine_speed(dataclasses.replace(task, cycle_deg=None))
    assert err.value.key == "cycle_deg"
    with pytest.raises(ModelError, match=r"operations\[10\.1->10\.2\]\.min_ms needs speed_rpm") as err:
        dataclasses.replace(task, speed_rpm=None).min_angles_deg()
    assert err.value.key == "speed_rpm"


def test_held_highs_model_agrees_with_the_cvxpy_lp_and_says_infeasible():
    from mechopt.solvers.cyclogram import HeldLP
    from mechopt.solvers.cyclogram.net import Net
    task = registry.find("loom/group1").build()[0]
    net = Net(task, "exact")
    held = HeldLP(len(net.names), net.tails, net.heads, first=net.first, last=net.last, with_cycle=True)
    status, p = held.solve(net.lb, cycle_deg=360.0)
    assert status is Status.SOLVED
    assert p[net.last] - p[net.first] == pytest.approx(plan_cyclogram(task).values["span_deg"], abs=1e-9)
    status, p = held.solve(net.lb * 1.1, cycle_deg=360.0)            # a re-solve on changed bounds
    assert status is Status.SOLVED and p[net.last] == pytest.approx(1.1 * 114.75, abs=1e-9)
    status, p = held.solve(net.lb, cycle_deg=100.0)
    assert status is Status.INFEASIBLE and p is None


def test_at_its_highest_speed_the_machine_s_longest_flight_is_the_flight_time(task, lp, chain_T):
    """The other question at a given n (loom.repair_cyclogram, exact laws): the longest limiting
    operation. At the highest speed it shrinks to the flight's own 60 ms; at 420 rpm it is the
    cycle minus the chain's exact bounds."""
    from mechopt.solvers.loom import repair_cyclogram
    n = lp.values["max_speed_rpm"]
    at_max = repair_cyclogram(dataclasses.replace(task, speed_rpm=n), stress_form="exact")
    assert at_max.status is Status.SOLVED
    assert at_max.values["limiting_op_deg"] == pytest.approx(0.006 * 60.0 * n, rel=1e-7)
    at_420 = repair_cyclogram(task, stress_form="exact")
    assert at_420.values["limiting_op_deg"] == pytest.approx(360.0 - CHAIN_FIXED_DEG - chain_T
                                                            - 900 * 30 / 800, abs=1e-6)


