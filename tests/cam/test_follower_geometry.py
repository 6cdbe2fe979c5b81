"""Follower geometry against independent computations: the offset translating roller's pressure
angle against the hand formula and against normals of a dense polygon of the pitch curve built by
kinematic inversion; the sense of rotation swapping rise and return; an oscillating roller's
pressure angle from its polygon; a flat face's radius of curvature against circles through
consecutive profile points, its cusp and least base radius against the closed form
Rb > -min(s + s''), and a harmonic out-and-back cam that is an eccentric circle."""
import math

import numpy as np
import pytest
from cam_closed_forms import CycloidRDRD, HarmonicOutAndBack

from mechopt.kit.result import Status
from mechopt.models.cam_followers import CamFollower
from mechopt.solvers.cam import least_base_radius, size_cam

THETA = np.linspace(0, 2 * math.pi, 200_000, endpoint=False)


def roller(**kw):
    return CamFollower(**({"base_radius_mm": 40.0, "roller_radius_mm": 10.0, "motion": CycloidRDRD()} | kw))


def flat(**kw):
    return CamFollower(**({"base_radius_mm": 40.0, "face": "flat", "motion": CycloidRDRD()} | kw))


def polygon_pressure_deg(P, direction, sigma):
    """|angle| between the pitch polygon's normal (central differences of the cam-frame points,
    turned back to the fixed frame) and the follower's direction of motion (fixed frame)."""
    d = np.roll(P, -1, axis=1) - np.roll(P, 1, axis=1)
    c, s = np.cos(sigma * THETA), np.sin(sigma * THETA)      # Rot(+sigma theta): cam frame -> fixed
    d = np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
    n = np.array([-d[1], d[0]]) / np.hypot(*d)
    return np.degrees(np.arccos(np.abs(np.sum(n * direction, axis=0))))


def inversion(R, sigma):
    """The roller centre seen from the cam: Rot(-sigma theta) R (kinematic inversion)."""
    c, s = np.cos(sigma * THETA), np.sin(sigma * THETA)
    return np.array([c * R[0] + s * R[1], -s * R[0] + c * R[1]])


@pytest.mark.parametrize("sense, e", [("ccw", 0.0), ("ccw", 8.0), ("cw", 8.0), ("ccw", -8.0)])
def test_offset_translating_roller_pressure_angle_against_the_hand_formula_and_a_polygon(sense, e):
    task = roller(offset_mm=e, sense=sense)
    sigma = 1 if sense == "ccw" else -1
    s, ds, _, _ = task.motion.at(THETA)
    s0 = math.sqrt(50.0**2 - e**2)
    hand = np.degrees(np.arctan((sigma * ds - e) / (s0 + s)))                # Norton, Design of Machinery, sec. 8.7
    got = np.degrees(task.curves(THETA).pressure_rad)
    assert np.max(np.abs(got - hand)) < 1e-9
    poly = polygon_pressure_deg(inversion(np.array([np.full_like(s, e), s0 + s]), sigma), np.array([[0.0], [1.0]]), sigma)
    assert np.max(np.abs(np.abs(got) - poly)) < 1e-5
    r = size_cam(task)
    rise, ret = ds > 1e-9, ds < -1e-9
    assert r.values["max_pressure_angle_rise_deg"] == pytest.approx(np.abs(hand[rise]).max(), abs=1e-6)
    assert r.values["max_pressure_angle_return_deg"] == pytest.approx(np.abs(hand[ret]).max(), abs=1e-6)


def test_the_sense_of_rotation_swaps_rise_and_return_for_an_offset_follower():
    ccw, cw = (size_cam(roller(offset_mm=8.0, sense=k)).values for k in ("ccw", "cw"))
    assert ccw["max_pressure_angle_rise_deg"] < ccw["max_pressure_angle_return_deg"]     # offset on the helping side
    assert cw["max_pressure_angle_rise_deg"] == pytest.approx(ccw["max_pressure_angle_return_deg"], rel=1e-9)
    assert cw["max_pressure_angle_return_deg"] == pytest.approx(ccw["max_pressure_angle_rise_deg"], rel=1e-9)


