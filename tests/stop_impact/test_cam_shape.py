"""The cam for the shop (models/cam_shape.py): the pitch curve's radius of
curvature and pressure angle against hand formulas and an independent polygon computation, the
undercut named with its angle, the point table's chordal error, a tabulated law plugging in."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mechopt
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.cam_follower import law_values
from mechopt.models.cam_shape import (
    CamShape,
    check_undercut,
    chord_errors,
    flank,
    pitch,
    point_table,
    summarise,
    tabulated_law,
)
from mechopt.registry import find
from mechopt.solvers.stop_impact import cam_profile
from mechopt.solvers.stop_impact.cam_shape import shape_cam

LIFT = "stop-impact/lift-cam-profile"


def _translating(**more):
    given = dict(base_radius_mm=40.0, roller_radius_mm=10.0, stroke_mm=20.0, rise_deg=90.0, return_deg=90.0,
                 dwell_deg=30.0, law="harmonic")
    return CamShape(**(given | more))



def _lift_task(**more):
    return find(LIFT).build(more)[0]


def test_a_translating_followers_radius_of_curvature_is_the_hand_formula_on_a_harmonic_rise():
    cam = _translating()
    beta, h, rp = math.radians(90.0), 20.0, 50.0
    theta = np.linspace(0.01, beta - 0.01, 200)
    s = h / 2 * (1 - np.cos(np.pi * theta / beta))
    ds = h * np.pi / (2 * beta) * np.sin(np.pi * theta / beta)
    dds = h * np.pi**2 / (2 * beta**2) * np.cos(np.pi * theta / beta)
    r = rp + s
    hand = (r**2 + ds**2) ** 1.5 / (r**2 + 2 * ds**2 - r * dds)     # e = 0 (Norton, ch. 8)
    assert np.allclose(pitch(cam, theta).radius_mm, hand, rtol=1e-10)
    # on the dwells the pitch curve is a circle about the cam's centre
    assert np.allclose(pitch(cam, [math.radians(100), math.radians(300)]).radius_mm, [rp + h, rp], rtol=1e-10)


def test_a_translating_followers_pressure_angle_is_the_hand_formula_with_an_offset():
    cam = _translating(offset_mm=8.0, law="cycloidal")
    beta, h = math.radians(90.0), 20.0
    theta = np.linspace(0.0, beta, 101)
    S, dS, _ = law_values("cycloidal", theta / beta)
    s0 = math.sqrt(50.0**2 - 8.0**2)
    hand = np.arctan(np.abs(h * dS / beta - 8.0) / (s0 + h * S))     # tan phi = (s' - e) / (s0 + s)
    assert np.allclose(pitch(cam, theta).pressure_rad, hand, atol=1e-12)


@pytest.mark.parametrize("make", [_translating, _lift_task], ids=["translating", "oscillating"])
def test_the_pitch_curve_runs_clockwise_and_its_normal_points_away_from_the_centre(make):
    cam = make()
    p = pitch(cam, np.linspace(0, 2 * math.pi, 4000, endpoint=False))
    x, y = p.P
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) < 0
    assert np.all(np.sum(p.P * p.normal, axis=0) > 0)
    inner = flank(cam, p.theta)
    assert np.all(np.hypot(*inner) < np.hypot(*p.P))
    assert np.allclose(np.hypot(*(p.P - inner)), cam.roller_radius_mm)


def _lever_points(theta, *, d, a, b, H, Rb, Rr, rise, dwell, ret, law):
    """The lift's pitch points by hand from the lever's geometry and the law's S alone."""
    psi0 = math.acos((d * d + a * a - (Rb + Rr) ** 2) / (2 * a * d))
    th = np.mod(theta, 2 * math.pi)
    b1, dw, b2 = (math.radians(v) for v in (rise, dwell, ret))
    u = np.where(th <= b1, law_values(law, th / b1)[0], np.where(
        th <= b1 + dw, 1.0, np.where(th <= b1 + dw + b2, 1 - law_values(law, (th - b1 - dw) / b2)[0], 0.0)))
    psi = psi0 + H / (a + b) * u
    R = np.array([d - a * np.cos(psi), a * np.sin(psi)])
    c, s = np.cos(th), np.sin(th)
    return np.array([c * R[0] + s * R[1], -s * R[0] + c * R[1]]), psi


