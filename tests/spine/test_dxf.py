"""The cam and the torch path to the shop: `mechopt run SCENE --dxf DIR`
writes closed polylines on named layers in mm that, re-read by ezdxf, match the model's curve
within the stated chordal error; one writer at a time, never a partial file, and a scene with
nothing to export says so."""
import math
import os
import sys

import ezdxf
import numpy as np
import pytest

import mechopt
from mechopt import dxf
from mechopt.cli import main
from mechopt.figures import cam_cutter as cutter_output
from mechopt.files import take_lock
from mechopt.kit.errors import MechoptError, SceneError
from mechopt.models.cam_cutter import ideal_point, limacon_implicit, real_point
from mechopt.models.cam_shape import chord_errors, distance_to_segment, flank, mirrored, pitch

LIFT = "stop-impact/lift-cam-profile"


@pytest.fixture(scope="module")
def lift():
    return mechopt.solve(LIFT)


def _within_chords(curve, t, xy, stated, period=2 * math.pi):
    """The model's curve, sampled densely inside every chord between the file's vertices, stays
    within the stated chordal error of that chord."""
    ends = np.r_[t, period]
    frac = np.arange(1, 200) / 200
    inner = ends[:-1, None] + frac * np.diff(ends)[:, None]
    Q = np.asarray(curve(inner.ravel())).reshape(2, *inner.shape)
    A, B = xy.T, np.roll(xy, -1, axis=0).T
    worst = distance_to_segment(Q, A[:, :, None], B[:, :, None]).max()
    assert worst <= stated * (1 + 1e-3), (worst, stated)
    return worst


def test_the_lift_cam_re_read_by_ezdxf_matches_the_model_within_its_chordal_error(lift, tmp_path):
    [(path, _), *_] = dxf.export_run(lift, tmp_path)
    doc = ezdxf.readfile(str(path))
    assert doc.header["$INSUNITS"] == 4 and {"CAM_PROFILE", "CAM_GROOVE_OUTER", "PITCH_CURVE"} <= {layer.dxf.name for layer in doc.layers}
    read = dxf.read_polylines(path)
    stated = lift.values["chord_error_mm"]
    assert stated <= lift.task.chord_tol_mm == 0.01
    curves = {"CAM_PROFILE": ("profile", lambda t: flank(lift.task, t, "inner")),
              "CAM_GROOVE_OUTER": ("groove_outer", lambda t: flank(lift.task, t, "outer")),
              "PITCH_CURVE": ("pitch", lambda t: pitch(lift.task, t).P)}
    for layer, (name, curve) in curves.items():
        t = np.radians(lift.arrays[f"{name}_cam_angle_deg"])
        xy = read[layer]
        assert xy.shape == (t.size, 2)
        assert np.allclose(xy, np.asarray(curve(t)).T, atol=1e-9), layer      # every vertex on the curve
        _within_chords(curve, t, xy, stated)


@pytest.fixture(scope="module")
def minimax():
    return mechopt.solve("cam-cutter/minimax")


def _torch_cut(H, L):
    """The limaçon from the origin to its double point (arccos(-L/H), where its inner loop begins)
    and its mirror, as the shop's drawing tables it."""
    end = math.acos(-L / H)
    cut = mirrored(lambda s: np.array(real_point(s, H, L)), 0.0, end)
    return cut, end, cutter_output.point_table(cut, cutter_output.TORCH_TOL_MM, period=2 * end, breaks=(end,))


def test_the_torch_path_is_the_solved_limacon_and_the_ideal_path_on_another_layer(minimax, tmp_path):
    [(path, torch), (_, ideal)] = dxf.export_run(minimax, tmp_path)
    read = dxf.read_polylines(path)
    H, L = minimax.values["H_mm"], minimax.values["L_mm"]
    xy = read["TORCH_PATH"]
    assert np.abs(limacon_implicit(xy[:, 0], xy[:, 1], H, L)).max() < 1e-6 * (H + L) ** 4
    curve, end, table = _torch_cut(H, L)
    assert np.allclose(xy, table.xy, atol=1e-9)
    assert torch.chord_error_mm <= cutter_output.TORCH_TOL_MM and ideal.chord_error_mm <= cutter_output.TORCH_TOL_MM
    _within_chords(curve, table.t, xy, torch.chord_error_mm, period=2 * end)
    assert np.abs(read["IDEAL_PATH"][:, 1]).max() > 0 and read["IDEAL_PATH"][0] == pytest.approx([0.0, 0.0], abs=1e-12)


