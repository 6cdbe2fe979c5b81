"""Sweep figures: the table-to-grid step places each variant in its own cell, the feasibility
boundary runs between solved and not-solved cells, and every layout (line, map, small multiples,
fallbacks, scatter) writes its PNG for a real sweep without crashing."""
import numpy as np
import pytest
from PIL import Image

from mechopt import registry
from mechopt import sweep as sw
from mechopt.figures.sweep import MAX_PANELS, boundary_of, grid_of, plot_sweep

LOOM = "loom/group1"


def _hand_table(points, keys=("H_mm", "L_mm"), random=()):
    """A sweep table built the way `sweep` builds it: one row per (key values..., status, value)."""
    rows = []
    for number, (*where, status, value) in enumerate(points):
        row = dict(zip(keys, where)) | {"variant": number, "status": status, "message": "",
                                        "build_s": 0.0, "solve_s": 0.0}
        if value is not None:
            row["max_deviation_mm"] = value
        rows.append(row)
    axes = [{"key": k, "low": 0.0, "high": 1.0, "num": 2} for k in keys if k not in random]
    meta = {"case": "cam-cutter/hand", "scene_sha256": "0" * 64,
            "spec": {"case": "cam-cutter/hand", "grid": axes, "samples": 0, "seed": 0,
                     "random": [{"key": k, "low": 0.0, "high": 1.0, "num": 0} for k in random]}}
    return sw._table(rows, list(keys), meta)


# H in {58, 59, 60}, L in {47, 48}: variant order shuffled, one variant (60, 48) missing,
# (58, 48) infeasible but with a value, (60, 47) invalid without one.
POINTS = [(59.0, 48.0, "SOLVED", 0.072), (58.0, 47.0, "SOLVED", 0.060), (60.0, 47.0, "INVALID", None),
          (58.0, 48.0, "INFEASIBLE", 0.081), (59.0, 47.0, "SOLVED", 0.065)]


def test_grid_places_each_variant_in_its_cell():
    grid = grid_of(_hand_table(POINTS), "H_mm", "L_mm", "max_deviation_mm")
    assert grid.xs.tolist() == [58.0, 59.0, 60.0] and grid.ys.tolist() == [47.0, 48.0]
    # rows are L (y), columns are H (x)
    assert grid.z[1, 1] == 0.072 and grid.z[0, 0] == 0.060 and grid.z[0, 1] == 0.065
    assert grid.z[1, 0] == 0.081                     # a not-solved variant keeps the value it gave
    assert np.isnan(grid.z[0, 2]) and np.isnan(grid.z[1, 2])       # no value; no variant
    assert grid.solved.tolist() == [[True, True, False], [False, True, False]]
    assert grid.status.tolist() == [["SOLVED", "SOLVED", "INVALID"], ["INFEASIBLE", "SOLVED", None]]


def test_grid_where_selects_one_value_of_a_third_key():
    points = [(h, l, w, "SOLVED" if h + 10 * w < 60 else "INFEASIBLE", h * l * w)
              for h in (58.0, 59.0) for l in (47.0, 48.0) for w in (0.05, 0.1)]
    table = _hand_table(points, keys=("H_mm", "L_mm", "err_width_mm"))
    grid = grid_of(table, "H_mm", "L_mm", "max_deviation_mm", where={"err_width_mm": 0.1})
    assert grid.z[1, 0] == pytest.approx(58.0 * 48.0 * 0.1, rel=1e-15)
    assert grid.solved.tolist() == [[True, False], [True, False]]     # 58 + 1 < 60, 59 + 1 = 60
    with pytest.raises(ValueError, match=r"2 variants fall on the cell H_mm = 58, L_mm = 47; fix the other swept "
                                         r"keys with where=\{key: value\}"):
        grid_of(table, "H_mm", "L_mm", "max_deviation_mm")


