"""A cam's drawing for the shop (`mechopt.cam_sheet`), re-read with ezdxf: its layers, units mm,
the bore circle at the centre with the stated diameter, the rise-start mark at the angle the
lever's geometry gives (by hand, law of cosines), the shaft-zero mark turned back by the loom's
cyclogram event, the sense of rotation; and the synthesised law's cam, whose rise read back from
the drawing's vertices alone is the synthesised law."""
import dataclasses
import math
import re

import ezdxf
import numpy as np
import pytest

import mechopt
from mechopt import dxf
from mechopt.cam_sheet import Phase, Table, cam_sheet
from mechopt.cli import main
from mechopt.kit.errors import ModelError
from mechopt.solvers.stop_impact import law_of, synthesise_law

LIFT = "stop-impact/lift-cam-profile"
LAYERS = {"PITCH_CURVE", "CAM_PROFILE", "CAM_GROOVE_OUTER", "CENTRE", "REFERENCE"}
# a cheap variant of stop-impact/law-synthesis (one speed, few coefficients, no library laws beside it)
CHEAP_SYNTHESIS = dict(objective="least_rebound", coefficients=10, band_low_rpm=420.0, sample_speeds=1, compare=False)


@pytest.fixture(scope="module")
def lift():
    return mechopt.solve(LIFT)


@pytest.fixture(scope="module")
def synthesised():
    return mechopt.solve("stop-impact/law-synthesis", **CHEAP_SYNTHESIS)


def _read(path):
    doc = ezdxf.readfile(str(path))
    return doc, list(doc.modelspace())


def _angle_deg(line):
    (x0, y0, _), (x1, y1, _) = line.dxf.start, line.dxf.end
    return math.degrees(math.atan2(y1 - y0, x1 - x0))


def _stated(texts, label):
    [deg] = [float(m[1]) for t in texts if (m := re.match(rf"{label} at (-?[0-9.]+) deg", t))]
    return deg


def _rest_direction_deg(task):
    """The roller centre's direction from the cam's centre at rest, by hand: the lever's pivot A at
    (d, 0), the roller at a from A with |R| = base + roller radius (law of cosines)."""
    d, a, rp = task.centre_distance_mm, task.a_mm, task.base_radius_mm + task.roller_radius_mm
    psi0 = math.acos((d * d + a * a - rp * rp) / (2 * a * d))
    return math.degrees(math.atan2(a * math.sin(psi0), d - a * math.cos(psi0)))


def test_the_lift_cams_drawing_re_read_has_its_layers_bore_marks_and_units(lift, tmp_path):
    [(path, _), *_] = dxf.export_run(lift, tmp_path)
    doc, entities = _read(path)
    assert doc.header["$INSUNITS"] == 4 and LAYERS <= {layer.dxf.name for layer in doc.layers}
    texts = [e.dxf.text for e in entities if e.dxftype() == "TEXT"]
    assert "UNITS: mm" in texts
    [bore] = [e for e in entities if e.dxftype() == "CIRCLE" and e.dxf.layer == "CENTRE"]
    assert tuple(bore.dxf.center)[:2] == (0.0, 0.0) and 2 * bore.dxf.radius == pytest.approx(30.0, abs=1e-12)
    assert 2 * bore.dxf.radius == lift.task.bore_diameter_mm
    cross = [e for e in entities if e.dxftype() == "LINE" and e.dxf.layer == "CENTRE"]
    assert sorted(round(_angle_deg(e) % 180, 9) for e in cross) == [0.0, 90.0]
    marks = {e.dxf.color: e for e in entities if e.dxftype() == "LINE" and e.dxf.layer == "REFERENCE"
             and e.dxf.color in (1, 5)}
    rise, zero = marks[1], marks[5]
    expected = _rest_direction_deg(lift.task)                    # 40.80 deg for the lift's lever
    assert _angle_deg(rise) == pytest.approx(expected, abs=1e-6)
    assert _stated(texts, "RISE START MARK") == pytest.approx(expected, abs=1e-6)
    for mark in (rise, zero):                                    # radial: from the bore out past the cam
        (x0, y0, _), (x1, y1, _) = mark.dxf.start, mark.dxf.end
        assert math.hypot(x0, y0) == pytest.approx(bore.dxf.radius, rel=1e-12)
        assert abs(x0 * y1 - y0 * x1) < 1e-9 * math.hypot(x0, y0) * math.hypot(x1, y1)
    # the rise begins at the loom's event 3, solved here from the cyclogram's own scene
    event_3 = mechopt.solve("loom/group1").values["p_3_deg"]
    assert event_3 == pytest.approx(20.0, abs=1e-9)
    assert _angle_deg(zero) == pytest.approx(expected + event_3, abs=1e-6)      # the cam turns ccw
    assert _stated(texts, "SHAFT ZERO MARK") == pytest.approx(expected + event_3, abs=1e-6)
    assert any("loom/group1:p_3_deg" in t for t in texts) and any("COUNTER-CLOCKWISE" in t for t in texts)
    [arc] = [e for e in entities if e.dxftype() == "ARC" and e.dxf.layer == "REFERENCE"]
    barbs = [e for e in entities if e.dxftype() == "LINE" and e.dxf.layer == "REFERENCE" and e.dxf.color == 3]
    tip = {tuple(np.round(np.array(e.dxf.start)[:2], 9)) for e in barbs}
    end = math.radians(arc.dxf.end_angle)                        # ccw: the arrow at the arc's ccw end
    assert tip == {tuple(np.round(arc.dxf.radius * np.array([math.cos(end), math.sin(end)]), 9))}


