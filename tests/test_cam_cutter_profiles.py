"""Cams of any shape (issue 13, Sec. 2): the safe curve parser, the point table, the kerf offset,
the cusp, and the minimax on a general curve against independent computations."""
import shutil
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import differential_evolution
from scipy.spatial import cKDTree

from mechopt import registry
from mechopt.models.cam_cutter import LinkageFit, finish_angle, ideal_normal, ideal_point
from mechopt.models.cam_profile import (
    ExpressionCurve,
    ProfileFit,
    TableCurve,
    parse_expression,
    place,
    unit_normal,
)
from mechopt.models.errors import ModelError, SceneError
from mechopt.solvers.cam_cutter import minimax
from mechopt.solvers.result import Status

ROOT = Path(__file__).resolve().parents[1]
CARDIOID = ("a*(2*cos(t)+cos(2*t))", "a*(2*sin(t)+sin(2*t))")     # eq. (1)


def cardioid(a, t1):
    return ExpressionCurve(*CARDIOID, 0.0, t1, {"a": a})


@pytest.mark.parametrize("a, h", [(25.0, 2.0), (40.0, 3.0), (10.0, 0.5)])
def test_parsed_cardioid_offset_and_placed_is_eq_9(a, h):
    # the offset is computed from CasADi's AD normal, eq. (9) from the closed form (3)
    t1 = finish_angle(a, h)
    t = np.linspace(0.0, t1, 2001)
    x, y = place(cardioid(a, t1), h).point(t)
    X, Y = ideal_point(t, a, h)
    assert np.max(np.hypot(x - X, y - Y)) < 1e-12 * a * 10


def test_ad_normal_is_the_closed_form_normal():
    t = np.linspace(0.0, 3.0, 501)
    nx, ny = unit_normal(cardioid(25.0, 3.0), t)
    NX, NY = ideal_normal(t)
    assert np.max(np.hypot(nx - NX, ny - NY)) < 1e-12


def test_one_parse_serves_numbers_and_symbols():
    f = parse_expression("-A*sqrt(abs(t))**3 + exp(t/10)*log(2+t) - tan(t/4)/cos(pi*t)", {"A": 1.5})
    t = np.linspace(0.1, 1.2, 7)
    T = ca.SX.sym("t")
    g = ca.Function("g", [T], [f(T, {"A": 1.5}, ca)])
    assert np.allclose(f(t, {"A": 1.5}, np), np.array(g(ca.DM(t.reshape(1, -1)))).ravel(), rtol=1e-14)


@pytest.mark.parametrize("text, match", [
    ("__import__('os').system('true')", "is not allowed"),
    ("t.real", "is not allowed"),
    ("(lambda: 1)()", "is not allowed"),
    ("sin(t, 2)", "is not allowed"),
    ("t if t else 1", "is not allowed"),
    ("'50'", "is not allowed"),
    ("open", "unknown name 'open'"),
    ("50*cos(t", "not an expression"),
    ("", "expected an expression"),
])
def test_unsafe_or_malformed_expression_is_refused(text, match):
    with pytest.raises(ModelError, match=match):
        parse_expression(text, {"A": 1.0})


def test_closed_table_is_a_periodic_spline_through_its_points():
    s = np.linspace(0.0, 2 * np.pi, 61)
    curve = TableCurve(tuple(30 * np.cos(s)), tuple(30 * np.sin(s)), name="circle.csv")
    assert curve.closed
    t = np.linspace(curve.t0, curve.t1, 997)
    x, y = curve.point(t)
    assert np.max(np.abs(np.hypot(x, y) - 30)) < 2e-4           # chord-length spline on a circle
    nx, ny = unit_normal(curve, t)
    assert np.min(nx * x / 30 + ny * y / 30) > 1 - 1e-6          # counter-clockwise: outward normal


TABLE_SCENE = """id = "mine/table"
title = "a cam given as a point table"
source = "a test"
task = "cam_profile.ProfileFit"
solver = "cam_cutter.minimax"
[params]
err_width_mm = {{ value = 0.01, mark = "assumed", why = "a test" }}
[solver_settings]
count = 400
[structure]
points_mm = {points}
"""
CSV_TABLE = '{{ csv = "{csv}", columns = ["x_mm", "y_mm"] }}'


