"""The readjustable tool: one H for a family of cams, L per cam, against a
nested scalar minimisation that shares nothing with the family NLP but the dense distance."""
import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from mechopt import registry
from mechopt.kit.result import Status
from mechopt.models.cam_cutter import ToolFamily, finish_angle, ideal_point, matched_linkage
from mechopt.solvers.cam_cutter import evolve_family, readjustable
from mechopt.solvers.cam_cutter.deviation import path_distance


def best_for_cam(a, h, H, t_samples=900):
    """min over L of the cam's largest distance [mm] at fixed H: bounded Brent on the dense
    distance (the cam's L is free, so the family objective separates: max over cams of this)."""
    px, py = ideal_point(np.linspace(0.0, finish_angle(a, h), t_samples), a, h)
    L0 = sum(matched_linkage(a, h)) - H
    found = minimize_scalar(lambda L: path_distance(px, py, H, L).max(), bounds=(L0 - 3.0, L0 + 3.0),
                            method="bounded", options={"xatol": 1e-7})
    return found.fun


def family_worst(members, H):
    return max(best_for_cam(a, h, H) for a, h in members)


@pytest.fixture(scope="module")
def scene_run():
    return registry.run("cam-cutter/readjustable")


def test_readjustable_scene_is_the_nested_minimum(scene_run):
    members = scene_run.task.members
    H = scene_run.scene.spec.expect["H_mm"].value
    worst = family_worst(members, H)
    assert worst == pytest.approx(scene_run.scene.spec.expect["worst_deviation_mm"].value, abs=2e-5)
    assert worst == pytest.approx(scene_run.values["worst_deviation_mm"], abs=2e-5)
    for dH in (-0.02, 0.02):             # a minimum in H: either side is worse
        assert family_worst(members, H + dH) > worst + 1e-4
    table = scene_run.arrays
    assert len(table["L_mm"]) == len(members) == 15
    assert np.all(table["deviation_mm"] <= scene_run.values["worst_deviation_mm"] + 1e-12)


def test_served_range_ends_bracket_the_band(scene_run):
    task, H, band = scene_run.task, scene_run.values["H_mm"], scene_run.task.err_width_mm
    low, high = scene_run.values["a_served_min_mm"], scene_run.values["a_served_max_mm"]
    assert low < task.a_min_mm and high > task.a_max_mm

    def worst_at(a):
        return max(best_for_cam(a, h, H) for h in task.h_values_mm)

    for end, outward in ((low, -1.0), (high, 1.0)):
        assert worst_at(end - outward * 0.015) <= band
        assert worst_at(end + outward * 0.015) > band
        rising = [worst_at(end + outward * d) for d in (0.03, 0.08, 0.15)]      # no second window
        assert rising == sorted(rising)


def test_a_family_no_H_can_serve_is_infeasible_with_the_best_band_and_where():
    run = registry.run("cam-cutter/readjustable", {"err_width_mm": 0.1})
    assert run.status is Status.INFEASIBLE and run.result.violated == ("err_width",)
    best = run.values["worst_deviation_mm"]
    assert best == pytest.approx(0.173432, abs=1e-4)          # the scene's best band: the band does not move it
    assert "no single H keeps every cam within err_width_mm=0.1; best achievable family band 0.1734 mm" in run.result.message
    assert "member a = 25.1 mm, h = 2.2 mm at t = " in run.result.message
    assert "a_served_min_mm" not in run.values                 # nothing is served


def test_family_too_wide_scene_is_infeasible_at_the_nested_minimum():
    run = registry.run("cam-cutter/family-too-wide")
    expect = run.scene.spec.expect
    assert run.status is Status.INFEASIBLE and "set by member a = 23 mm, h = 2 mm at t = " in run.result.message
    members, H = run.task.members, expect["H_mm"].value
    worst = family_worst(members, H)
    assert worst == pytest.approx(expect["worst_deviation_mm"].value, abs=2e-5)
    assert min(family_worst(members, H + d) for d in (-0.05, 0.05)) > worst + 1e-4


def test_an_H_bound_that_binds_is_named_and_a_served_range_at_its_limit_is_not_solved():
    run = registry.run("cam-cutter/readjustable", {"H_max_mm": 59.0, "served": False})
    assert run.values["H_mm"] == pytest.approx(59.0, abs=1e-6)
    assert "H_max_mm" in run.result.message
    wide = registry.run("cam-cutter/readjustable", {"err_width_mm": 30.0})      # serves everything it tries
    assert wide.status is Status.LIMIT and "still served (search limit a_min / 4" in wide.result.message
    assert "a_served_max_mm" not in wide.values


def test_one_cam_family_is_the_single_cam_minimax():
    from mechopt.models.cam_cutter import LinkageFit
    from mechopt.solvers.cam_cutter import minimax
    run = readjustable(ToolFamily(a_min_mm=25.0, a_max_mm=25.0, err_width_mm=0.075, a_count=1), count=1000,
                       served=False)
    one = minimax(LinkageFit(a_mm=25.0, err_width_mm=0.075, h_mm=2.0))
    assert run.values["H_mm"] == pytest.approx(one.values["H_mm"], abs=1e-4)
    assert run.values["worst_deviation_mm"] == pytest.approx(one.values["max_deviation_mm"], abs=1e-6)


def test_the_differential_evolution_peer_runs_and_reports_its_status():
    task = ToolFamily(a_min_mm=24.9, a_max_mm=25.1, err_width_mm=0.2, a_count=2, h_values_mm=(2.0,))
    short = evolve_family(task, count=50, maxiter=3)
    assert short.status is Status.LIMIT and np.isfinite(short.values["worst_deviation_mm"])
    assert short.values["worst_deviation_mm"] >= readjustable(task, served=False).values["worst_deviation_mm"] - 1e-9


def test_a_served_range_needs_the_family_served_first():
    from mechopt.solvers.cam_cutter.family import served_range
    task, _ = registry.find("cam-cutter/readjustable").build()
    low, high, info = served_range(task, 59.2)          # 0.23 mm below the family's H: a = 25.1 mm is lost
    assert low is None and high is None
    assert "the family's own cam a = 25.1 mm is not served at H = 59.2 mm" in info["note"]
