"""A cam as a sequence of segments (models/cam_motion.py): the follower's motion against an
independent closed form, the peaks per segment against a dense sampling, the joins' steps named
with their segments, angle and size, the hard cases (angles not adding to a turn, lifts not
returning, bad rows), and the segments read from a scene's TOML or CSV."""
import math
import textwrap

import numpy as np
import pytest

from mechopt import ModelError, SceneError, laws
from mechopt.models.cam_motion import CamMotion, Segment

H = 10.0                    # mm
RISE_DEG, TOP_DEG, RETURN_DEG, BOTTOM_DEG = 90.0, 60.0, 120.0, 90.0


def rows(rise="cycloidal", fall="cycloidal", h=H, angles=(RISE_DEG, TOP_DEG, RETURN_DEG, BOTTOM_DEG)):
    return [dict(segment="rise", law=rise, angle_deg=angles[0], lift_mm=h),
            dict(segment="dwell", angle_deg=angles[1], lift_mm=0.0),
            dict(segment="return", law=fall, angle_deg=angles[2], lift_mm=-h),
            dict(segment="dwell", angle_deg=angles[3], lift_mm=0.0)]


def cycloidal_cam(theta):
    """s, s', s'', s''' of the rise-dwell-return-dwell cycloidal cam written out by hand
    (independent of the library): s = h (x - sin(2 pi x) / (2 pi)) on the rise, h minus that on the return."""
    theta = np.mod(theta, 2 * math.pi)
    b1, top, b2 = (math.radians(v) for v in (RISE_DEG, TOP_DEG, RETURN_DEG))
    out = [np.zeros_like(theta) for _ in range(4)]
    for start, beta, sign, base in ((0.0, b1, 1.0, 0.0), (b1 + top, b2, -1.0, H)):
        on = (theta >= start) & (theta < start + beta)
        x = (theta[on] - start) / beta
        w = 2 * math.pi
        out[0][on] = base + sign * H * (x - np.sin(w * x) / w)
        out[1][on] = sign * H * (1 - np.cos(w * x)) / beta
        out[2][on] = sign * H * w * np.sin(w * x) / beta**2
        out[3][on] = sign * H * w**2 * np.cos(w * x) / beta**3
    out[0][(theta >= b1) & (theta < b1 + top)] = H
    return out


def test_the_motion_is_the_closed_form_over_the_turn():
    cam = CamMotion(rows())
    theta = np.linspace(-1.0, 2 * math.pi + 1.0, 5001)          # beyond a turn: taken modulo 2 pi
    for got, want in zip(cam.at(theta), cycloidal_cam(theta)):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
    assert cam.steps() == [] and cam.warnings({}) == []
    assert [seg.start_deg for seg in cam.segments] == [0.0, 90.0, 150.0, 270.0]
    assert [seg.start_mm for seg in cam.segments] == [0.0, H, H, 0.0]


def test_the_derivatives_are_the_finite_differences_of_the_motion():
    cam = CamMotion(rows(rise="modified_sine", fall="polynomial_345"))
    theta, h = np.linspace(0.01, 2 * math.pi - 0.01, 997), 1e-6
    up, down, here = cam.at(theta + h), cam.at(theta - h), cam.at(theta)
    for k in (1, 2, 3):
        np.testing.assert_allclose((up[k - 1] - down[k - 1]) / (2 * h), here[k],
                                   atol=1e-5 * max(1.0, float(np.abs(here[k]).max())))


def test_the_peaks_per_segment_are_the_sampled_peaks_in_mm_per_rad():
    cam = CamMotion(rows(rise="modified_trapezoid", fall="harmonic"))
    theta = np.linspace(0, 2 * math.pi, 720_001)
    s = cam.at(theta)
    peaks = cam.segment_peaks()
    assert [p["law"] for p in peaks] == ["modified_trapezoid", "", "harmonic", ""]
    for p, (lo, hi) in zip(peaks, [(0, 90), (90, 150), (150, 270), (270, 360)]):
        on = (theta >= math.radians(lo)) & (theta < math.radians(hi))
        for k, key in ((1, "velocity_mm_per_rad"), (2, "acceleration_mm_per_rad2"), (3, "jerk_mm_per_rad3")):
            assert p[key] == pytest.approx(float(np.abs(s[k][on]).max()) if on.any() else 0.0, rel=1e-6, abs=1e-12)
    # the harmonic return: |h| pi / (2 beta) [mm/rad], the cam's largest velocity
    assert peaks[2]["velocity_mm_per_rad"] == pytest.approx(H * math.pi / 2 / math.radians(RETURN_DEG), rel=1e-12)
    whole = cam.peaks()
    assert whole["velocity_mm_per_rad"] == pytest.approx(2 * H / math.radians(RISE_DEG))    # the rise's, Cv = 2
    assert whole["jerk_mm_per_rad3"] == math.inf            # the harmonic's acceleration steps at its ends


