"""Cams of any shape: the safe curve parser, the point table, the kerf offset,
the cusp, and the minimax on a general curve against independent computations."""
import dataclasses
import shutil
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.spatial import cKDTree

from mechopt import registry
from mechopt.kit.errors import ModelError, SceneError
from mechopt.kit.result import Status
from mechopt.models.cam_cutter import LinkageFit, finish_angle, ideal_normal, ideal_point
from mechopt.models.cam_profile import (
    ExpressionCurve,
    ProfileFit,
    TableCurve,
    parse_expression,
    place,
    unit_normal,
)
from mechopt.solvers.cam_cutter import minimax

ROOT = Path(__file__).resolve().parents[2]
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
    # as a general curve its box holds both cranks, |H| up to 4.66 a: the paper's cardioid's
    # minimax linkage is global over them too (the best mirrored crank is 8.27 mm off)
    assert got.diagnostics["box_mm"][0] < 0 and got.diagnostics["global_certified"]


def test_a_band_the_limacons_cannot_keep_is_infeasible_with_where():
    run = registry.run("cam-cutter/other-profile", {"err_width_mm": 0.3})
    assert run.status is Status.INFEASIBLE and run.result.violated == ("err_width",)
    assert "best achievable 0.3057 mm; set at t = " in run.result.message
    assert run.result.diagnostics["global_certified"]          # no linkage of the box keeps 0.3 mm
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


def _grid_distance(px, py, H, L, vertices=256):
    """Largest distance from the points to each limaçon (H, L[j]) of a row, directly over a
    coarse polyline: the brute-force grid's measure (its error, ~0.01 mm, ranks basins only)."""
    s = np.linspace(0.0, 2 * np.pi, vertices, endpoint=False)
    L = np.asarray(L)[:, None, None]
    rx, ry = L * (np.cos(s) - 1) + 0.5 * H * (np.cos(2 * s) - 1), L * np.sin(s) + 0.5 * H * np.sin(2 * s)
    return np.sqrt(((rx - px[:, None]) ** 2 + (ry - py[:, None]) ** 2).min(axis=2)).max(axis=1)


def brute_force_minimax(px, py, box, *, step=2.0, basins=4):
    """A brute-force global search over the box: every (H, L) of a `step` mm grid, then
    Nelder-Mead from the best grid point of each of the `basins` best basins (grid points more
    than 3 steps apart), on the distance of `_distance_to_limacon`. Returns (value, H, L), best first."""
    H = np.arange(box[0], box[1] + 1e-9, step)
    L = np.arange(box[2], box[3] + 1e-9, step)
    sub = np.linspace(0, px.size - 1, 50).round().astype(int)
    grid = np.array([_grid_distance(px[sub], py[sub], h, L) for h in H])
    seeds = []
    for flat in np.argsort(grid, axis=None):
        i, j = np.unravel_index(flat, grid.shape)
        if all(abs(H[i] - h) > 3 * step or abs(L[j] - l) > 3 * step for h, l in seeds):
            seeds.append((H[i], L[j]))
        if len(seeds) == basins:
            break

    def worst(v):
        return _distance_to_limacon(px, py, v[0], v[1], 2**12).max()

    found = [minimize(worst, seed, method="Nelder-Mead", options={"xatol": 1e-6, "fatol": 1e-9}) for seed in seeds]
    return sorted((float(f.fun), *map(float, f.x)) for f in found)


def test_other_profile_scene_is_the_global_minimax_of_a_brute_force_search():
    scene = registry.find("cam-cutter/other-profile")
    task, _ = scene.build()
    t = np.linspace(task.t_start_rad, task.t_end_rad, 1500)
    px, py = task.path_point(t)            # the offset path itself is pinned above against eq. (9)
    found = brute_force_minimax(px, py, task.bounds())
    value, H, L = found[0]
    exp = scene.spec.expect
    assert H == pytest.approx(exp["H_mm"].value, abs=0.01) and L == pytest.approx(exp["L_mm"].value, abs=0.01)
    assert H < 0                                   # the mirrored crank
    assert found[1][1] > 0 and found[1][0] == pytest.approx(0.356156, abs=2e-5)    # the best H > 0
    assert found[1][0] / value - 1 > 0.14          # the mirrored crank keeps a band 14 % narrower
    # at the scene's optimum, finely: its value, and no better point around it
    best = np.array([exp["H_mm"].value, exp["L_mm"].value])
    fine = _distance_to_limacon(px, py, *best, 2**16).max()
    assert fine == pytest.approx(exp["max_deviation_mm"].value, abs=2e-6)
    for dH, dL in [(d * np.cos(q), d * np.sin(q)) for d in (0.003, 0.03) for q in np.linspace(0, 2 * np.pi, 8, endpoint=False)]:
        assert _distance_to_limacon(px, py, *(best + (dH, dL)), 2**16).max() > fine - 2e-6
    # the package's certificate: a lower bound below every brute-force value, within its gap
    run = registry.run(scene.id)
    d = run.result.diagnostics
    assert d["global_certified"] and d["global_gap_mm"] <= d["global_gap_target_mm"]
    assert d["global_lower_bound_mm"] <= value <= run.values["max_deviation_mm"] + 1e-5


