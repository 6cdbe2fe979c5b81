"""The cam scenes' expected figures against independent computations: each scene's number is
what a hand formula on closed-form laws written here gives (the package's law library and
follower geometry are not used), so a scene's row cannot drift from it."""
import math

import numpy as np
import pytest
from cam_closed_forms import cycloid, piecewise, poly345

from mechopt import registry
from mechopt.models.cam_shape import CamShape, pitch

THETA = np.linspace(0, 2 * math.pi, 1_000_000, endpoint=False)
DESIGN = [(cycloid, 120.0, 30.0), (None, 60.0, 0.0), (poly345, 120.0, -30.0), (None, 60.0, 0.0)]


def expected(scene_id, name):
    return registry.find(scene_id).spec.expect[name].value


def hand_pressure_deg(base_mm, pieces, e=8.0, roller=12.5):
    """Largest |phi| on the rise and on the return, tan(phi) = (s' - e) / (s + sqrt(Rp^2 - e^2))."""
    s, ds, _ = piecewise(THETA, pieces)
    phi = np.degrees(np.abs(np.arctan((ds - e) / (s + math.sqrt((base_mm + roller) ** 2 - e * e)))))
    return float(phi[ds > 1e-9].max()), float(phi[ds < -1e-9].max())


def test_translating_roller_scene_against_the_hand_formulas():
    run = registry.run("cam/translating-roller")
    rise, ret = hand_pressure_deg(40.0, DESIGN)
    for name, value in (("max_pressure_angle_rise_deg", rise), ("max_pressure_angle_return_deg", ret)):
        assert run.values[name] == pytest.approx(value, abs=1e-6)
        assert expected("cam/translating-roller", name) == pytest.approx(value, abs=1e-6)
    # the pitch curve by kinematic inversion; circles through consecutive points (no derivatives)
    s, _, _ = piecewise(THETA, DESIGN)
    R = np.array([np.full_like(s, 8.0), math.sqrt(52.5**2 - 64.0) + s])
    c, n = np.cos(THETA), np.sin(THETA)
    P = np.array([c * R[0] + n * R[1], -n * R[0] + c * R[1]])
    a, b, d = np.roll(P, 1, axis=1), P, np.roll(P, -1, axis=1)
    ab, bd, da = np.hypot(*(b - a)), np.hypot(*(d - b)), np.hypot(*(a - d))
    cross = (b - a)[0] * (d - a)[1] - (b - a)[1] * (d - a)[0]
    convex = cross < 0                                   # the pitch curve runs clockwise: convex turns right
    rho = float((ab * bd * da / (2 * np.abs(cross)))[convex].min())
    assert run.values["min_pitch_radius_mm"] == pytest.approx(rho, rel=1e-5)
    assert expected("cam/translating-roller", "min_pitch_radius_mm") == pytest.approx(rho, rel=1e-5)


def jump_rpm_by_search(pieces, k, preload, m):
    """The speed where min over the turn of k s + F0 + m w^2 s'' reaches 0, by bisection."""
    theta = np.linspace(0, 2 * math.pi, 7200, endpoint=False)          # the scene's samples
    s, _, dds = piecewise(theta, pieces)
    lo, hi = 1.0, 1e5
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        w = mid * math.pi / 30
        lo, hi = (mid, hi) if np.min(k * s + preload + m * w**2 * dds / 1000) > 0 else (lo, mid)
    return lo


@pytest.mark.parametrize("scene_id, pieces, k, preload, m", [
    ("cam/translating-roller", DESIGN, 10.0, 100.0, 2.0),
    ("cam/spring-cycloid-problem", [(cycloid, 120.0, 10.0), (None, 60.0, 0.0), (cycloid, 120.0, -10.0),
                                    (None, 60.0, 0.0)], 15.0, 37.5, 1.8)])
def test_jump_speeds_against_a_direct_search(scene_id, pieces, k, preload, m):
    got = jump_rpm_by_search(pieces, k, preload, m)
    assert registry.run(scene_id).values["jump_speed_rpm"] == pytest.approx(got, rel=1e-9)
    assert expected(scene_id, "jump_speed_rpm") == pytest.approx(got, rel=1e-6)