def test_oscillating_roller_pressure_angle_and_radius_against_its_polygon():
    task = roller(follower="oscillating", pivot_distance_mm=100.0, arm_mm=80.0)
    s = task.motion.at(THETA)[0]
    psi = task.psi0_rad(40.0) + s / 80.0
    R = np.array([100.0 - 80.0 * np.cos(psi), 80.0 * np.sin(psi)])        # the roller centre by hand
    P = inversion(R, 1)
    poly = polygon_pressure_deg(P, np.array([np.sin(psi), np.cos(psi)]), 1)
    c = task.curves(THETA)
    assert np.max(np.abs(np.abs(np.degrees(c.pressure_rad)) - poly)) < 1e-5
    assert np.max(np.abs(c.pitch - P)) < 1e-9
    a, b, d = P, np.roll(P, -1, axis=1), np.roll(P, 1, axis=1)
    circ = circumradius(d, a, b)
    convex = c.pitch_radius_mm > 0
    assert np.max(np.abs(circ[convex] - c.pitch_radius_mm[convex]) / c.pitch_radius_mm[convex]) < 1e-5


def circumradius(a, b, c):
    """Radius of the circle through three points (2 x n each)."""
    ab, bc, ca = np.hypot(*(b - a)), np.hypot(*(c - b)), np.hypot(*(a - c))
    cross = np.abs((b - a)[0] * (c - a)[1] - (b - a)[1] * (c - a)[0])
    return ab * bc * ca / (2 * cross)


def test_flat_face_radius_of_curvature_is_rb_plus_s_plus_s2_and_matches_its_polygon():
    task = flat()
    s, _, dds, _ = task.motion.at(THETA)
    c = task.curves(THETA)
    assert np.max(np.abs(c.profile_radius_mm - (40.0 + s + dds))) < 1e-9      # Norton sec. 8.9
    P = c.profile
    circ = circumradius(np.roll(P, 1, axis=1), P, np.roll(P, -1, axis=1))
    # second order in the step; first order at the phase joins where s''' jumps (4e-4 mm there)
    assert np.max(np.abs(circ - c.profile_radius_mm) / c.profile_radius_mm) < 2e-5


def test_flat_face_least_base_radius_and_cusp_against_the_closed_form():
    motion = CycloidRDRD(h=20.0, rise=60.0, dwell=30.0, ret=90.0)
    s, _, dds, _ = motion.at(THETA)
    closed = float(np.max(-(s + dds)))                  # rho = Rb + s + s'' > 0 everywhere
    r = least_base_radius(flat(motion=motion, base_radius_min_mm=1.0, base_radius_max_mm=100.0))
    assert r.status is Status.SOLVED
    assert r.values["least_base_radius_mm"] == pytest.approx(closed, abs=2e-4)
    assert r.values["least_base_radius_mm"] >= closed - 1e-9        # the feasible end: no cusp there
    cusped = size_cam(flat(motion=motion, base_radius_mm=closed - 1.0))
    assert cusped.status is Status.INFEASIBLE and "cusp" in cusped.violated
    at = float(np.degrees(THETA[np.argmax(-(s + dds))]))
    assert cusped.values["min_profile_radius_at_deg"] == pytest.approx(at, abs=0.01)
    assert f"cam angle {cusped.values['min_profile_radius_at_deg']:.3f} deg" in cusped.message
    assert size_cam(flat(motion=motion, base_radius_mm=closed + 1.0)).status is Status.SOLVED


def test_harmonic_out_and_back_under_a_flat_face_is_an_eccentric_circle():
    # s = 25 (1 - cos theta) under a radial flat face on a 25 mm base: the face is at 50 - 25 cos theta
    # from the shaft, the support function of a circle of radius 50 mm whose centre is 25 mm off it;
    # the contact runs s' = 25 sin theta along the face: a face 50 mm long
    task = flat(base_radius_mm=25.0, motion=HarmonicOutAndBack(50.0))
    c = task.curves(THETA)
    centre = np.array([[0.0], [-25.0]])              # at theta = 0 the face is 25 mm from the shaft
    assert np.max(np.abs(np.hypot(*(c.profile - centre)) - 50.0)) < 1e-9
    r = size_cam(task)
    assert r.values["face_travel_mm"] == pytest.approx(50.0, abs=1e-6)
    assert r.values["face_width_needed_mm"] == pytest.approx(50.0, abs=1e-6)       # centred on the stem
    assert r.values["max_pressure_angle_deg"] == pytest.approx(0.0, abs=1e-12)
    assert r.values["min_profile_radius_mm"] == pytest.approx(50.0, abs=1e-9)