def _ring(r, n=90):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return Table(np.column_stack([r * np.cos(a), r * np.sin(a)]), 0.0)


def test_a_cam_turning_clockwise_has_its_arrow_and_shaft_zero_the_other_way():
    items = cam_sheet(_ring(50.0), _ring(40.0), bore_diameter_mm=20.0, rise_start_deg=90.0, sense="cw",
                      phase=Phase(30.0, "a test's cyclogram"))
    lines = {i.colour: i for i in items if isinstance(i, dxf.ShopLine) and i.layer == "REFERENCE"}
    zero = np.subtract(lines[5].end, lines[5].start)
    assert math.degrees(math.atan2(zero[1], zero[0])) == pytest.approx(60.0, abs=1e-9)
    [arc] = [i for i in items if isinstance(i, dxf.ShopArc)]
    start = math.radians(arc.start_deg)
    assert np.allclose(lines[3].start, arc.radius_mm * np.array([math.cos(start), math.sin(start)]))
    assert any("CLOCKWISE (cw)" in i.text for i in items if isinstance(i, dxf.ShopText))


@pytest.mark.parametrize(("change", "says"), [
    (dict(bore_diameter_mm=80.0), "bore_diameter_mm=80: allowed: 0 < d < 80"),
    (dict(sense="up"), "sense='up': allowed: ccw, cw"),
    (dict(rise_start_deg=math.nan), "rise_start_deg=nan: allowed: a finite angle"),
])
def test_a_cam_sheet_with_bad_input_names_the_key_and_the_allowed_range(change, says):
    given = dict(bore_diameter_mm=20.0, rise_start_deg=90.0, sense="ccw") | change
    with pytest.raises(ModelError, match=re.escape(says)):
        cam_sheet(_ring(50.0), _ring(40.0), **given)


def _law_read_back(xy, task, t_deg):
    """S(xi) over the rise from the drawing's pitch vertices alone: |P| gives the lever's angle psi
    (law of cosines), the polar angle of R(psi) less that of P the cam angle theta."""
    d, a = task.centre_distance_mm, task.a_mm
    rp = task.base_radius_mm + task.roller_radius_mm
    psi0 = math.acos((d * d + a * a - rp * rp) / (2 * a * d))
    swing = task.stroke_mm / (task.a_mm + task.b_mm)
    r2 = np.sum(xy**2, axis=1)
    psi = np.arccos(np.clip((d * d + a * a - r2) / (2 * a * d), -1, 1))
    theta = np.mod(np.arctan2(a * np.sin(psi), d - a * np.cos(psi)) - np.arctan2(xy[:, 1], xy[:, 0]), 2 * np.pi)
    rise = theta < math.radians(t_deg) * (1 - 1e-9)
    return theta[rise] / math.radians(t_deg), (psi[rise] - psi0) / swing


def test_the_synthesised_laws_cam_read_back_from_its_drawing_is_that_law(synthesised, tmp_path):
    assert synthesised.status.value == "SOLVED"
    [(path, _), *_] = dxf.export_run(synthesised, tmp_path)
    doc, entities = _read(path)
    assert doc.header["$INSUNITS"] == 4 and LAYERS <= {layer.dxf.name for layer in doc.layers}
    lift = mechopt.solve(LIFT).task
    task = dataclasses.replace(lift, stroke_mm=synthesised.task.stroke_mm, a_mm=synthesised.task.a_mm,
                               b_mm=synthesised.task.b_mm)
    xi, S = _law_read_back(dxf.read_polylines(path)["PITCH_CURVE"], task, synthesised.values["t_deg"])
    assert xi.size > 20
    assert S == pytest.approx(law_of(synthesised.result).values(xi)[0], abs=1e-9)
    texts = [e.dxf.text for e in entities if e.dxftype() == "TEXT"]
    assert _stated(texts, "RISE START MARK") == pytest.approx(_rest_direction_deg(task), abs=1e-6)
    assert any(f"t = {synthesised.values['t_deg']:.6g} deg" in t for t in texts)


def test_the_lift_cams_drawing_read_back_is_the_cycloid(lift, tmp_path):
    [(path, _), *_] = dxf.export_run(lift, tmp_path)
    xi, S = _law_read_back(dxf.read_polylines(path)["PITCH_CURVE"], lift.task, lift.task.rise_deg)
    assert xi.size > 20 and S == pytest.approx(xi - np.sin(2 * np.pi * xi) / (2 * np.pi), abs=1e-9)