# -- joins ------------------------------------------------------------------------------------------

def test_a_harmonic_cycloidal_join_names_its_acceleration_jump():
    """Harmonic rise (10 mm over 90 deg) straight into a cycloidal return: at 90 deg the harmonic
    ends at s'' = -h (pi^2 / 2) / beta^2 = -20 mm/rad^2 exactly (beta = pi / 2), the cycloid starts
    at 0: a step of +20 mm/rad^2, an infinite jerk. The dwell before the rise sees the harmonic
    start at +20."""
    cam = CamMotion([dict(segment="rise", law="harmonic", angle_deg=90, lift_mm=H),
                     dict(segment="return", law="cycloidal", angle_deg=90, lift_mm=-H),
                     dict(segment="dwell", angle_deg=180, lift_mm=0)])
    steps = {(j.before, j.after): j for j in cam.steps()}
    assert set(steps) == {(3, 1), (1, 2)}
    join = steps[(1, 2)]
    assert (join.order, join.angle_deg) == (2, 90.0)
    assert join.jump == pytest.approx(20.0, rel=1e-12)
    assert str(join) == ("acceleration jump of +20 mm/rad^2 at cam angle 90 deg between segment 1 (rise, harmonic) "
                         "and segment 2 (return, cycloidal): an infinite jerk there")
    assert steps[(3, 1)].jump == pytest.approx(20.0) and steps[(3, 1)].angle_deg == 0.0
    assert sorted(cam.warnings({})) == sorted(map(str, cam.steps()))
    # the same jump from the motion itself, either side of the join
    eps = 1e-9
    before, after = (cam.at(math.radians(90) + d)[2][0] for d in (-eps, eps))
    assert after - before == pytest.approx(20.0, rel=1e-6)


def test_joins_refuse_makes_a_step_an_error():
    with pytest.raises(ModelError, match=r"joins='refuse': acceleration jump .*; acceleration jump of \+20 mm/rad\^2 "
                                         r"at cam angle 90 deg between segment 1 \(rise, harmonic\) and segment 2") as err:
        CamMotion([dict(segment="rise", law="harmonic", angle_deg=90, lift_mm=H),
                   dict(segment="return", law="cycloidal", angle_deg=90, lift_mm=-H),
                   dict(segment="dwell", angle_deg=180, lift_mm=0)], joins="refuse")
    assert err.value.key == "joins"
    CamMotion(rows(), joins="refuse")              # a cycloidal cam has none


def test_a_velocity_step_is_an_infinite_acceleration():
    """A constant-velocity rise (S = xi, a degree-1 polynomial) from a dwell: s' steps by h / beta."""
    line = laws.polynomial([(0, 0, 0), (1, 0, 1)], name="constant_velocity")
    cam = CamMotion([Segment("rise", line, 180.0, H), dict(segment="return", law="cycloidal", angle_deg=180,
                                                           lift_mm=-H)])
    velocity = [j for j in cam.steps() if j.order == 1]
    assert [(j.before, j.after, j.angle_deg) for j in velocity] == [(2, 1, 0.0), (1, 2, 180.0)]
    assert velocity[0].jump == pytest.approx(H / math.pi)
    assert "velocity jump of +3.1831 mm/rad at cam angle 0 deg" in str(velocity[0])
    assert str(velocity[0]).endswith("an infinite acceleration there")
    assert cam.peaks()["acceleration_mm_per_rad2"] == math.inf


# -- hard cases -------------------------------------------------------------------------------------

def test_angles_not_adding_to_a_turn_are_refused_with_their_sum():
    with pytest.raises(ModelError, match=r"segments=90 \+ 60 \+ 120 \+ 80 deg: the angles add to 350 deg; "
                                         r"allowed: a full turn, 360 deg") as err:
        CamMotion(rows(angles=(90, 60, 120, 80)))
    assert err.value.key == "segments"


