"""The machine's highest speed on the graph: Newton on the positive cycles
against the LP in (p, n) (same speed to 1e-9 relative) and bisection, on the loom's scenes and
the benchmark's machine (random networks with windows and syncs: tests/cyclogram/test_speed.py);
the limiting cycle named, the ranging at the highest speed against the closed form along the chain."""
import dataclasses

import pytest

from mechopt import registry
from mechopt.benchmarks.loom import machine
from mechopt.kit.result import Status
from mechopt.solvers.cyclogram import max_machine_speed, plan_cyclogram

CHAIN_FIXED_DEG = 20 + 10 + 15 + 5 + 20 + 15 + 25     # [phi] along loom/machine-speed's critical chain
STRESS_9_10_DEG_PER_RPM = 900 * 30 / (800 * 420)
FLIGHT_DEG_PER_RPM = 0.006 * 60.0


@pytest.fixture(scope="module")
def task():
    return registry.find("loom/machine-speed").build()[0]


@pytest.fixture(scope="module")
def graph(task):
    return max_machine_speed(task, method="graph", check=True)


@pytest.mark.parametrize("case, rpm", [("loom/machine-speed", 469.556), ("loom/machine-speed-paper-reading", 475.106)])
def test_the_scenes_speed_on_the_graph_is_the_lp_s(case, rpm):
    task = registry.find(case).build()[0]
    auto, lp = max_machine_speed(task), max_machine_speed(task, method="lp")
    assert auto.status is Status.SOLVED and auto.diagnostics["method"] == "graph"
    assert auto.values["max_speed_rpm"] == pytest.approx(lp.values["max_speed_rpm"], rel=1e-9)
    assert round(auto.values["max_speed_rpm"], 3) == rpm
    for key in ("span_deg", "limiting_op_deg", "t_3_7_deg", "sigma_9_10_MPa", "amplitude_3_7_mm"):
        assert auto.values[key] == pytest.approx(lp.values[key], rel=1e-9, abs=1e-9)


def test_check_runs_the_lp_and_says_so(graph):
    assert graph.status is Status.SOLVED and "checked by the LP in (p, n)" in graph.message
    lp = max_machine_speed(registry.find("loom/machine-speed").build()[0], method="lp", check=True)
    assert lp.status is Status.SOLVED and "checked by the graph" in lp.message
    assert graph.diagnostics["check"]["status"] == "SOLVED" and graph.diagnostics["check"]["rel"] <= 1e-9


def test_the_limiting_cycle_is_named_in_the_designer_s_words(graph):
    cycle = graph.diagnostics["limiting_cycle"]
    assert cycle[-1] == "cycle p(24) - p(1) <= 360 deg"
    laws = [c.split(" ")[0] for c in cycle[:-1]]
    assert laws == ["min_angle[1->3]", "amplitude[3->7]", "min_angle[7->8]", "min_angle[8->9]", "contact_stress[9->10]",
                    "min_angle[10->10.1]", "min_time[10.1->10.2]", "min_angle[10.2->11]", "min_angle[11->12]",
                    "min_angle[12->13]", "min_angle[13->24]"]
    assert "(flight, 0.36 deg/rpm)" in cycle[6]
    assert graph.diagnostics["newton_steps"] <= 3


def test_ranging_at_the_highest_speed_against_the_closed_form(graph):
    """Along the chain: [phi] 110 deg plus n (g_amp + g_stress + g_flight) = 360. Without one
    limit's growth its arc keeps its [phi] (the flight's 100 deg) and n solves the rest."""
    rows = {r["constraint"]: r for r in graph.diagnostics["ranging_at_max_speed"]}
    g_amp = rows["amplitude[3->7]"]["deg_per_rpm"]
    n = graph.values["max_speed_rpm"]
    assert n == pytest.approx((360 - CHAIN_FIXED_DEG) / (g_amp + STRESS_9_10_DEG_PER_RPM + FLIGHT_DEG_PER_RPM), rel=1e-12)
    no_flight = rows["min_time[10.1->10.2]"]
    assert no_flight["rpm_without_it"] == pytest.approx((360 - CHAIN_FIXED_DEG - 100) / (g_amp + STRESS_9_10_DEG_PER_RPM),
                                                        rel=1e-12)
    assert no_flight["then_limited_by"] == ["amplitude[3->7]", "contact_stress[9->10]"]
    slope = g_amp + STRESS_9_10_DEG_PER_RPM + FLIGHT_DEG_PER_RPM
    assert all(r["rpm_per_deg_per_rpm"] == pytest.approx(-n / slope, rel=1e-12) for r in rows.values())
    assert rows["amplitude[3->7]"]["rpm_without_it"] > n and rows["contact_stress[9->10]"]["rpm_without_it"] > n
    floats = graph.diagnostics["float_deg"]
    assert floats["3->7"] == pytest.approx(0.0, abs=1e-9) and floats["1->2"] > 1.0