def test_boundary_runs_between_solved_and_unsolved_cells():
    # solved below the staircase L <= 50 - (H - 56) of a 5 x 4 grid, a missing variant at its top corner
    hs, ls = [56.0, 57.0, 58.0, 59.0, 60.0], [47.0, 48.0, 49.0, 50.0]
    points = [(h, l, "SOLVED" if l <= 50 - (h - 56) else "INFEASIBLE", 0.05) for h in hs for l in ls
              if (h, l) != (60.0, 50.0)]
    grid = grid_of(_hand_table(points), "H_mm", "L_mm", "max_deviation_mm")
    lines = boundary_of(grid)
    assert lines
    vertices = np.concatenate(lines)
    for x, y in vertices:
        # a vertex sits halfway between two neighbouring cell centres along a grid line: one solved, one not
        if np.isclose(grid.xs, x).any():
            i, j = int(np.argmin(abs(grid.xs - x))), int(np.searchsorted(grid.ys, y))
            assert y == pytest.approx(0.5 * (grid.ys[j - 1] + grid.ys[j]))
            a, b = (j - 1, i), (j, i)
        else:
            i, j = int(np.searchsorted(grid.xs, x)), int(np.argmin(abs(grid.ys - y)))
            assert y == pytest.approx(grid.ys[j]) and x == pytest.approx(0.5 * (grid.xs[i - 1] + grid.xs[i]))
            a, b = (j, i - 1), (j, i)
        assert grid.solved[a] != grid.solved[b], (x, y)
    # every solved/unsolved neighbour pair (both present) has its midpoint on the boundary
    pairs = [((j, i), (j, i + 1)) for j in range(4) for i in range(4)] + \
            [((j, i), (j + 1, i)) for j in range(3) for i in range(5)]
    crossings = [(0.5 * (grid.xs[a[1]] + grid.xs[b[1]]), 0.5 * (grid.ys[a[0]] + grid.ys[b[0]]))
                 for a, b in pairs if grid.status[a] and grid.status[b] and grid.solved[a] != grid.solved[b]]
    assert len(crossings) == 7       # 4 along H, 3 along L
    for point in crossings:
        assert np.min(np.hypot(*(vertices - point).T)) < 1e-12


def test_no_boundary_when_every_cell_is_on_one_side_or_the_grid_is_a_line():
    solved = grid_of(_hand_table([(58.0, 47.0, "SOLVED", 0.1), (59.0, 47.0, "SOLVED", 0.1),
                                  (58.0, 48.0, "SOLVED", 0.1), (59.0, 48.0, "SOLVED", 0.1)]),
                     "H_mm", "L_mm", "max_deviation_mm")
    assert boundary_of(solved) == []
    line = grid_of(_hand_table([(58.0, 47.0, "SOLVED", 0.1), (59.0, 47.0, "INFEASIBLE", 0.1)]),
                   "H_mm", "L_mm", "max_deviation_mm")
    assert boundary_of(line) == []


def _assert_pngs(paths, names):
    assert [p.name for p in paths] == names
    for path in paths:
        with Image.open(path) as image:
            assert image.size[0] > 500 and image.size[1] > 400
            assert np.asarray(image.convert("L")).std() > 10      # a picture, not a blank page


def test_loom_three_key_sweep_draws_small_multiples(tmp_path):
    scene = registry.find(LOOM)
    grid = [sw.parse_grid(t) for t in ("amplitude_limit_mm=0.08:0.14:4", "sigma_H_limit_MPa=700:900:3",
                                       "amplitude_slope_mm_per_deg=-0.004:0:3")]
    table = sw.sweep(scene, grid, progress=False)
    # a zero slope is refused by the model: one slope's map is all not-solved, the boundary-free side
    assert table.column("status").to_pylist().count("INVALID") == 12
    paths = plot_sweep(table, tmp_path, scene=scene, outputs=["span_deg", "t_3_7_deg"])
    _assert_pngs(paths, [f"sweep_{o}_vs_amplitude_limit_mm_sigma_H_limit_MPa_by_amplitude_slope_mm_per_deg.png"
                         for o in ("span_deg", "t_3_7_deg")])


def test_fallbacks_do_not_crash(tmp_path):
    # more than MAX_PANELS values of the third key, a fourth key, random points, an empty table
    many = [(h, l, w, s, "SOLVED" if h < 59 + w else "INFEASIBLE", h + l + w)
            for h in (58.0, 59.0, 60.0) for l in (47.0, 48.0) for w in range(MAX_PANELS + 3) for s in (1.0, 2.0)]
    table = _hand_table(many, keys=("H_mm", "L_mm", "err_width_mm", "step_mm"))
    _assert_pngs(plot_sweep(table, tmp_path), ["sweep_max_deviation_mm_vs_H_mm_L_mm_by_err_width_mm.png"])
    scattered = _hand_table([(58.3, 47.1, "SOLVED", 0.05), (59.7, 47.9, "INFEASIBLE", 0.09),
                             (58.9, 47.4, "SOLVED", 0.06)], random=("L_mm",))
    _assert_pngs(plot_sweep(scattered, tmp_path / "r"), ["sweep_max_deviation_mm_vs_H_mm_L_mm.png"])
    failed = _hand_table([(h, l, "INFEASIBLE", 0.09) for h in (58.0, 59.0) for l in (47.0, 48.0)])
    _assert_pngs(plot_sweep(failed, tmp_path / "f"), ["sweep_max_deviation_mm_vs_H_mm_L_mm.png"])
    empty = _hand_table([(58.0, 47.0, "SOLVED", 0.05)]).slice(0, 0)
    (path,) = plot_sweep(empty, tmp_path / "e", outputs=["max_deviation_mm"])
    assert path.stat().st_size > 0