def _crossings(xy, closed=True) -> int:
    """Pairs of non-adjacent segments of a polyline that cross (each strictly straddles the other's line)."""
    A = xy if closed else xy[:-1]
    B = np.roll(xy, -1, axis=0) if closed else xy[1:]
    n = len(A)

    def side(P, Q, R):                               # sign of (Q - P) x (R - P), all pairs
        return np.sign((Q[:, None, 0] - P[:, None, 0]) * (R[None, :, 1] - P[:, None, 1])
                       - (Q[:, None, 1] - P[:, None, 1]) * (R[None, :, 0] - P[:, None, 0]))
    straddle = (side(A, B, A) * side(A, B, B) < 0) & (side(A, B, A) * side(A, B, B) < 0).T
    i, j = np.triu_indices(n, 2)
    keep = ~((i == 0) & (j == n - 1)) if closed else np.ones_like(i, bool)
    return int(straddle[i[keep], j[keep]].sum())


def test_the_torch_path_is_cut_without_its_inner_loop_and_ends_where_the_ideal_path_ends(minimax, tmp_path):
    """The solved linkage's limaçon has an inner loop (H > L: a 12 x 6 mm contour inside the cam,
    x -107 ... -95 mm); the drawing cuts to its double point and the mirror closes it."""
    [(path, _), *_] = dxf.export_run(minimax, tmp_path)
    read = dxf.read_polylines(path)
    H, L = minimax.values["H_mm"], minimax.values["L_mm"]
    assert H > L
    whole = cutter_output.point_table(lambda s: np.array(real_point(s, H, L)), cutter_output.TORCH_TOL_MM)
    assert _crossings(whole.xy) > 0                 # the whole limaçon crosses itself: the check can fail
    xy = read["TORCH_PATH"]
    assert _crossings(xy) == 0
    # every vertex on the outer branch: about the pole (-(L + H), 0) its distance rho is L + H cos
    # of its polar angle (on the inner loop it would be H cos - L)
    u, v = xy[:, 0] + L + H, xy[:, 1]
    rho = np.hypot(u, v)
    assert np.abs(rho - (L + H * u / np.where(rho > 0, rho, 1.0)))[rho > 1e-9].max() < 1e-9 * (H + L)
    on_axis = [p[np.abs(p[:, 1]) < 1e-9] for p in (xy, read["IDEAL_PATH"])]
    assert [len(a) for a in on_axis] == [2, 2]      # the start at the origin, the corner at t_FINISH
    assert on_axis[0][1] == pytest.approx([-(H + L), 0.0], abs=1e-9)             # the double point
    end = np.array(ideal_point(minimax.task.t_end_rad, minimax.task.a_mm, minimax.task.h_mm))
    assert on_axis[1][1] == pytest.approx(end, abs=1e-9)
    # the ideal path's end lies on the cut's branch through the double point within the solved
    # deviation: a brute-force foot search on the limaçon near its double point
    s = math.acos(-L / H) + np.linspace(-0.05, 0.05, 200_001)
    gap = np.hypot(*(np.array(real_point(s, H, L)) - end[:, None])).min()
    assert gap <= minimax.values["max_deviation_mm"] * (1 + 1e-6)


def test_cli_run_dxf_writes_the_drawing_and_names_each_layers_error(tmp_path, capsys):
    assert main(["run", LIFT, "--dxf", str(tmp_path / "shop")]) == 0
    out = capsys.readouterr().out
    assert "dxf: " in out and "CAM_PROFILE:" in out and "chordal error 0.00" in out
    assert (tmp_path / "shop" / "stop-impact_lift-cam-profile.dxf").exists()