def test_the_benchmark_machine_10_groups_of_100_agrees_with_the_lp():
    task = machine()
    graph, lp = max_machine_speed(task, method="graph"), max_machine_speed(task, method="lp")
    assert graph.status is Status.SOLVED and lp.status is Status.SOLVED
    assert graph.values["max_speed_rpm"] == pytest.approx(lp.values["max_speed_rpm"], rel=1e-9)
    assert graph.diagnostics["critical_chain"][0] == "start"


def test_a_window_that_limits_the_speed_is_on_the_named_cycle(task):
    """A window from 1 to 10.1 of 120 deg: the cycle closes through it, not through the machine's cycle."""
    windowed = dataclasses.replace(task, windows=[{"from": "1", "to": "10.1", "max_deg": 120.0}])
    graph, lp = (max_machine_speed(windowed, method=m, check=m == "graph") for m in ("graph", "lp"))
    assert graph.status is Status.SOLVED and "checked by the LP" in graph.message
    assert graph.values["max_speed_rpm"] == pytest.approx(lp.values["max_speed_rpm"], rel=1e-9)
    assert "window p(10.1) - p(1) <= 120 deg" in graph.diagnostics["limiting_cycle"]
    assert not any(c.startswith("cycle") for c in graph.diagnostics["limiting_cycle"])


def test_a_check_that_disagrees_is_inaccurate(task, monkeypatch):
    import mechopt.solvers.cyclogram.speed as speed
    real = speed.speed_by_lp

    def off(*args):
        n, *rest = real(*args)
        return (n * (1 + 1e-6), *rest)
    monkeypatch.setattr(speed, "speed_by_lp", off)
    r = max_machine_speed(task, check=True)
    assert r.status is Status.INACCURATE and "check failed: the LP in (p, n) gives" in r.message


def test_one_limit_changed_on_group1_the_graph_re_solves_and_certifies_the_held_lp():
    """A what-if: [sigma_H] moved; the held HiGHS model re-solved and certified by a fresh
    graph pass, both against a fresh LP of the changed scene; a held answer off by 1e-6 deg is
    INACCURATE, and a network that cannot be held agrees only with an infeasible LP."""
    from mechopt.solvers.cyclogram import HeldLP
    from mechopt.solvers.cyclogram.graph import HeldSpan
    from mechopt.solvers.cyclogram.net import Net, back_arcs
    task = registry.find("loom/group1").build()[0]
    net = Net(task, "exact")
    held = HeldLP(len(net.names), net.tails, net.heads, first=net.first, last=net.last,
                  window_arcs=net.window_idx, sync_arcs=net.sync_idx)
    graph = HeldSpan(len(net.names), net.tails, net.heads, net.first, net.last, back_arcs(net, with_cycle=False)[0])
    windows = [w for _, _, w in task.window_arcs()]
    spans = []
    for sigma in (600.0, 700.0, 800.0, 1000.0):
        changed = dataclasses.replace(task, sigma_H_limit_MPa=sigma)
        lb = Net(changed, "exact").lb
        status, p = held.solve(lb, windows)
        assert status is Status.SOLVED
        verdict, span = graph.certify(lb, p[net.last] - p[net.first])
        assert verdict is Status.SOLVED
        assert span == pytest.approx(plan_cyclogram(changed, method="lp").values["span_deg"], rel=1e-9)
        spans.append(span)
    assert spans[0] > spans[-1]                        # a lower [sigma_H] asks for longer cam angles
    assert graph.certify(lb, span + 1e-6)[0] is Status.INACCURATE
    assert graph.certify(lb, None)[0] is Status.INACCURATE