def _polygon_checks(cam, n=200_000):
    """Least convex and concave circumradius of consecutive point triples, and the largest angle
    between the lever's motion and the normal of central-difference chords."""
    theta = np.linspace(0, 2 * math.pi, n, endpoint=False)
    P, psi = _lever_points(theta, d=cam.centre_distance_mm, a=cam.a_mm, b=cam.b_mm, H=cam.stroke_mm,
                           Rb=cam.base_radius_mm, Rr=cam.roller_radius_mm, rise=cam.rise_deg,
                           dwell=cam.dwell_deg, ret=cam.return_deg, law=cam.law)
    A, C = np.roll(P, 1, axis=1), np.roll(P, -1, axis=1)
    ab, bc, ca = np.hypot(*(P - A)), np.hypot(*(C - P)), np.hypot(*(A - C))
    cross = (P - A)[0] * (C - A)[1] - (P - A)[1] * (C - A)[0]
    rho = -ab * bc * ca / (2 * cross)                 # the curve runs clockwise: convex > 0
    c, s = np.cos(theta), np.sin(theta)
    move = np.array([c * np.sin(psi) + s * np.cos(psi), -s * np.sin(psi) + c * np.cos(psi)])
    chord = (C - A) / np.hypot(*(C - A))
    phi = np.degrees(np.arctan2(np.abs(np.sum(move * chord, axis=0)),
                                np.abs(move[0] * chord[1] - move[1] * chord[0])))
    return rho[rho > 0].min(), (-rho[rho < 0]).min(), phi.max()


def test_the_lift_cams_checks_are_an_independent_polygon_computations():
    scene = find(LIFT)
    convex, concave, phi = _polygon_checks(scene.build()[0])
    expect = scene.spec.expect
    for name, got in (("min_radius_of_curvature_mm", convex), ("min_concave_radius_mm", concave),
                      ("max_pressure_angle_deg", phi)):
        assert got == pytest.approx(expect[name].value, rel=expect[name].rel), name
    run = mechopt.solve(LIFT)
    assert run.status is Status.SOLVED and all(c.ok for c in run.checks)


def test_the_lift_cams_geometry_is_cam_geometrys_roller_cam_one_implementation(monkeypatch):
    """cam_shape computes the roller centre; the pitch curve, normal, radii and both walls of the
    groove are models/cam_geometry's (one implementation): a call counted, and its signed pressure
    angle folded onto [0, 90] deg is cam_shape's unsigned one."""
    from mechopt.models import cam_geometry, cam_shape

    calls = []

    def counted(*args, **kwargs):
        calls.append(args[-1])                  # the sense
        return cam_geometry.roller_cam(*args, **kwargs)
    monkeypatch.setattr(cam_shape, "roller_cam", counted)
    cam = _lift_task()
    theta = np.linspace(0, 2 * math.pi, 3601)
    p = pitch(cam, theta)
    inner, outer = flank(cam, theta, "inner"), flank(cam, theta, "outer")
    assert calls == [1, 1, 1]                   # pitch, inner and outer wall; counter-clockwise
    R, dR, ddR, moving = cam_shape.roller_centre(cam, theta)
    c = cam_geometry.roller_cam(theta, R, dR, ddR, moving, cam.roller_radius_mm, 1)
    signed = np.abs(c.pressure_rad)
    assert np.max(np.abs(p.pressure_rad - np.minimum(signed, math.pi - signed))) < 1e-12
    assert np.array_equal(p.P, c.pitch) and np.array_equal(inner, c.profile)
    # the outer wall the roller's radius outside the pitch curve, the inner inside, along its normal
    assert np.max(np.abs(outer - p.P - cam.roller_radius_mm * p.normal)) < 1e-12
    assert np.max(np.abs(inner - p.P + cam.roller_radius_mm * p.normal)) < 1e-12


def test_a_roller_larger_than_the_least_radius_of_curvature_is_an_undercut_named_with_its_angle():
    cam = _lift_task(roller_radius_mm=30.0, base_radius_mm=45.0)      # the same pitch curve, a larger roller
    result = cam_profile(cam)
    assert result.status is Status.INFEASIBLE and result.violated == ("undercut",)
    assert "convex radius of curvature 25.39 mm at cam angle 26.988 deg (inner flank)" in result.message
    assert "profile_x_mm" not in result.arrays and "pitch_x_mm" in result.arrays
    assert result.values["undercut_margin_mm"] == pytest.approx(25.39498 - 30.0, abs=1e-4)
    with pytest.raises(ModelError, match=r"undercut: roller_radius_mm=30 >= the pitch curve's convex radius .* "
                                         r"at cam angle 2[67]\.\d+ deg"):
        flank(cam, np.linspace(0, 2 * math.pi, 7200))
    with pytest.raises(ModelError, match=r"at cam angle 26\.98\d deg \(inner flank\)"):
        check_undercut(cam, summarise(cam))


