"""The graph method of plan_cyclogram on the loom's scenes, certified by the LP: the two methods side
by side, a check that disagrees, a one-limit what-if on the held graph, a tie of two bounds, and the
repair's rebound walk refused when too long (the engine's own: tests/cyclogram/test_graph.py)."""
import dataclasses

import pytest

import mechopt
from mechopt import registry
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Status
from mechopt.solvers.cyclogram import plan_cyclogram
from mechopt.solvers.cyclogram.certify import certify
from mechopt.solvers.loom import repair_cyclogram


@pytest.mark.parametrize("case", ["loom/group1", "loom/machine", "loom/group1-linear-stress",
                                  "loom/group1-window-conflict"])
def test_graph_and_lp_give_the_same_answer_on_every_loom_scene(case):
    task = registry.find(case).build()[0]
    r = plan_cyclogram(task, check=True)
    assert "check failed" not in r.message and r.diagnostics["check"] == "lp"
    lp = plan_cyclogram(task, method="lp")
    assert r.status is lp.status
    for key, value in lp.values.items():
        if key.startswith(("sens_", "limiting")) or key == "span_deg":     # times off the chain are not unique
            assert r.values[key] == pytest.approx(value, abs=1e-6), key


def test_a_check_that_disagrees_is_inaccurate():
    task = registry.find("loom/group1").build()[0]
    graph, lp = plan_cyclogram(task), plan_cyclogram(task, method="lp")
    wrong = dataclasses.replace(lp, values=lp.values | {"span_deg": 100.0})
    r = certify(graph, wrong, 1e-6)
    assert r.status is Status.INACCURATE and "span_deg 114.75 against 100.0" in r.message
    assert certify(graph, lp, 1e-6).status is Status.SOLVED
    assert certify(graph, lp, 1e-6).values["check_rel"] <= 1e-12
    conflict = plan_cyclogram(registry.find("loom/group1-window-conflict").build()[0])
    assert certify(conflict, lp, 1e-6).status is Status.INACCURATE          # the LP solves what the graph refuses


@pytest.mark.parametrize("setting", [{"scan_step_deg": 0.001}, {"scan_to_deg": 360.0}])
def test_a_rebound_walk_too_long_is_refused_before_it_starts(setting):
    # formerly scan_step_deg = 0.001 ran for minutes and scan_to_deg = 360 for 46 s
    task = registry.find("loom/group1-repaired").build()[0]
    with pytest.raises(SettingError, match=r"the limit is 1000: raise scan_step_deg") as err:
        repair_cyclogram(task, **setting)
    assert err.value.key == "scan_step_deg"


def test_a_one_limit_what_if_is_solved_and_certified_by_the_held_graph():
    """HeldSpan.solve, a what-if: [sigma_H] moved on loom/group1, the span is plan_cyclogram's
    for the changed task, certified (times feasible, a tight chain of the same value); a window
    the changed bounds cannot meet is INFEASIBLE; a wrong bound vector is not certified as another's."""
    from mechopt.solvers.cyclogram.graph import HeldSpan
    from mechopt.solvers.cyclogram.net import Net, back_arcs
    task = registry.find("loom/group1").build()[0]
    net = Net(task, "exact")
    held = HeldSpan(len(net.names), net.tails, net.heads, net.first, net.last, back_arcs(net, with_cycle=False)[0])
    for sigma in (650.0, 800.0, 950.0):
        changed = dataclasses.replace(task, sigma_H_limit_MPa=sigma)
        status, span, p = held.solve(Net(changed, "exact").lb)
        assert status is Status.SOLVED
        assert span == pytest.approx(plan_cyclogram(changed).values["span_deg"], rel=1e-12)
    tight = dataclasses.replace(task, windows=[{"from": "3", "to": "8", "max_deg": 40.0}])
    tnet = Net(tight, "exact")
    conflict = HeldSpan(len(tnet.names), tnet.tails, tnet.heads, tnet.first, tnet.last,
                        back_arcs(tnet, with_cycle=False)[0])
    assert conflict.solve(tnet.lb)[0] is Status.INFEASIBLE


def test_a_tie_of_two_bounds_is_a_non_unique_dual_not_a_failed_certificate():
    # at 700 MPa the stress bound ties another bound: d span / d sigma_H differs from below and
    # from above, and the graph and the LP may each return any value between (both are duals)
    run = mechopt.solve("loom/group1", sigma_H_limit_MPa=700.0, check=True)
    assert run.result.status is Status.SOLVED
    below, above = run.result.diagnostics["sens_not_unique"]["sens_sigma_H_deg_per_MPa"]
    task, h = run.task, 0.01                      # independent: the LP's spans at 700 -+ h
    span = [plan_cyclogram(dataclasses.replace(task, sigma_H_limit_MPa=s), method="lp").values["span_deg"]
            for s in (700.0 - h, 700.0, 700.0 + h)]
    assert below == pytest.approx((span[1] - span[0]) / h, rel=1e-3)
    assert above == pytest.approx((span[2] - span[1]) / h, rel=1e-3)
    assert below != pytest.approx(above, rel=0.1)
    assert min(below, above) - 1e-9 <= run.result.values["sens_sigma_H_deg_per_MPa"] <= max(below, above) + 1e-9
    at_800 = mechopt.solve("loom/group1", sigma_H_limit_MPa=800.0, check=True).result
    assert at_800.status is Status.SOLVED and "sens_not_unique" not in at_800.diagnostics