def test_a_follower_that_does_not_return_is_refused_with_the_lifts_sum():
    bad = rows()
    bad[2]["lift_mm"] = -8.0
    with pytest.raises(ModelError, match=r"the lifts add to 2 mm; allowed: 0 \(the follower returns to its start\)"):
        CamMotion(bad)


@pytest.mark.parametrize(("change", "match"), [
    ({"segment": "fall"}, r"segments\[2\]\.segment='fall': allowed rise, dwell, return"),
    ({"lift_mm": 10.0}, r"segments\[2\]\.lift_mm=10.0: allowed < 0 \(a return falls\) for a return"),
    ({"law": "parabolic"}, r"segments\[2\]\.law='parabolic': unknown motion law; allowed: cycloidal"),
    ({"angle_deg": -120.0}, r"segments\[2\]\.angle_deg=-120.0: allowed > 0 and <= 360"),
    ({"angle_deg": math.inf}, r"segments\[2\]\.angle_deg=inf: expected a finite number"),
    ({"speed": 3}, r"segments\[2\]=.*unknown key\(s\) speed; allowed: segment, law, angle_deg, lift_mm"),
])
def test_a_bad_row_is_refused_by_its_key(change, match):
    bad = rows()
    bad[2] = bad[2] | change
    with pytest.raises(ModelError, match=match):
        CamMotion(bad)


def test_a_dwell_with_a_law_and_an_empty_cam_are_refused():
    bad = rows()
    bad[1]["law"] = "cycloidal"
    with pytest.raises(ModelError, match=r"segments\[1\]\.law='cycloidal': a dwell has no law"):
        CamMotion(bad)
    with pytest.raises(ModelError, match="segments=\\(\\): expected a list of 1 to"):
        CamMotion(())


# -- read from a scene ------------------------------------------------------------------------------
# The cam's own solvers build on this model elsewhere; any solver lets the scene layer build the task
# (the segments are read and checked when the scene loads).

SCENE = """\
id = "cam/segments-test"
title = "segments read from a scene"
source = "a test"
task = "cam_motion.CamMotion"
solver = "loom.plan_cyclogram"
"""


def _load(tmp_path, body, csv=None):
    from mechopt.scene import load
    if csv is not None:
        (tmp_path / "segments.csv").write_text(textwrap.dedent(csv))
    path = tmp_path / "cam.toml"
    path.write_text(SCENE + textwrap.dedent(body))
    return load(path)


def test_segments_from_a_toml_list_of_tables(tmp_path):
    body = "".join("\n[[structure.segments]]\n" + "".join(f"{k} = {v!r}\n".replace("'", '"') for k, v in r.items())
                   for r in rows())
    cam = _load(tmp_path, body).build()[0]
    np.testing.assert_allclose(np.c_[cam.at(np.linspace(0, 6.2, 50))],
                               np.c_[CamMotion(rows()).at(np.linspace(0, 6.2, 50))], rtol=0, atol=0)


def test_segments_from_a_csv_beside_the_scene(tmp_path):
    csv = """\
        segment,law,angle_deg,lift_mm,why
        rise,cycloidal,90,10,a test
        dwell,,60,0,
        return,cycloidal,120,-10,
        dwell,,90,0,
        """
    body = '[structure]\nsegments = { csv = "segments.csv", columns = ["segment", "law", "angle_deg", "lift_mm"] }\n'
    cam = _load(tmp_path, body, csv).build()[0]
    theta = np.linspace(0, 2 * math.pi, 361)
    for got, want in zip(cam.at(theta), cycloidal_cam(theta)):
        np.testing.assert_allclose(got, want, atol=1e-9)


def test_a_scene_whose_angles_miss_a_turn_names_its_file_and_key(tmp_path):
    csv = """\
        segment,law,angle_deg,lift_mm
        rise,cycloidal,90,10
        return,cycloidal,120,-10
        dwell,,140,0
        """
    body = '[structure]\nsegments = { csv = "segments.csv", columns = ["segment", "angle_deg", "lift_mm"] }\n'
    with pytest.raises(SceneError, match=r"cam\.toml: structure\.segments=90 \+ 120 \+ 140 deg: the angles add to "
                                         r"350 deg; allowed: a full turn, 360 deg"):
        _load(tmp_path, body, csv)
    with pytest.raises(SceneError, match=r"structure\.segments\[1\]\.lift_mm=10.0: allowed < 0"):
        _load(tmp_path, body, csv.replace("return,cycloidal,120,-10", "return,cycloidal,120,10"))