def test_a_grooves_outer_wall_is_undercut_where_the_pitch_curve_is_concave():
    # a steep rise on a small cam: concave radius below the roller, the convex side still clear
    cam = _translating(law="cycloidal", rise_deg=40.0, return_deg=120.0, base_radius_mm=25.0, roller_radius_mm=10.0,
                       closure="groove", max_pressure_angle_deg=60.0)
    s = summarise(cam)
    assert s.min_concave_radius_mm < 10.0 < s.min_convex_radius_mm
    result = cam_profile(cam)
    assert result.violated == ("undercut",) and "(outer flank)" in result.message


def test_a_pressure_angle_above_its_limit_is_infeasible_named_with_its_angle():
    result = cam_profile(_lift_task(base_radius_mm=50.0, roller_radius_mm=15.0, max_pressure_angle_deg=40.0))
    assert result.status is Status.INFEASIBLE and result.violated == ("pressure_angle",)
    assert "pressure angle 43.0" in result.message and "exceeds max_pressure_angle_deg=40" in result.message


@pytest.mark.parametrize("tol", [0.1, 0.01, 0.001])
def test_the_point_table_keeps_its_chordal_error_and_crowds_where_the_curve_bends(tol):
    cam = _lift_task()
    curve = lambda t: flank(cam, t)                     # noqa: E731
    table = point_table(curve, tol, breaks=cam.phase_ends_rad())
    assert table.chord_error_mm <= tol
    # measured again, four times as finely: the stated error holds to 1e-3 of itself
    assert chord_errors(curve, np.r_[table.t, 2 * math.pi], 256).max() <= table.chord_error_mm * (1 + 1e-3)
    steps = np.hypot(*np.diff(np.vstack([table.xy, table.xy[:1]]), axis=0).T)
    sharp = np.argmin(np.abs(table.t - math.radians(26.988)))
    assert steps[sharp] < 0.6 * np.median(steps)        # shorter chords where the radius is least


def test_the_number_of_points_grows_as_the_square_root_of_the_tolerance():
    cam = _lift_task()
    counts = [point_table(lambda t: flank(cam, t), tol).t.size for tol in (0.04, 0.01, 0.0025)]
    assert 1.6 < counts[1] / counts[0] < 2.4 and 1.6 < counts[2] / counts[1] < 2.4


def test_a_tabulated_law_gives_the_library_laws_cam():
    cam = _lift_task()
    xi = np.linspace(0, 1, 201)
    law = tabulated_law(xi, *law_values("cycloidal", xi))
    ours, library = shape_cam(cam, law), cam_profile(cam)
    for name in ("min_radius_of_curvature_mm", "min_concave_radius_mm", "max_pressure_angle_deg"):
        assert ours.values[name] == pytest.approx(library.values[name], rel=1e-6), name


def test_quintic_hermite_pieces_are_exact_at_the_nodes_and_on_a_quintic():
    xi = np.linspace(0, 1, 5)
    S = lambda x: 10 * x**3 - 15 * x**4 + 6 * x**5                   # noqa: E731
    dS = lambda x: 30 * x**2 - 60 * x**3 + 30 * x**4                # noqa: E731
    ddS = lambda x: 60 * x - 180 * x**2 + 120 * x**3                # noqa: E731
    law = tabulated_law(xi, S(xi), dS(xi), ddS(xi))
    x = np.linspace(0, 1, 333)
    for got, want in zip(law(x), (S(x), dS(x), ddS(x))):
        assert np.allclose(got, want, atol=1e-10)


