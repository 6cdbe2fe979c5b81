"""Are the cam-cutter answers global? The certificate's bound against brute
force, and each solver's answer against a brute-force search of its own question."""
import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.result import Status
from mechopt.solvers.cam_cutter.bound import cell_bounds, tangent_bound
from mechopt.solvers.cam_cutter.certificate import (
    Cells,
    _measure,
    box_lower_bound,
    largest_distance,
    lipschitz_radius,
    warm_cells,
)
from mechopt.solvers.cam_cutter.deviation import foot_points


@pytest.mark.parametrize("hH, hL", [(0.0, 1.0), (1.0, 0.0), (1.0, 1.0), (3.0, 0.2), (0.01, 2.5)])
def test_lipschitz_radius_is_the_largest_move_of_a_limacon_point(hH, hL):
    s = np.linspace(0.0, 2 * np.pi, 200_001)
    moves = [np.hypot(dL * (np.cos(s) - 1) + dH / 2 * (np.cos(2 * s) - 1), dL * np.sin(s) + dH / 2 * np.sin(2 * s)).max()
             for dH in (-hH, hH) for dL in (-hL, hL)]         # linear in (dH, dL): largest at a corner
    assert lipschitz_radius(hH, hL) == pytest.approx(max(moves), rel=1e-8)


def test_the_lower_bound_is_below_every_linkage_of_its_box():
    task, _ = registry.find("cam-cutter/other-profile").build()
    px, py = task.path_point(np.linspace(task.t_start_rad, task.t_end_rad, 40))
    box = (-16.0, -11.0, 50.0, 55.0)
    got = box_lower_bound(px, py, box, upper=0.5, gap=0.02, max_cells=800)
    rng = np.random.default_rng(7)
    values = [largest_distance(px, py, rng.uniform(*box[:2]), rng.uniform(*box[2:])) for _ in range(200)]
    assert got.cells >= 128 and got.lower <= min(values)
    assert got.lower > 0.25                # and it is no empty bound: the box's best is ~0.30 mm


def _dense_distance(px, py, H, L):
    """Distance [mm] from each point to the limaçon (10): nearest of 2^16 vertices, then Newton on
    the foot condition (`foot_points`, which the bound does not use: it has its own polyline,
    Newton and windows)."""
    return foot_points(px, py, H, L, vertices=2**16)[0]


# cells about each scene's optimum, small and large, and one across the cardioid's double-point node
CELLS = [("cam-cutter/minimax", 59.6018, 47.4275, h) for h in (0.002, 0.05, 1.0)] + \
        [("cam-cutter/other-profile", -13.5629, 52.1528, h) for h in (0.002, 0.05, 1.0)] + \
        [("cam-cutter/table-profile", 4.0764, 52.0001, h) for h in (0.001, 0.2)]


@pytest.mark.parametrize("scene, H0, L0, h", CELLS)
def test_each_cell_bound_is_below_the_distance_everywhere_in_its_cell(scene, H0, L0, h):
    """Brute force: on a 7 x 7 grid of (H, L) over the cell (corners included) every node's dense
    distance is at least the cell's zero-order bound and, where it applies, the first-order bound
    at that (H, L); so the largest over nodes is at least the cell's bound (`_measure`)."""
    task, _ = registry.find(scene).build()
    px, py = task.path_point(np.linspace(task.t_start_rad, task.t_end_rad, 60))
    H, L, hH, hL = H0 + 0.3 * h, L0 - 0.2 * h, h, 0.7 * h
    zero, d0, gH, gL, E, first = cell_bounds(px, py, H, L, hH, hL)
    assert first.mean() >= 0.8                        # the first-order bound is the rule, not the exception
    cells = Cells(*(np.array([v]) for v in (H, L, hH, hL, -np.inf)))
    bound = _measure(px, py, cells, np.arange(px.size)[None, :])[0].bound[0]
    least = _least_largest_distance(px, py, (H, L, hH, hL), (zero, d0, gH, gL, E, first), 7)
    assert bound <= least + 1e-12
    if h <= 0.002:                     # and near the optimum within the certificate's 1e-3 mm target
        assert least - bound < 5e-4


# the second-order window (signed curvature, the move's own normal and tangential parts): cells at
# each optimum where it closes the certificate, one far from it, and a coarse one across it
DENSE_CELLS = [("cam-cutter/minimax", 59.6018, 47.4275, 0.0, 0.05), ("cam-cutter/minimax", 59.6018, 47.4275, 0.0, 0.1),
               ("cam-cutter/minimax", 59.6018, 47.4275, 3.0, 0.5), ("cam-cutter/minimax", 59.6018, 47.4275, 0.0, 0.8),
               ("cam-cutter/other-profile", -13.5629, 52.1528, 0.0, 0.05)]