def test_csv_table_of_a_limacon_gives_back_its_linkage(tmp_path):
    # the example: 37 rows (4 decimals) of r = 50 + 4 cos(theta) about the origin, a limaçon:
    # eq. (10) with H = 4, L = 50 in closed form, so the spline's path must find them again;
    # the scene names the CSV relative to its own folder
    (tmp_path / "tables").mkdir()
    shutil.copy(ROOT / "examples" / "cam-profile-table.csv", tmp_path / "tables" / "cam.csv")
    (tmp_path / "cam.toml").write_text(TABLE_SCENE.format(points=CSV_TABLE.format(csv="tables/cam.csv")), encoding="utf-8")
    run = registry.run(str(tmp_path / "cam.toml"))
    assert run.status is Status.SOLVED and run.values["max_deviation_mm"] < 3e-4
    assert run.values["H_mm"] == pytest.approx(4.0, abs=5e-3) and run.values["L_mm"] == pytest.approx(50.0, abs=1e-3)


@pytest.mark.parametrize("table, match", [
    ("x_mm,y_mm\n1,2\n1,x\n", r"cam\.csv: line 3 \('1,x'\): expected numbers in x_mm, y_mm"),
    ("x,y\n1,2\n", r"cam\.csv: header \['x', 'y'\] lacks x_mm, y_mm"),
    (None, r"cam\.csv: cannot read: No such file .*\(the table for structure\.points_mm\)"),
])
def test_a_bad_csv_table_is_named_with_its_line(tmp_path, table, match):
    if table is not None:
        (tmp_path / "cam.csv").write_text(table, encoding="utf-8")
    (tmp_path / "cam.toml").write_text(TABLE_SCENE.format(points=CSV_TABLE.format(csv="cam.csv")), encoding="utf-8")
    with pytest.raises(SceneError, match=match):
        registry.find(str(tmp_path / "cam.toml"))


def test_duplicate_points_are_refused_naming_file_and_rows():
    x, y = [0.0, 1.0, 1.0, 2.0, 3.0], [0.0, 1.0, 1.0, 1.5, 1.0]
    with pytest.raises(ModelError, match=r"cam\.csv: rows 2, 3: repeated point"):
        TableCurve(tuple(x), tuple(y), name="cam.csv")


def test_unordered_points_are_refused_naming_file_and_rows():
    s = np.linspace(0.0, np.pi, 12)
    x, y = list(30 * np.cos(s)), list(30 * np.sin(s))
    x[5], x[6], y[5], y[6] = x[6], x[5], y[6], y[5]              # two rows swapped
    with pytest.raises(ModelError, match=r"cam\.csv: rows .*6.*turns back .*not in path order"):
        TableCurve(tuple(x), tuple(y), name="cam.csv")


def test_a_cusp_is_found_named_and_no_offset_through_it():
    curve = cardioid(25.0, np.pi)                                # the cardioid's cusp, t = pi
    assert curve.find_cusps() == [pytest.approx(np.pi, abs=1e-7)]
    with pytest.raises(ModelError, match=r"cusp at t = 3\.14159 \(\(x, y\) = \(-25, 0\) mm\)") as err:
        ProfileFit(err_width_mm=0.1, x_expr=CARDIOID[0], y_expr=CARDIOID[1], t1_rad=np.pi,
                   constants={"a": 25.0}, h_mm=2.0)
    assert err.value.key == "h_mm"
    # without the offset the cusp needs no normal: the exact linkage H = L = 2a, no NaN
    run = minimax(ProfileFit(err_width_mm=0.01, x_expr=CARDIOID[0], y_expr=CARDIOID[1], t1_rad=np.pi,
                             constants={"a": 25.0}), count=400)
    assert run.status is Status.SOLVED
    assert run.values["H_mm"] == pytest.approx(50.0, abs=1e-5) and run.values["L_mm"] == pytest.approx(50.0, abs=1e-5)


def test_the_cardioid_as_a_curve_gives_the_cardioid_minimax():
    a, h = 25.0, 2.0
    curve_task = ProfileFit(err_width_mm=0.075, x_expr=CARDIOID[0], y_expr=CARDIOID[1],
                            t1_rad=finish_angle(a, h), constants={"a": a}, h_mm=h)
    got, ref = minimax(curve_task, count=1000), minimax(LinkageFit(a_mm=a, err_width_mm=0.075, h_mm=h), count=1000)
    for key in ("H_mm", "L_mm", "max_deviation_mm"):
        assert got.values[key] == pytest.approx(ref.values[key], abs=1e-7)


def test_a_band_the_limacons_cannot_keep_is_infeasible_with_where():
    run = registry.run("cam-cutter/other-profile", {"err_width_mm": 0.3})
    assert run.status is Status.INFEASIBLE and run.result.violated == ("err_width",)
    assert "best achievable 0.3562 mm; set at t = " in run.result.message
    x, y = run.result.diagnostics["max_deviation_at_mm"]
    assert np.isfinite(x) and np.isfinite(y)


