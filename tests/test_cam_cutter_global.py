"""Are the cam-cutter answers global (issue 20, Sec. 3)? The certificate's bound against brute
force, and each solver's answer against a brute-force search of its own question."""
import numpy as np
import pytest

from mechopt import registry
from mechopt.solvers.cam_cutter.certificate import box_lower_bound, largest_distance, lipschitz_radius
from mechopt.solvers.result import Status


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
    lower, cells, complete = box_lower_bound(px, py, box, upper=0.5, gap=0.02, max_cells=800)
    rng = np.random.default_rng(7)
    values = [largest_distance(px, py, rng.uniform(*box[:2]), rng.uniform(*box[2:])) for _ in range(200)]
    assert cells > 64 and lower <= min(values)
    assert lower > 0.25                # and it is no empty bound: the box's best is ~0.30 mm


def test_the_cardioid_minimax_is_certified_global_over_its_box():
    run = registry.run("cam-cutter/minimax")
    d = run.result.diagnostics
    assert run.status is Status.SOLVED and d["global_certified"]
    assert 0 <= d["global_gap_mm"] <= d["global_gap_target_mm"] == pytest.approx(1e-3)
    # brute force over the same box on a 0.5 mm grid (100 nodes): nothing below the bound
    task = run.task
    px, py = task.path_point(np.linspace(0.0, task.t_end_rad, 100))
    H_lo, H_hi, L_lo, L_hi = d["box_mm"]
    best = min(largest_distance(px, py, H, L) for H in np.arange(H_lo, H_hi, 0.5) for L in np.arange(L_lo, L_hi, 0.5))
    assert d["global_lower_bound_mm"] <= best
    assert run.values["max_deviation_mm"] <= best + 1e-9