@pytest.mark.parametrize("scene, H0, L0, away, h", DENSE_CELLS)
def test_the_bound_is_below_brute_force_on_a_dense_grid_of_its_cell(scene, H0, L0, away, h):
    """Brute force on a 13 x 13 grid of (H, L) over the cell (corners included): every node's
    dense distance is at least each of its bounds, and the cell's bound (`_measure`, on every node)
    is at most the least largest distance; at the cardioid's optimum it is within the certificate's
    1e-3 mm target already at h = 0.05 mm (the window of the first-order bound second order in h)."""
    task, _ = registry.find(scene).build()
    px, py = task.path_point(np.linspace(task.t_start_rad, task.t_end_rad, 60))
    H, L, hH, hL = H0 + away, L0 - 0.7 * away, h, 2 * h
    zero, d0, gH, gL, E, first = cell_bounds(px, py, H, L, hH, hL)
    cells = Cells(*(np.array([v]) for v in (H, L, hH, hL, -np.inf)))
    bound = _measure(px, py, cells, np.arange(px.size)[None, :])[0].bound[0]
    least = _least_largest_distance(px, py, (H, L, hH, hL), (zero, d0, gH, gL, E, first), 13)
    assert bound <= least + 1e-12
    if scene == "cam-cutter/minimax" and away == 0.0 and h <= 0.05:
        assert least - bound < 1e-3


def test_the_first_order_bound_holds_at_the_double_point_node():
    # the cardioid's last node sits by the limaçon's double point, where its two branches cross;
    # it is one of the answer's active nodes, so the bound must be first order there
    task, _ = registry.find("cam-cutter/minimax").build()
    px, py = task.path_point(np.array([task.t_end_rad]))
    zero, d0, gH, gL, E, first = cell_bounds(px, py, 59.6, 47.43, 0.01, 0.01)
    assert first[0]
    for dH in (-0.01, 0.0, 0.01):
        for dL in (-0.01, 0.0, 0.01):
            true = _dense_distance(px, py, 59.6 + dH, 47.43 + dL)[0]
            assert true >= (d0[0] + gH[0] * dH + gL[0] * dL - E[0]).min() - 1e-12


def test_the_tangent_bound_of_pairs_in_one_call_is_each_pairs_own():
    """The tangent-segment bound takes every pair's near arcs in one flat array: pairs with one near
    arc and with many (nodes by the cardioid's double point, where two branches pass, and along
    the path; small and large cells) give in one call what each gives alone, and each is below the
    dense distance over its cell's corners and centre."""
    task, _ = registry.find("cam-cutter/minimax").build()
    px, py = task.path_point(np.linspace(0.0, task.t_end_rad, 9))
    h = np.array([0.002, 0.05, 0.4, 1.5, 0.01, 0.2, 3.0, 0.1, 0.8])
    H, L = 59.6 + h, 47.43 - h / 2
    together = tangent_bound(px, py, H, L, h, 2 * h)
    alone = [tangent_bound(px[k:k + 1], py[k:k + 1], H[k], L[k], h[k], 2 * h[k])[0] for k in range(px.size)]
    assert np.array_equal(together, alone) and np.isfinite(together).all()
    for k in range(px.size):
        for dH, dL in ((0, 0), (-1, -1), (-1, 1), (1, -1), (1, 1)):
            assert together[k] <= _dense_distance(px[k:k + 1], py[k:k + 1], H[k] + dH * h[k], L[k] + 2 * dL * h[k])[0]


def test_a_warm_start_is_a_bound_for_the_moved_nodes():
    """Leaves of one path's certificate, lowered by how far its nodes moved, bound another's."""
    task, _ = registry.find("cam-cutter/minimax").build()
    box = (58.0, 61.0, 46.0, 49.0)
    t = np.linspace(0.0, task.t_end_rad, 30)
    px, py = task.path_point(t)
    first = box_lower_bound(px, py, box, upper=0.0609, gap=1e-3)
    shift = 0.004                                      # the path moved rigidly by 4 um
    moved = warm_cells(first.leaves, shift, box)
    again = box_lower_bound(px + shift, py, box, upper=0.0609, gap=0.02, start=moved)
    assert again.warm_started and again.cells < first.cells
    grid = [(H, L) for H in np.linspace(58.0, 61.0, 13) for L in np.linspace(46.0, 49.0, 13)]
    assert again.lower <= min(_dense_distance(px + shift, py, H, L).max() for H, L in grid)