def test_the_spring_problems_force_at_100_deg_by_hand():
    b, x, w = 2 * math.pi / 3, 5 / 6, 1000 * math.pi / 30
    s = 10 * (x - math.sin(2 * math.pi * x) / (2 * math.pi))
    dds = 10 * 2 * math.pi / b**2 * math.sin(2 * math.pi * x)
    force = 15 * s + 37.5 + 1.8 * w**2 * dds / 1000
    assert expected("cam/spring-cycloid-problem", "follower_force_at_report_N") == pytest.approx(force, rel=1e-9)
    assert force < 0                                  # the follower has left the cam there


def test_least_base_radius_scene_against_bisection_of_the_hand_formula():
    lo, hi = 5.0, 150.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if max(hand_pressure_deg(mid, DESIGN)) <= 30.0 else (mid, hi)
    assert expected("cam/translating-roller-least-base", "least_base_radius_mm") == pytest.approx(hi, abs=2e-4)
    assert registry.run("cam/translating-roller-least-base").values["least_base_radius_mm"] == pytest.approx(hi, abs=2e-4)


def test_unreachable_limit_scene_names_the_hand_formulas_least_angle():
    least = max(hand_pressure_deg(60.0, DESIGN))
    assert expected("cam/pressure-limit-unreachable", "least_achievable_pressure_angle_deg") == pytest.approx(least, abs=1e-4)


def test_flat_face_least_base_scene_against_the_closed_form():
    pieces = [(cycloid, 90.0, 25.0), (None, 90.0, 0.0), (cycloid, 90.0, -25.0), (None, 90.0, 0.0)]
    s, _, dds = piecewise(THETA, pieces)
    closed = float(np.max(-(s + dds)))
    assert expected("cam/flat-face-least-base", "least_base_radius_mm") == pytest.approx(closed, abs=2e-4)
    assert registry.run("cam/flat-face-least-base").values["least_base_radius_mm"] == pytest.approx(closed, abs=2e-4)


def test_eccentric_jump_scene_against_the_closed_form():
    P, k, e, m = 2.5, 1000.0, 0.015, 0.9
    closed = math.sqrt((P + 2 * k * e) / (m * e)) * 30 / math.pi
    assert expected("cam/eccentric-jump", "jump_speed_rpm") == pytest.approx(closed, abs=1e-3)


def test_the_lift_cam_in_the_cam_wing_agrees_with_models_cam_shape():
    # the same cam posed by the other model (stop-impact/lift-cam-profile's parameters): the roller
    # centre's kinematics written apart (cam_shape's lever swing H / (a + b) against cam_followers'
    # arc s / a), the geometry from R on one implementation (cam_geometry.roller_cam); the values
    # themselves are checked against an independent pitch polygon in tests/stop_impact/test_cam_shape.py
    shape = CamShape(base_radius_mm=60.0, roller_radius_mm=15.0, stroke_mm=35.0295, rise_deg=35.59355,
                     return_deg=35.59355, dwell_deg=60.0, centre_distance_mm=120.0, a_mm=80.0, b_mm=120.0,
                     follower="oscillating", closure="groove")
    theta = np.linspace(0, 2 * math.pi, 720_000, endpoint=False)
    p = pitch(shape, theta)
    rise = theta < math.radians(35.59355)
    ret = (theta > math.radians(95.59355)) & (theta < math.radians(131.1871))
    run = registry.run("cam/lift-cam-groove")
    for name, where in (("max_pressure_angle_rise_deg", rise), ("max_pressure_angle_return_deg", ret)):
        other = float(np.degrees(p.pressure_rad[where]).max())
        assert run.values[name] == pytest.approx(other, rel=1e-6)
        assert expected("cam/lift-cam-groove", name) == pytest.approx(other, rel=1e-6)
    convex = p.radius_mm > 0
    assert run.values["min_pitch_radius_mm"] == pytest.approx(float(p.radius_mm[convex].min()), rel=1e-6)
    # the crossovers: where the cycloid's s'' changes sign, the middle of the rise and of the return
    assert np.allclose(np.sort(run.arrays["crossover_deg"]), [35.59355 / 2, 95.59355 + 35.59355 / 2], atol=0.05)


def test_turning_the_lift_cam_clockwise_swaps_its_rise_and_return_pressure_angles():
    ccw = registry.run("cam/lift-cam-groove").values
    cw = registry.run("cam/lift-cam-groove", {"sense": "cw"}).values
    assert cw["max_pressure_angle_rise_deg"] == pytest.approx(ccw["max_pressure_angle_return_deg"], rel=1e-9)
    assert cw["max_pressure_angle_return_deg"] == pytest.approx(ccw["max_pressure_angle_rise_deg"], rel=1e-9)
