"""A cam of the cam wing goes to the shop (`mechopt run --dxf`): its drawing re-read with ezdxf
has its layers, units mm, the rise-start mark where the roller centre stands as the rise begins
(by hand), curves within their chordal tolerance of the cam, and the lift cam's drawing agrees
with the one models/cam_shape.py makes."""
import math

import ezdxf
import numpy as np
import pytest

from mechopt import registry
from mechopt.dxf import NothingToExport, export_run, read_polylines
from mechopt.models.cam_shape import distance_to_segment


def rise_mark_deg(path):
    doc = ezdxf.readfile(str(path))
    assert doc.header["$INSUNITS"] == 4                                     # millimetres
    [mark] = [e for e in doc.modelspace() if e.dxftype() == "LINE" and e.dxf.layer == "REFERENCE" and e.dxf.color == 1]
    (x0, y0, _), (x1, y1, _) = mark.dxf.start, mark.dxf.end
    return {e.dxf.layer for e in doc.modelspace()}, math.degrees(math.atan2(y1 - y0, x1 - x0))


def test_the_lift_cams_drawing_re_read_matches_the_other_models(tmp_path):
    run = registry.run("cam/lift-cam-groove")
    [(path, _), *_] = export_run(run, tmp_path)
    layers, mark = rise_mark_deg(path)
    assert layers == {"PITCH_CURVE", "CAM_PROFILE", "CAM_GROOVE_OUTER", "CENTRE", "REFERENCE"}
    d, a, rp = 120.0, 80.0, 75.0                                             # the roller at rest, by hand
    psi0 = math.acos((d * d + a * a - rp * rp) / (2 * a * d))
    assert mark == pytest.approx(math.degrees(math.atan2(a * math.sin(psi0), d - a * math.cos(psi0))), abs=1e-6)
    other = registry.run("stop-impact/lift-cam-profile")
    [(other_path, _), *_] = export_run(other, tmp_path / "other")
    assert rise_mark_deg(other_path)[1] == pytest.approx(mark, abs=1e-6)
    # each vertex of one model's profile lies on the other's polyline: the same point-table rule on
    # the profiles of two models whose roller centres are written apart (1e-10 mm measured)
    mine, theirs = read_polylines(path)["CAM_PROFILE"], read_polylines(other_path)["CAM_PROFILE"]
    A, B = theirs.T[:, None, :], np.roll(theirs, -1, axis=0).T[:, None, :]
    gap = np.min(distance_to_segment(mine.T[:, :, None], A, B), axis=1)
    assert gap.max() < 1e-6


def test_a_translating_roller_goes_to_the_shop_with_its_mark_on_the_stem(tmp_path):
    run = registry.run("cam/translating-roller", {"bore_diameter_mm": 20.0})
    [(path, _), *_] = export_run(run, tmp_path)
    layers, mark = rise_mark_deg(path)
    assert layers == {"PITCH_CURVE", "CAM_PROFILE", "CENTRE", "REFERENCE"}
    assert mark == pytest.approx(math.degrees(math.atan2(math.sqrt(52.5**2 - 8.0**2), 8.0)), abs=1e-6)
    profile = read_polylines(path)["CAM_PROFILE"]
    c = run.task.curves(np.radians(run.arrays["profile_cam_angle_deg"]))
    assert np.max(np.hypot(*(profile.T - c.profile))) < 1e-9                # the vertices are on the profile
    assert run.result.diagnostics["chord_error_mm"]["profile"] <= 0.01


def test_a_cam_without_a_bore_or_not_solved_is_not_drawn(tmp_path):
    with pytest.raises(NothingToExport, match="bore_diameter_mm not stated"):
        export_run(registry.run("cam/translating-roller"), tmp_path)
    steep = registry.run("cam/translating-roller", {"base_radius_mm": 5.0, "bore_diameter_mm": 5.0})
    with pytest.raises(NothingToExport, match="INFEASIBLE"):
        export_run(steep, tmp_path)


@pytest.mark.parametrize(("scene", "more"), [("cam/translating-roller", []),
                                              ("stop-impact/lift-cam-profile", ["--set", "bore_diameter_mm=0"])])
def test_dxf_of_a_cam_without_a_bore_is_refused_before_the_solve(scene, more, tmp_path, capsys, monkeypatch):
    """The bore is a parameter of the posed task: `--dxf` reads it there (the scene's file, its
    derived values, the --set) and refuses before any solver of the scene runs; a derived scene's
    sources are still solved to pose it (loom/group1 for the lift cam's phase)."""
    from mechopt import cli
    from mechopt.solvers.cam import size_cam
    from mechopt.solvers.stop_impact import cam_profile
    solve = registry._solve

    def no_cam_solve(solver, task, settings):
        assert solver not in (size_cam, cam_profile), "the cam was solved before --dxf refused it"
        return solve(solver, task, settings)
    monkeypatch.setattr(registry, "_solve", no_cam_solve)
    monkeypatch.setattr(registry, "run", lambda *a, **k: pytest.fail("solved before refusing --dxf"))
    assert cli.main(["run", scene, "--dxf", str(tmp_path), *more]) == 1
    err = capsys.readouterr().err
    assert f"{scene}: bore_diameter_mm not stated (0)" in err and "nothing was solved" in err
    assert not list(tmp_path.iterdir())
