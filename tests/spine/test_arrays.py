"""Every scene returns its arrays: what `--csv`, `figures()` and a notebook read,
named with units, read-only, and consistent with the values they come with."""
import numpy as np
import pytest

import mechopt
from mechopt.cli import arrays_csv
from mechopt.models.cam_cutter import limacon_implicit
from mechopt.units import unit_of

# scenes that return no arrays, and why; every other registry scene must return some
WITHOUT_ARRAYS = {
    "loom/group1-window-conflict": "INFEASIBLE: no plan exists, the answer is the conflicting chain (its message)",
    "stop-impact/frequencies": "closed-form scalars (stiffnesses, frequencies, contact time): no series to sample",
}
LABEL_COLUMNS = {"parameter", "operation", "event"}       # text naming a table's rows
# numbers with no unit: a flag, counts and indices, a ratio, and a column whose rows each have their
# parameter's unit (the sensitivity's `parameter_value`)
UNITLESS = {"cutting", "condition_number", "row", "code", "ratio", "parameter_value"}


def _ids():
    return [scene.spec.id for scene in mechopt.scenes()]


@pytest.mark.parametrize("scene_id", _ids())
def test_every_scene_returns_named_read_only_arrays_or_says_why_not(scene_id, solved_once):
    arrays = mechopt.solve(scene_id).arrays
    if scene_id in WITHOUT_ARRAYS:
        assert not arrays, f"{scene_id} now returns arrays: strike it from WITHOUT_ARRAYS"
        return
    assert arrays, f"{scene_id} returns no arrays"
    for name, array in arrays.items():
        assert not array.flags.writeable, name
        if name in LABEL_COLUMNS:
            assert array.dtype.kind == "U", name
        else:
            assert array.dtype == float, name
            assert unit_of(name) or "elasticity" in name or name in UNITLESS, \
                f"{scene_id}: array {name} states no unit"


def test_the_minimax_linkage_along_the_path_is_its_values():
    run = mechopt.solve("cam-cutter/minimax")
    a, v = run.arrays, run.values
    # the sampled deviation never exceeds the verified maximum, and comes within a sample spacing of it
    assert a["deviation_mm"].max() <= v["max_deviation_mm"] + 1e-12
    assert a["deviation_mm"].max() > v["max_deviation_mm"] - 1e-4
    # each limaçon point is at that distance from its path point, and on the limaçon (H, L)
    gap = np.hypot(a["limacon_x_mm"] - a["path_x_mm"], a["limacon_y_mm"] - a["path_y_mm"])
    np.testing.assert_allclose(gap, a["deviation_mm"], atol=1e-12)
    H, L = v["H_mm"], v["L_mm"]
    on_curve = limacon_implicit(a["limacon_x_mm"], a["limacon_y_mm"], H, L) / (H + L) ** 4
    assert np.abs(on_curve).max() < 1e-12

def test_the_grid_scans_answer_and_the_best_achievable_carry_the_path():
    found = mechopt.solve("cam-cutter/paper-grid")
    assert found.arrays["deviation_mm"].max() <= found.values["max_deviation_mm"] + 1e-12
    infeasible = mechopt.solve("cam-cutter/paper-grid", {"err_width_mm": 0.05})
    assert infeasible.result.status is mechopt.Status.INFEASIBLE
    assert infeasible.arrays["deviation_mm"].max() <= infeasible.values["best_deviation_mm"] + 1e-12


def test_the_loom_plan_is_a_table_of_operations_named_by_their_events():
    run = mechopt.solve("loom/group1")
    a, v = run.arrays, run.values
    assert list(a["operation"])[:2] == ["1->2", "1->3"]
    for k, op in enumerate(a["operation"]):
        x, y = op.split("->")
        assert a["start_deg"][k] == v[f"p_{x}_deg"] and a["end_deg"][k] == v[f"p_{y}_deg"]
        assert a["duration_deg"][k] == pytest.approx(v[f"t_{x}_{y}_deg"], abs=1e-12)
    floats = dict(zip(a["operation"], a["float_deg"]))
    assert min(floats.values()) > -1e-9
    assert all(floats[op] <= 1e-6 for op in run.result.diagnostics["critical_ops"])


def test_a_rebound_history_peaks_at_the_rebound_and_writes_as_csv():
    run = mechopt.solve("stop-impact/rebound-280-420")
    a = run.arrays
    for n in (280, 320, 370, 420):
        q = a[f"q_mm_{n}"]
        assert q[0] == 0.0                      # q(0) = 0: the lever leaves the plate's rest position
        assert q.max() == pytest.approx(run.values[f"rebound_mm_{n}"], rel=1e-3)
        assert q.max() <= run.values[f"rebound_mm_{n}"] * (1 + 1e-12)
    header = arrays_csv(a, "rebound.csv").splitlines()[0]
    assert header == "t_s,q_mm_280,q_mm_320,q_mm_370,q_mm_420"


def test_label_columns_write_as_text_in_csv():
    text = arrays_csv(mechopt.solve("loom/group1").arrays, "plan.csv").splitlines()
    assert text[0].startswith("operation,start_deg,end_deg,duration_deg,float_deg")
    assert text[1].startswith("1->2,0,10,10,")


def test_the_cam_rise_of_every_speed_is_on_the_nominal_angles_as_the_figure_draws_it():
    """cam_dynamics returns each speed's rise (what the Fig. 4 figure draws, no longer recomputed
    there): on the nominal rise's angles, the samples are that speed's own, NaN past its end."""
    from mechopt.solvers.stop_impact.cam_follower import follow_cam
    run = mechopt.solve("stop-impact/cam-dynamics")
    a, v, task = run.arrays, run.values, run.task
    rad = np.radians(task.t_deg)
    for n in (280, 320, 370):
        rise = follow_cam(task, float(n))
        shared = min(len(rise.xi), len(a["phi_deg"])) - 1          # the grid points both have (not the contact)
        np.testing.assert_allclose(a[f"x_mm_{n}"][:shared], rise.X[:shared] * task.stroke_mm, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(a[f"d2x_dphi2_mm_per_rad2_{n}"][:shared], rise.ddX[:shared] * task.stroke_mm / rad**2,
                                   rtol=1e-12, atol=1e-9)
        assert v[f"contact_angle_deg_{n}"] == pytest.approx(rise.contact_xi * task.t_deg, rel=1e-12)
    # the rigid law's analogues beside them: its velocity analogue integrates to its displacement
    phi = np.radians(a["phi_deg"])
    rise_of_s = np.sum(np.diff(phi) * (a["ds_dphi_mm_per_rad"][1:] + a["ds_dphi_mm_per_rad"][:-1]) / 2)
    assert rise_of_s == pytest.approx(a["s_mm"][-1] - a["s_mm"][0], rel=1e-5)