def test_a_warm_start_coarsened_to_the_move_is_still_a_bound():
    """Leaves finer than `finest` give way to unmeasured cells as wide over their span: fewer
    cells to start from, and the bound still below brute force over the moved path's box."""
    task, _ = registry.find("cam-cutter/minimax").build()
    box = (58.0, 61.0, 46.0, 49.0)
    px, py = task.path_point(np.linspace(0.0, task.t_end_rad, 30))
    first = box_lower_bound(px, py, box, upper=0.0609, gap=1e-3)
    shift = 0.03                                       # 30 gap targets: the fine leaves are stale
    start = warm_cells(first.leaves, shift, box, finest=0.1)
    fine = np.maximum(first.leaves.hH, first.leaves.hL) < 0.1
    assert fine.any() and start.H.size < first.leaves.H.size
    assert np.all(np.isinf(start.bound[-(start.H.size - int((~fine).sum())):]))      # the new cells: unmeasured
    again = box_lower_bound(px + shift, py, box, upper=0.0609, gap=1e-3, start=start)
    grid = [(H, L) for H in np.linspace(58.0, 61.0, 13) for L in np.linspace(46.0, 49.0, 13)]
    assert again.warm_started and again.lower <= min(_dense_distance(px + shift, py, H, L).max() for H, L in grid)


def test_a_sweep_warm_starts_the_certificate_and_keeps_the_answer():
    from mechopt.kit import warm
    cold = registry.run("cam-cutter/minimax", {"err_width_mm": 0.08}).result
    with warm.session():
        registry.run("cam-cutter/minimax", {"err_width_mm": 0.075})
        hot = registry.run("cam-cutter/minimax", {"err_width_mm": 0.08}).result
    assert hot.diagnostics["global_warm_started"] and not cold.diagnostics["global_warm_started"]
    assert hot.diagnostics["global_cells"] < cold.diagnostics["global_cells"]
    assert hot.status is cold.status is Status.SOLVED and hot.diagnostics["global_certified"]
    assert hot.values == cold.values


def test_the_cardioid_minimax_is_certified_global_over_its_box():
    run = registry.run("cam-cutter/minimax")
    d = run.result.diagnostics
    assert run.status is Status.SOLVED and d["global_certified"]
    assert 0 <= d["global_gap_mm"] <= d["global_gap_target_mm"] == pytest.approx(1e-3)
    # brute force over the same box on a 1 mm grid (100 nodes): nothing below the bound
    task = run.task
    px, py = task.path_point(np.linspace(0.0, task.t_end_rad, 100))
    H_lo, H_hi, L_lo, L_hi = d["box_mm"]
    best = min(largest_distance(px, py, H, L) for H in np.arange(H_lo, H_hi, 1.0) for L in np.arange(L_lo, L_hi, 1.0))
    assert d["global_lower_bound_mm"] <= best
    assert run.values["max_deviation_mm"] <= best + 1e-9


def _best_band(a, h, H, nodes=120):
    """min over L (bounded Brent within +-3 mm of the L that keeps the double point: H + L = the
    matched span) of the cam's largest node distance at fixed H [mm]."""
    from scipy.optimize import minimize_scalar

    from mechopt.models.cam_cutter import finish_angle, ideal_point, matched_linkage
    from mechopt.solvers.cam_cutter.deviation import foot_points
    px, py = ideal_point(np.linspace(0.0, finish_angle(a, h), nodes), a, h)
    L0 = sum(matched_linkage(a, h)) - H
    return minimize_scalar(lambda L: foot_points(px, py, H, L, vertices=2**12)[0].max(),
                           bounds=(L0 - 3.0, L0 + 3.0), method="bounded", options={"xatol": 1e-6}).fun


@pytest.mark.parametrize("scene, H_range", [("cam-cutter/readjustable", (45.0, 75.0)),
                                            ("cam-cutter/family-too-wide", (40.0, 80.0))])