# --- an independent check of the other-profile scene: differential evolution on a distance
# computed here (KD-tree over a fine limaçon polyline, then the exact distance to its two
# segments), sharing no code with the package's foot-point search or its NLP

def _distance_to_limacon(px, py, H, L, vertices=2**15):
    s = np.linspace(0.0, 2 * np.pi, vertices, endpoint=False)
    rx, ry = L * (np.cos(s) - 1) + 0.5 * H * (np.cos(2 * s) - 1), L * np.sin(s) + 0.5 * H * np.sin(2 * s)
    _, k = cKDTree(np.c_[rx, ry]).query(np.c_[px, py])
    best = np.full(px.shape, np.inf)
    for j in (k - 1, k + 1):
        j = j % vertices
        ax, ay, bx, by = rx[k], ry[k], rx[j], ry[j]
        u = np.clip(((px - ax) * (bx - ax) + (py - ay) * (by - ay)) / ((bx - ax) ** 2 + (by - ay) ** 2), 0, 1)
        best = np.minimum(best, np.hypot(ax + u * (bx - ax) - px, ay + u * (by - ay) - py))
    return best


def test_other_profile_scene_agrees_with_differential_evolution():
    scene = registry.find("cam-cutter/other-profile")
    task, _ = scene.build()
    t = np.linspace(task.t_start_rad, task.t_end_rad, 1500)
    px, py = task.path_point(t)            # the offset path itself is pinned above against eq. (9)

    def worst(v, vertices=2**12):
        return _distance_to_limacon(px, py, v[0], v[1], vertices).max()

    found = differential_evolution(lambda v: worst(v, 2**11), [(1.0, 40.0), (40.0, 60.0)], seed=3, tol=1e-10,
                                   popsize=10, maxiter=80, polish=False)
    exp = scene.spec.expect
    assert found.x[0] == pytest.approx(exp["H_mm"].value, abs=0.1)
    assert found.x[1] == pytest.approx(exp["L_mm"].value, abs=0.05)
    # at the scene's optimum, finely: its value, and no better point around it
    best = np.array([exp["H_mm"].value, exp["L_mm"].value])
    value = worst(best, 2**16)
    assert value == pytest.approx(exp["max_deviation_mm"].value, abs=2e-6)
    for dH, dL in [(d * np.cos(q), d * np.sin(q)) for d in (0.003, 0.03) for q in np.linspace(0, 2 * np.pi, 8, endpoint=False)]:
        assert worst(best + (dH, dL), 2**16) > value - 2e-6


def test_the_placement_reading_matters_and_start_at_origin_is_taken():
    # "as_given": the centred ellipse is 50 mm from the origin, where every limaçon starts
    scene = registry.find("cam-cutter/other-profile")
    task, _ = scene.build({"placement": "as_given"})
    run = minimax(task, count=400)
    assert run.status is not Status.SOLVED and run.values["max_deviation_mm"] > 40
    assert scene.spec.structure["placement"] == "start_at_origin"


def test_an_optimum_on_the_default_box_is_limit_not_solved():
    # an ellipse longer than it is tall wants H < 0 (the egg turned round): the box floor stops it
    task = ProfileFit(err_width_mm=2.0, x_expr="A*cos(t)", y_expr="B*sin(t)", t1_rad=np.pi,
                      constants={"A": 50.0, "B": 47.5}, h_mm=2.0)
    run = minimax(task, count=400)
    assert run.status is Status.LIMIT
    assert "H at its lower bound H_min_mm" in run.message and "the default box" in run.message


def test_a_users_scene_takes_a_point_table_in_its_structure(tmp_path):
    s = np.linspace(0.0, np.pi, 25)
    r = 50 + 4 * np.cos(s)                                    # the limaçon H = 4, L = 50 again
    rows = ", ".join(f"[{x:.6f}, {y:.6f}]" for x, y in zip(r * np.cos(s), r * np.sin(s)))
    path = tmp_path / "table.toml"
    path.write_text(TABLE_SCENE.format(points=f"[{rows}]"), encoding="utf-8")
    run = registry.run(str(path))
    assert run.status is Status.SOLVED and run.values["H_mm"] == pytest.approx(4.0, abs=0.02)


@pytest.mark.parametrize("method", ["grid_scan", "robust", "evolve"])
def test_the_cardioid_only_methods_refuse_a_general_curve(method):
    from mechopt.solvers.cam_cutter import fit_linkage
    task, _ = registry.find("cam-cutter/other-profile").build()
    with pytest.raises(ModelError, match=f"{method} solves the cardioid .* by cam_cutter.minimax"):
        fit_linkage(task, method=method)