def test_the_synthesised_laws_have_shop_drawings():
    from mechopt.solvers.loom import codesign_machine_speed
    assert dxf.SHOP_DRAWINGS[synthesise_law].__name__ == "synthesised_cam"
    assert dxf.SHOP_DRAWINGS[codesign_machine_speed].__name__ == "codesigned_cam"


def test_a_scene_whose_solver_has_no_drawing_is_refused_before_the_solve(tmp_path, capsys, monkeypatch):
    from mechopt import registry
    monkeypatch.setattr(registry, "run", lambda *a, **k: pytest.fail("solved before refusing --dxf"))
    assert main(["run", "stop-impact/rebound-280-420", "--dxf", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "nothing to export as DXF (task LeverStop)" in err and "nothing was solved" in err
    assert not list(tmp_path.iterdir())


def test_a_cam_without_a_stated_bore_is_not_drawn(tmp_path):
    run = mechopt.solve(LIFT, bore_diameter_mm=0.0)
    with pytest.raises(dxf.NothingToExport, match=r"bore_diameter_mm not stated \(0\)"):
        dxf.export_run(run, tmp_path)
    assert not list(tmp_path.iterdir())


@pytest.fixture(scope="module")
def codesigned():
    """A coarse co-design (tests/loom/test_codesign.py's settings)."""
    return mechopt.solve("loom/machine-speed-codesign", coefficients=8, sample_speeds=2, phase_from_deg=30.0,
                         phase_to_deg=42.0, phase_tol_deg=1.0)


@pytest.mark.parametrize(("which", "t_name"), [("synthesised", "t_deg"), ("codesigned", "t_3_7_deg")])
def test_the_drawing_from_the_solvers_arrays_is_the_lift_cam_cut_to_its_law_as_before(which, t_name, tmp_path,
                                                                                      request):
    """The writers draw the cam the solver returned (arrays cam_...), no longer re-cutting it: its
    polylines re-read with ezdxf are the lift cam of stop-impact/lift-cam-profile (its task as
    posed, the lever's arms and stroke, rise and return over t) cut to the law by shape_cam, as
    the writers made them before, to 1e-9 mm, vertex for vertex."""
    from mechopt.solvers.stop_impact import shape_cam
    run = request.getfixturevalue(which)
    assert run.status.value == "SOLVED" and "cam_pitch_x_mm" in run.arrays
    [(path, _), *_] = dxf.export_run(run, tmp_path)
    drawn = dxf.read_polylines(path)
    lever = run.task if which == "synthesised" else run.task.lever_model
    t_deg, law = run.values[t_name], law_of(run.result)
    shape = dataclasses.replace(mechopt.solve(LIFT).task, stroke_mm=lever.stroke_mm, a_mm=lever.a_mm,
                                b_mm=lever.b_mm, rise_deg=t_deg, return_deg=t_deg)
    before = shape_cam(shape, lambda xi: tuple(law.values(xi)[:3]))
    assert set(drawn) == {"PITCH_CURVE", "CAM_PROFILE", "CAM_GROOVE_OUTER"}
    for layer, name in (("PITCH_CURVE", "pitch"), ("CAM_PROFILE", "profile"), ("CAM_GROOVE_OUTER", "groove_outer")):
        xy = np.column_stack([before.arrays[f"{name}_x_mm"], before.arrays[f"{name}_y_mm"]])
        assert drawn[layer].shape == xy.shape and np.max(np.abs(drawn[layer] - xy)) < 1e-9


def test_the_codesigned_machines_lift_cam_is_placed_by_its_own_re_planned_cyclogram(codesigned, tmp_path):
    """The shaft-zero mark is turned back from the rise-start mark by the re-planned event 3, and
    the rise read back is its law."""
    run = codesigned
    assert run.status.value == "SOLVED"
    [(path, _), *_] = dxf.export_run(run, tmp_path)
    _, entities = _read(path)
    lever, t_deg = run.task.lever_model, run.values["t_3_7_deg"]
    task = dataclasses.replace(mechopt.solve(LIFT).task, stroke_mm=lever.stroke_mm, a_mm=lever.a_mm, b_mm=lever.b_mm)
    [zero] = [e for e in entities if e.dxftype() == "LINE" and e.dxf.layer == "REFERENCE" and e.dxf.color == 5]
    assert _angle_deg(zero) == pytest.approx(_rest_direction_deg(task) + run.values["p_3_deg"], abs=1e-6)
    texts = [e.dxf.text for e in entities if e.dxftype() == "TEXT"]
    assert any("re-planned cyclogram, event 3: lift leaves the lower stop" in t for t in texts)
    xi, S = _law_read_back(dxf.read_polylines(path)["PITCH_CURVE"], task, t_deg)
    assert xi.size > 20 and S == pytest.approx(law_of(run.result).values(xi)[0], abs=1e-9)