def test_the_family_answer_is_the_brute_force_minimum_over_H(scene, H_range):
    from scipy.optimize import minimize_scalar
    run = registry.run(scene, {"served": False} if scene.endswith("readjustable") else {})
    assert run.result.diagnostics["global_certified"] is False        # stated, not certified
    # the two members whose band is widest at the answer: their worst band, a lower bound of the
    # family's at every H, minimised over H by brute force (a 2 mm grid, then Brent around its best)
    active = np.argsort(run.arrays["deviation_mm"])[::-1][:2]
    members = [run.task.members[i] for i in active]

    def worst(H):
        return max(_best_band(a, h, H) for a, h in members)

    grid = np.arange(*H_range, 2.0)
    k = int(np.argmin([worst(H) for H in grid]))
    found = minimize_scalar(worst, bounds=(grid[k] - 2.0, grid[k] + 2.0), method="bounded", options={"xatol": 1e-5})
    # nothing in H_range does better than the answer (to the node sampling), and it is the same H
    assert run.values["worst_deviation_mm"] <= found.fun + 2e-4
    assert found.x == pytest.approx(run.values["H_mm"], abs=0.02)


def test_the_robust_answer_is_the_best_worst_case_of_the_lattice_around_it():
    from mechopt.solvers.cam_cutter.deviation import path_distance
    run = registry.run("cam-cutter/robust")
    assert run.result.diagnostics["global_certified"] is False        # a descent: stated, not certified
    task, step = run.task, run.task.step_mm
    px, py = task.path_point(np.linspace(0.0, task.t_end_rad, 1000))
    i0, j0 = round(run.values["H_mm"] / step), round(run.values["L_mm"] / step)
    near = {(i, j): path_distance(px, py, i * step, j * step).max()
            for i in range(i0 - 6, i0 + 7) for j in range(j0 - 6, j0 + 7)}

    def worst_case(i, j):
        return max(near[i + di, j + dj] for di in (-1, 0, 1) for dj in (-1, 0, 1))

    best = min(worst_case(i, j) for i in range(i0 - 5, i0 + 6) for j in range(j0 - 5, j0 + 6))
    assert worst_case(i0, j0) == pytest.approx(best, abs=1e-12)      # no lattice point within 0.05 mm does better


def test_a_cam_whose_inner_loop_lies_near_a_node_is_still_certified():
    # a = 22, h = 0.1 mm: the limaçon's inner loop (H - L ~ 1.8 mm) lies near the last node, whose
    # first-order bound then does not apply; the tangent-segment bound on the near arcs closes it
    run = registry.run("cam-cutter/minimax", {"a_mm": 22.0, "h_mm": 0.1})
    d = run.result.diagnostics
    assert run.status is Status.SOLVED and d["global_certified"] and d["global_cells"] < 5000
    task = run.task
    px, py = task.path_point(np.linspace(0.0, task.t_end_rad, 100))
    H_lo, H_hi, L_lo, L_hi = d["box_mm"]
    best = min(largest_distance(px, py, H, L) for H in np.arange(H_lo, H_hi, 1.0) for L in np.arange(L_lo, L_hi, 1.0))
    assert d["global_lower_bound_mm"] <= best


def _least_largest_distance(px, py, cell, bounds, n):
    """Brute force on an n x n grid of (H, L) over the cell (corners included): every node's dense
    distance at least its zero- and first-order bounds; the least over the grid of the largest distance."""
    (H, L, hH, hL), (zero, d0, gH, gL, E, first) = cell, bounds
    least = np.inf
    for dH in np.linspace(-hH, hH, n):
        for dL in np.linspace(-hL, hL, n):
            true = _dense_distance(px, py, H + dH, L + dL)
            affine = np.where(first, (d0 + gH * dH + gL * dL - E).min(axis=1), -np.inf)
            assert np.all(true >= zero - 1e-12) and np.all(true >= affine - 1e-12)
            least = min(least, true.max())
    return least


def test_certificates_on_four_threads_match_serial_ones():
    """The bound's tables (vertex offsets, sub-arc angles) are shared read-only by every call: the
    certificates of eight cams, four threads at a time, are the serial ones to the last bit."""
    from concurrent.futures import ThreadPoolExecutor
    task, _ = registry.find("cam-cutter/minimax").build()
    box = (57.0, 62.0, 45.0, 50.0)
    px, py = task.path_point(np.linspace(0.0, task.t_end_rad, 27))
    paths = [(px * (1 + 0.002 * k), py * (1 + 0.002 * k)) for k in range(8)]      # cams 0.2 % apart

    def certify(path):
        got = box_lower_bound(*path, box, upper=0.0609, gap=1e-3)
        return got.lower, got.cells, got.leaves.bound.tobytes()

    serial = [certify(p) for p in paths]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(certify, paths))
    assert threaded == serial and len({s[0] for s in serial}) > 1