def test_partial_rises_and_returns_stack_their_lifts():
    """Rise 4 mm, hold, rise 6 mm more, hold, return 10 mm in two parts: each segment starts where
    the one before left the follower, and the motion is each law scaled to its part."""
    cam = CamMotion([dict(segment="rise", law="polynomial_345", angle_deg=60, lift_mm=4),
                     dict(segment="dwell", angle_deg=30, lift_mm=0),
                     dict(segment="rise", law="cycloidal", angle_deg=60, lift_mm=6),
                     dict(segment="dwell", angle_deg=60, lift_mm=0),
                     dict(segment="return", law="modified_sine", angle_deg=90, lift_mm=-7),
                     dict(segment="return", law="polynomial_4567", angle_deg=60, lift_mm=-3)])
    assert [seg.start_mm for seg in cam.segments] == [0, 4, 4, 10, 10, 3]
    assert [seg.start_deg for seg in cam.segments] == [0, 60, 90, 150, 210, 300]
    x = 0.3                                                 # 30 % into the second rise
    s, ds, dds, _ = (v[0] for v in cam.at(math.radians(90 + 0.3 * 60)))
    beta = math.radians(60)
    assert s == pytest.approx(4 + 6 * (x - math.sin(2 * math.pi * x) / (2 * math.pi)), abs=1e-12)
    assert ds == pytest.approx(6 * (1 - math.cos(2 * math.pi * x)) / beta, abs=1e-12)
    assert dds == pytest.approx(6 * 2 * math.pi * math.sin(2 * math.pi * x) / beta**2, abs=1e-11)
    assert cam.steps() == []


def test_the_motion_in_time_is_the_angle_derivatives_times_omega_powers():
    cam = CamMotion(rows())
    theta = np.linspace(0, 2 * math.pi, 73)
    omega = 2 * math.pi * 300 / 60
    for k, (timed, angular) in enumerate(zip(cam.in_time(theta, 300.0), cam.at(theta))):
        np.testing.assert_allclose(timed, angular * omega**k, rtol=1e-15)
    with pytest.raises(ModelError, match=r"speed_rpm=0: allowed > 0"):
        cam.in_time(theta, 0)


def test_a_synthesised_law_is_a_segments_law_by_its_numbers():
    """A synthesised spline law (models/cam_law.py) drives a rise as a library law does: the
    motion is its own values scaled, its knots are where the peaks' search looks."""
    from mechopt.models.cam_law import SplineBasis
    spline = SplineBasis(8).law(np.linspace(0.1, 0.9, 5))
    cam = CamMotion([dict(segment="rise", law=spline, angle_deg=120, lift_mm=5.0),
                     dict(segment="dwell", angle_deg=60, lift_mm=0),
                     dict(segment="return", law="cycloidal", angle_deg=120, lift_mm=-5.0),
                     dict(segment="dwell", angle_deg=60, lift_mm=0)])
    x = np.linspace(0, 1, 101, endpoint=False)
    beta = math.radians(120)
    for k, (got, want) in enumerate(zip(cam.at(x * beta), spline.values(x))):
        np.testing.assert_allclose(got, 5.0 * want / beta**k, atol=1e-12)
    assert cam.segments[0].law.breaks == (0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875)
    assert cam.steps() == []                               # a C2 spline from rest to rest
    import casadi as ca
    with pytest.raises(ModelError, match="known by its numbers only, it has no CasADi form"):
        cam.segments[0].law.expression(ca.SX.sym("x"))


def test_a_segment_given_as_an_object_is_held_to_the_tables_rules():
    with pytest.raises(ModelError, match=r"segments\[0\]\.lift_mm=-10.0: allowed > 0 for a rise"):
        CamMotion([Segment("rise", laws.law("cycloidal"), 180.0, -10.0),
                   dict(segment="return", law="cycloidal", angle_deg=180, lift_mm=10.0)])