def test_a_scene_with_nothing_to_export_says_so_and_writes_nothing(tmp_path, capsys):
    assert main(["run", "stop-impact/frequencies", "--dxf", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "nothing to export as DXF (task LeverStop)" in err and "nothing was solved" in err
    assert not list(tmp_path.iterdir())


def test_an_undercut_cam_is_not_exported(tmp_path, capsys):
    code = main(["run", LIFT, "--dxf", str(tmp_path), "--set", "roller_radius_mm=30", "--set", "base_radius_mm=45"])
    assert code == 3
    err = capsys.readouterr().err
    assert "status INFEASIBLE, nothing exported as DXF (undercut: roller_radius_mm=30" in err
    assert "at cam angle 26.988 deg (inner flank)" in err
    assert not list(tmp_path.iterdir())


def test_a_second_writer_is_refused_and_the_first_ones_lock_is_left_alone(lift, tmp_path):
    target = tmp_path / "cam.dxf"
    fd = take_lock(tmp_path / "cam.dxf.lock")
    try:
        with pytest.raises(SceneError, match="cam.dxf is being written by another process"):
            dxf.write_dxf(dxf.shop_curves(lift), target)
        assert not target.exists()
    finally:
        os.close(fd)
    dxf.write_dxf(dxf.shop_curves(lift), target)
    assert target.exists() and not (tmp_path / "cam.dxf.lock").exists()


def test_a_failed_write_leaves_no_partial_file(lift, tmp_path, monkeypatch):
    def broken(curves, *, title=""):
        raise OSError("disk full")
    monkeypatch.setattr(dxf, "dxf_bytes", broken)
    with pytest.raises(OSError, match="disk full"):
        dxf.write_dxf(dxf.shop_curves(lift), tmp_path / "cam.dxf")
    assert not list(tmp_path.iterdir())
    monkeypatch.undo()
    import mechopt.files
    real = mechopt.files.os.replace
    monkeypatch.setattr(mechopt.files.os, "replace", lambda *a: (_ for _ in ()).throw(OSError("no space")))
    with pytest.raises(OSError, match="no space"):
        dxf.write_dxf(dxf.shop_curves(lift), tmp_path / "cam.dxf")
    monkeypatch.setattr(mechopt.files.os, "replace", real)
    assert not list(tmp_path.iterdir())


def test_without_ezdxf_the_error_names_the_extra(lift, monkeypatch):
    monkeypatch.setitem(sys.modules, "ezdxf", None)
    with pytest.raises(MechoptError, match=r"writing DXF needs ezdxf: pip install 'mechopt\[dxf\]'"):
        dxf.dxf_bytes(dxf.shop_curves(lift))


def test_a_file_where_the_dxf_folder_belongs_is_refused_before_any_work(tmp_path, capsys):
    (tmp_path / "f").write_text("x")
    assert main(["run", LIFT, "--dxf", str(tmp_path / "f")]) == 2
    assert "an existing file, not a folder" in capsys.readouterr().err


def test_the_stated_error_is_measured_not_assumed(lift):
    t = np.radians(lift.arrays["profile_cam_angle_deg"])
    curve = lambda s: flank(lift.task, s)                            # noqa: E731
    measured = chord_errors(curve, np.r_[t, 2 * math.pi], 64).max()
    assert measured <= lift.values["chord_error_mm"] + 1e-15
    assert measured > 0.5 * lift.task.chord_tol_mm                  # not a loose bound: the points are spent


def test_without_ezdxf_the_cli_says_so_before_solving(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "ezdxf", None)
    assert main(["run", LIFT, "--dxf", str(tmp_path)]) == 2
    err = capsys.readouterr()
    assert "pip install 'mechopt[dxf]'" in err.err and "status" not in err.out


def test_an_ideal_path_its_mirror_does_not_close_is_drawn_open_to_its_end(tmp_path):
    run = mechopt.solve("cam-cutter/other-profile", t1_rad=2.5, err_width_mm=5.0)       # ends off the axis
    curves = {c.layer: c for c in dxf.shop_curves(run)}
    ideal, torch = curves["IDEAL_PATH"], curves["TORCH_PATH"]
    assert not torch.closed and not ideal.closed and ideal.chord_error_mm <= cutter_output.TORCH_TOL_MM
    end = np.array(run.task.path_point(np.array([2.5]))).ravel()
    assert ideal.xy[-1] == pytest.approx(end, abs=1e-12)
    feet = np.column_stack([run.arrays["limacon_x_mm"], run.arrays["limacon_y_mm"]])[[0, -1]]
    assert torch.xy[[0, -1]] == pytest.approx(feet, abs=1e-9)      # the torch cut between the path's feet
    assert _crossings(torch.xy, closed=False) == 0
    path = dxf.write_dxf(list(curves.values()), tmp_path / "open.dxf")
    [polyline] = [e for e in ezdxf.readfile(str(path)).modelspace() if e.dxf.layer == "IDEAL_PATH"]
    assert not polyline.closed


def test_the_dxf_module_knows_no_mechanism_and_writers_are_registered_by_solver():
    """dxf.py writes drawings; which curves a solver's result has is said beside its figures."""
    import ast
    from pathlib import Path
    tree = ast.parse(Path(dxf.__file__).read_text(encoding="utf-8"))
    imported = [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    assert not [m for m in imported if m.startswith(("mechopt.models", "mechopt.solvers"))]
    from mechopt.figures import cam_shape
    from mechopt.solvers.cam_cutter import minimax
    from mechopt.solvers.stop_impact import cam_profile
    assert dxf.SHOP_DRAWINGS[cam_profile] is cam_shape.cam_shop_curves
    assert dxf.SHOP_DRAWINGS[minimax] is cutter_output.torch_shop_curves
    with pytest.raises(MechoptError, match="registered twice"):
        dxf.shop_drawing(minimax)(lambda run: [])
