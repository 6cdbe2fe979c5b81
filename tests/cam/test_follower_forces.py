"""Closure and forces: the jump speed against a direct search over the speed, a spring too weak for
its speed (status as the scene asks), a groove's crossovers (never called lift-off), the follower
force by hand, and the Hertz stress against the half-width route of a cylinder pair."""
import math

import numpy as np
import pytest
from cam_closed_forms import CycloidRDRD

from mechopt.kit.result import Status
from mechopt.models.cam_followers import CamFollower
from mechopt.solvers.cam import size_cam

SPRING = {"mass_kg": 1.8, "spring_rate_N_per_mm": 15.0, "preload_N": 37.5}


def cam(**kw):
    return CamFollower(**({"base_radius_mm": 40.0, "roller_radius_mm": 10.0, "motion": CycloidRDRD(h=10.0)}
                          | SPRING | kw))


def least_force_N(rpm, theta, motion):
    """min over the turn of k s + F0 + m omega^2 s'' (written here from Newton's law)."""
    s, _, dds, _ = motion.at(theta)
    w = rpm * math.pi / 30
    return float(np.min(15.0 * s + 37.5 + 1.8 * w**2 * dds / 1000))


def test_jump_speed_against_a_direct_search_over_the_speed():
    r = size_cam(cam(speed_rpm=100.0))
    theta = np.linspace(0, 2 * math.pi, 7200, endpoint=False)     # the solver's samples
    lo, hi = 1.0, 5000.0
    for _ in range(80):                                            # bisection on the sign of the least force
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if least_force_N(mid, theta, CycloidRDRD(h=10.0)) > 0 else (lo, mid)
    assert r.values["jump_speed_rpm"] == pytest.approx(lo, rel=1e-9)
    assert r.status is Status.SOLVED and r.values["min_follower_force_N"] > 0


@pytest.mark.parametrize("ask", ["LIMIT", "INFEASIBLE"])
def test_a_spring_too_weak_for_the_speed_reports_the_jump_speed_with_the_status_asked(ask):
    r = size_cam(cam(speed_rpm=1000.0, on_jump=ask))
    assert r.status is Status(ask) and r.violated == ("jump",)
    assert r.values["jump_speed_rpm"] < 1000.0
    assert f"jump speed {r.values['jump_speed_rpm']:.4g} rpm" in r.message and "leaves the cam" in r.message


def test_the_follower_force_at_an_angle_by_hand():
    # cycloidal rise of 10 mm over 120 deg at 1000 rpm, 100 deg into the rise: x = 5/6
    r = size_cam(cam(speed_rpm=1000.0, report_angle_deg=100.0, on_jump="LIMIT"))
    b, x, w = 2 * math.pi / 3, 5 / 6, 1000 * math.pi / 30
    s = 10 * (x - math.sin(2 * math.pi * x) / (2 * math.pi))
    dds = 10 * 2 * math.pi / b**2 * math.sin(2 * math.pi * x)
    assert r.values["s_at_report_mm"] == pytest.approx(s, rel=1e-12)
    assert r.values["follower_force_at_report_N"] == pytest.approx(15 * s + 37.5 + 1.8 * w**2 * dds / 1000, rel=1e-12)


def test_a_groove_reports_crossovers_to_the_other_wall_not_lift_off():
    r = size_cam(cam(closure="groove", spring_rate_N_per_mm=0.0, preload_N=0.0, backlash_mm=0.05, speed_rpm=300.0))
    assert r.status is Status.SOLVED
    # a cycloid's acceleration changes sign in the middle of the rise (60 deg) and of the return (240 deg)
    assert r.values["crossovers"] == 2.0
    assert np.allclose(np.sort(r.arrays["crossover_deg"]), [60.0, 240.0], atol=0.05)
    assert "crosses to the other wall" in r.message and "backlash_mm=0.05" in r.message
    assert "leaves" not in r.message and "jump_speed_rpm" not in r.values


def test_hertz_stress_against_the_half_width_route():
    task = cam(speed_rpm=300.0, roller_width_mm=12.0, cam_E_MPa=206_000.0, follower_E_MPa=200_000.0,
               cam_nu=0.29, follower_nu=0.3)
    r = size_cam(task)
    i = int(np.argmax(r.arrays["contact_stress_MPa"]))
    F, R1, R2 = r.arrays["contact_force_N"][i], 10.0, r.arrays["profile_radius_mm"][i]
    m = (1 - 0.29**2) / 206_000.0 + (1 - 0.3**2) / 200_000.0
    b = math.sqrt(2 * F / (math.pi * 12.0) * m / (0.5 * (1 / R1 + 1 / R2)))   # contact half-width [mm]
    assert r.values["max_contact_stress_MPa"] == pytest.approx(2 * F / (math.pi * b * 12.0), rel=1e-9)


def test_an_eccentric_cams_jump_speed_and_lift_off_angles_against_the_closed_form():
    # an eccentric (e = 15 mm) under a flat face: s = e (1 - cos theta), s'' = e cos theta; the force
    # P + k e + (m w^2 - k) e cos theta (SI) first reaches 0 at theta = 180 deg, at w^2 = (P + 2 k e) / (m e),
    # and beyond that speed is < 0 between the two roots of cos theta = -(P + k e) / ((m w^2 - k) e)
    from cam_closed_forms import HarmonicOutAndBack

    P, k, e, m, rpm = 2.5, 1000.0, 0.015, 0.9, 500.0
    task = CamFollower(base_radius_mm=25.0, face="flat", motion=HarmonicOutAndBack(2 * e * 1000), mass_kg=m,
                       spring_rate_N_per_mm=k / 1000, preload_N=P, speed_rpm=rpm, on_jump="LIMIT")
    r = size_cam(task, samples=36_000)
    assert r.values["jump_speed_rpm"] == pytest.approx(math.sqrt((P + 2 * k * e) / (m * e)) * 30 / math.pi, rel=1e-9)
    assert r.values["jump_at_deg"] == pytest.approx(180.0, abs=1e-9)
    w = rpm * math.pi / 30
    root = math.degrees(math.acos(-(P + k * e) / ((m * w**2 - k) * e)))
    assert np.allclose(np.sort(r.arrays["lift_off_deg"]), [root, 360.0 - root], atol=1e-4)
    assert r.status is Status.LIMIT and f"{root:.2f}" in r.message