def test_table_profile_scene_is_the_minimax_of_a_brute_force_search():
    """The template `mechopt new cam-table` copies: eq. (10)'s limaçon (H = 4, L = 50 mm) as 37
    rows, offset by the 2 mm kerf; its expectations are this search's answer."""
    scene = registry.find("cam-cutter/table-profile")
    task, _ = scene.build()
    px, py = task.path_point(np.linspace(task.t_start_rad, task.t_end_rad, 1500))
    value, H, L = brute_force_minimax(px, py, task.bounds())[0]
    exp = scene.spec.expect
    assert H == pytest.approx(exp["H_mm"].value, abs=exp["H_mm"].abs)
    assert L == pytest.approx(exp["L_mm"].value, abs=exp["L_mm"].abs)
    assert value == pytest.approx(exp["max_deviation_mm"].value, abs=exp["max_deviation_mm"].abs)


def test_the_placement_reading_matters_and_start_at_origin_is_taken():
    # "as_given": the centred ellipse is 50 mm from the origin, where every limaçon starts
    scene = registry.find("cam-cutter/other-profile")
    task, _ = scene.build({"placement": "as_given"})
    run = minimax(task, count=400)
    assert run.status is not Status.SOLVED and run.values["max_deviation_mm"] > 3
    assert scene.spec.structure["placement"] == "start_at_origin"


def test_the_h_positive_reading_keeps_the_band_of_the_local_optimum():
    task, _ = registry.find("cam-cutter/other-profile").build()
    positive = minimax(dataclasses.replace(task, H_min_mm=1.0), count=1000)     # the H > 0 reading
    assert positive.status is Status.SOLVED and positive.diagnostics["global_certified"]
    assert positive.values["H_mm"] == pytest.approx(15.215569, abs=0.01)
    assert positive.values["max_deviation_mm"] == pytest.approx(0.356156, abs=2e-5)


def test_an_answer_with_no_crank_is_named_not_solved():
    # an ellipse longer than it is tall, links of 20 .. 80 mm: the best limaçon is the circle H = 0
    task = ProfileFit(err_width_mm=2.0, x_expr="A*cos(t)", y_expr="B*sin(t)", t1_rad=np.pi,
                      constants={"A": 50.0, "B": 47.5}, h_mm=2.0, H_min_mm=-60.0, H_max_mm=60.0,
                      L_min_mm=20.0, L_max_mm=80.0)
    got = minimax(task, count=400, certify="off")
    assert got.status is Status.LIMIT and abs(got.values["H_mm"]) < 1e-3
    assert "no crank (H = 0 is no mechanism)" in got.message


def test_the_mirrored_crank_is_the_limacon_mirrored_and_placed_at_the_origin():
    from mechopt.models.cam_cutter import real_point
    s = np.linspace(0.0, 2 * np.pi, 7)
    H, L = 13.0, 52.0
    x, y = real_point(s, -H, L)
    # r = L - H cos t about the pole is r = L + H cos t mirrored across the pole's y axis (t -> pi - t)
    mx, my = real_point(np.pi - s, H, L)
    pole_neg, pole_pos = -(L - H), -(L + H)
    assert np.allclose(x - pole_neg, -(mx - pole_pos)) and np.allclose(y, my)
    assert real_point(0.0, -H, L) == pytest.approx((0.0, 0.0))


@pytest.mark.parametrize("key, value, match", [
    ("H_min_mm", -2601.0, r"H_min_mm=-2601\.0: allowed -2600 \.\.\. 2600"),
    ("L_min_mm", -1.0, r"L_min_mm=-1\.0: allowed > 0 \.\.\. 2600"),
])
def test_box_sides_out_of_range_are_refused(key, value, match):
    with pytest.raises(ModelError, match=match) as err:
        ProfileFit(err_width_mm=0.4, x_expr="50*cos(t)", y_expr="52*sin(t)", h_mm=2.0, **{key: value})
    assert err.value.key == key


def test_a_certificate_cut_short_is_inaccurate_not_solved():
    task, _ = registry.find("cam-cutter/other-profile").build()
    got = minimax(task, count=400, max_cells=200)
    assert got.status is Status.INACCURATE and "not certified global over the box" in got.message
    assert got.diagnostics["global_gap_mm"] > got.diagnostics["global_gap_target_mm"]


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