def test_a_face_narrower_than_the_contacts_travel_names_both_widths():
    r = size_cam(flat(face_width_mm=30.0))
    need = r.values["face_width_needed_mm"]
    assert r.status is Status.INFEASIBLE and r.violated == ("face_width",)
    assert "face_width_mm=30" in r.message and f"{need:.3f} mm" in r.message
    s, ds, _, _ = CycloidRDRD().at(THETA)
    assert r.values["face_travel_mm"] == pytest.approx(ds.max() - ds.min(), rel=1e-6)    # the contact runs s'
    assert size_cam(flat(face_width_mm=need + 0.01)).status is Status.SOLVED


def test_an_undercut_roller_is_named_at_its_cam_angle():
    task = roller(base_radius_mm=8.0, roller_radius_mm=12.0, motion=CycloidRDRD(h=30.0, rise=45.0, ret=45.0))
    r = size_cam(task)
    assert r.status is Status.INFEASIBLE and "undercut" in r.violated
    assert f"{r.values['min_pitch_radius_at_deg']:.3f} deg" in r.message and "roller_radius_mm=12" in r.message
    assert "pitch_x_mm" in r.arrays and "profile_x_mm" not in r.arrays       # no profile for the shop


def test_a_pressure_angle_limit_no_base_radius_meets_is_infeasible_naming_the_least_angle():
    task = roller(offset_mm=5.0, max_pressure_angle_deg=20.0, base_radius_min_mm=5.0, base_radius_max_mm=20.0)
    r = least_base_radius(task)
    assert r.status is Status.INFEASIBLE
    least = size_cam(roller(offset_mm=5.0, base_radius_mm=20.0)).values["max_pressure_angle_deg"]
    assert r.values["least_achievable_pressure_angle_deg"] == pytest.approx(least, abs=1e-6)
    assert f"least achievable is {least:.4f} deg" in r.message and "base_radius_max_mm=20" in r.message


def test_least_base_radius_for_a_pressure_angle_limit_meets_it_at_the_answer():
    task = roller(offset_mm=5.0, max_pressure_angle_deg=30.0, base_radius_min_mm=5.0, base_radius_max_mm=200.0)
    r = least_base_radius(task)
    assert r.status is Status.SOLVED
    rb = r.values["least_base_radius_mm"]
    at = size_cam(roller(offset_mm=5.0, base_radius_mm=rb)).values["max_pressure_angle_deg"]
    below = size_cam(roller(offset_mm=5.0, base_radius_mm=rb - 1e-3)).values["max_pressure_angle_deg"]
    assert at <= 30.0 < below


def test_oscillating_flat_face_envelope_against_intersections_of_its_lines():
    # the face's lines seen from the cam, m . X = p, intersected pairwise (no support-function
    # derivatives): the envelope's points; the pressure angle from the arm's motion at that point
    d, L, f = 120.0, 80.0, 5.0
    task = flat(follower="oscillating", pivot_distance_mm=d, arm_mm=L, face_offset_mm=f)
    s = task.motion.at(THETA)[0]
    psi = math.asin((40.0 + f) / d) + s / L
    p = d * np.sin(psi) - f
    alpha = math.pi / 2 - psi - THETA                      # m's angle seen from the ccw cam
    m = np.array([np.cos(alpha), np.sin(alpha)])
    m2, p2 = np.roll(m, -1, axis=1), np.roll(p, -1)
    det = m[0] * m2[1] - m[1] * m2[0]
    X = np.array([(p * m2[1] - p2 * m[1]) / det, (m[0] * p2 - m2[0] * p) / det])   # between theta_k and theta_k+1
    c = task.curves(THETA + 0.5 * (THETA[1] - THETA[0]))
    assert np.max(np.hypot(*(X - c.profile))) < 1e-6
    C = np.array([np.cos(THETA) * X[0] - np.sin(THETA) * X[1], np.sin(THETA) * X[0] + np.cos(THETA) * X[1]])
    r = C - np.array([[d], [0.0]])
    v = np.array([r[1], -r[0]])                            # the arm's point moving as psi grows: -J (C - A)
    fixed = np.array([np.sin(psi), np.cos(psi)])
    hand = np.degrees(np.arccos(np.abs(np.sum(v * fixed, axis=0)) / np.hypot(*v)))
    got = np.abs(np.degrees(task.curves(THETA).pressure_rad))
    assert np.max(np.abs(got - hand)) < 1e-3