@pytest.mark.parametrize("more, match", [
    (dict(offset_mm=60.0), r"offset_mm=60: must be below the prime radius"),
    (dict(rise_deg=200.0, return_deg=200.0), r"rise_deg \+ dwell_deg \+ return_deg = 430 deg: more than a turn"),
    (dict(law="parabolic"), r"law='parabolic': unknown motion law; allowed: cycloidal"),
    (dict(follower="oscillating"), r"centre_distance_mm=0: an oscillating follower needs it > 0"),
    (dict(follower="oscillating", centre_distance_mm=300.0, a_mm=80.0, b_mm=100.0),
     r"cannot reach the prime circle .* from centre_distance_mm=300"),
])
def test_an_impossible_cam_is_refused_by_name(more, match):
    with pytest.raises(ModelError, match=match):
        _translating(**more)


def test_a_bad_tabulated_law_is_refused_by_name():
    with pytest.raises(ModelError, match="nodes must increase from 0 to 1"):
        tabulated_law([0, 0.5, 0.4, 1], [0, 0.5, 0.4, 1], [1] * 4, [0] * 4)
    with pytest.raises(ModelError, match="needs >= 2 nodes and S, S', S'' at each"):
        tabulated_law([0, 1], [0, 1], [1], [0, 0])


@settings(max_examples=12, deadline=None)
@given(base=st.floats(30.0, 80.0), stroke=st.floats(2.0, 30.0), rise=st.floats(60.0, 150.0),
       law=st.sampled_from(["cycloidal", "modified_sine", "polynomial_345", "harmonic"]),
       tol=st.sampled_from([0.05, 0.01]))
def test_any_feasible_cams_flank_is_the_roller_away_from_its_pitch_and_its_table_keeps_the_tolerance(
        base, stroke, rise, law, tol):
    cam = _translating(base_radius_mm=base, stroke_mm=stroke, rise_deg=rise, return_deg=rise, dwell_deg=20.0,
                       law=law, roller_radius_mm=5.0, max_pressure_angle_deg=89.0)
    s = summarise(cam, samples=1440)
    if s.undercut_margin_mm <= 0:
        return
    table = point_table(lambda t: flank(cam, t), tol, breaks=cam.phase_ends_rad())
    assert table.chord_error_mm <= tol
    p = pitch(cam, table.t)
    assert np.allclose(np.hypot(*(p.P - table.xy.T)), 5.0)


def test_the_cam_is_drawn_with_its_curvature_and_an_undercut_one_without_a_profile():
    assert set(mechopt.solve(LIFT).figures()) == {"profile", "curvature"}
    undercut = mechopt.solve(LIFT, roller_radius_mm=30.0, base_radius_mm=45.0)
    labels = [line.get_label() for line in undercut.figures()["profile"].axes[0].lines]
    assert any(label.startswith("pitch curve") for label in labels)
    assert not any(label.startswith("cam profile") for label in labels)


def test_a_synthesised_laws_cam_is_checked_like_a_library_laws():
    """The shop's path for a synthesised law: the spline law of `synthesise_law` shapes
    the lift cam through `shape_cam`, and its least radii and largest pressure angle agree with the
    independent polygon computation on the same law's S alone. The radii to 1e-3: a cubic's S'''
    jumps at its knots, so the radius has a corner there (the least convex one sits on a knot at
    128.55 deg, slopes ~1200 mm/rad), which the polygon's triples round off by O(h) (6e-4 here,
    measured); the pressure angle, smooth, to 1e-5."""
    import dataclasses
    from types import SimpleNamespace

    from mechopt.solvers.stop_impact.synthesis import law_of, synthesise_law
    lever = find("stop-impact/amplitude-law").build()[0]
    run = synthesise_law(lever, objective="least_rebound", coefficients=24, band_low_rpm=280.0, sample_speeds=3,
                         max_acceleration_mm_per_rad2=570.0, verify=False, compare=False)
    assert run.status is Status.SOLVED
    law = law_of(run)
    cam = dataclasses.replace(_lift_task(), rise_deg=lever.t_deg, return_deg=lever.t_deg)
    ours = shape_cam(cam, lambda xi: law.values(xi)[:3])
    assert ours.status is Status.SOLVED
    convex, concave, phi = _polygon_checks(SimpleNamespace(**(dataclasses.asdict(cam) | {"law": law})))
    for name, got, rel in (("min_radius_of_curvature_mm", convex, 1e-3), ("min_concave_radius_mm", concave, 1e-3),
                           ("max_pressure_angle_deg", phi, 1e-5)):
        assert ours.values[name] == pytest.approx(got, rel=rel), name
    assert ours.values["min_radius_of_curvature_mm"] <= convex      # the polygon rounds the corner up
