"""The lift cam's law synthesised with its cam's geometry (solvers/stop_impact/cam_rows.py):
the law found keeps the pressure angle and the radii of curvature by an independent polygon of the
pitch curve built from the lever's positions alone, keeps the rebound by the chain (CVODES rise,
eq. (2)), and the limit it was given binds; a limit no law meets is INFEASIBLE naming the least
angle reached; the sequential steps stop at their count."""
import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest
from test_cam_shape import _lever_points, _polygon_checks

from mechopt import registry
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Status
from mechopt.models.cam_shape import summarise
from mechopt.solvers.stop_impact import cam_rows
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.synthesis import law_of, synthesise_law
from mechopt.solvers.stop_impact.window_lp import linear_lever

SCENE = "stop-impact/law-synthesis-geometry"
CAM = ("base_radius_mm", "roller_radius_mm", "centre_distance_mm", "dwell_deg")


@pytest.fixture(scope="module")
def posed():
    """(task, settings) of the scene."""
    return registry.find(SCENE).build()[:2]


@pytest.fixture(scope="module")
def run():
    return registry.run(SCENE).result


def _cam(task, settings, law, t_deg):
    """The lift cam cut to `law` over t (rise and mirrored return), as the scene poses it."""
    return SimpleNamespace(base_radius_mm=settings["cam_base_radius_mm"], roller_radius_mm=settings["cam_roller_radius_mm"],
                           centre_distance_mm=settings["cam_centre_distance_mm"], dwell_deg=settings["cam_dwell_deg"],
                           a_mm=task.a_mm, b_mm=task.b_mm, stroke_mm=task.stroke_mm, rise_deg=t_deg,
                           return_deg=t_deg, law=law)


def _polygon_pressure_deg(cam, lo_deg, hi_deg, n=100_001):
    """The largest angle between the lever's motion and the normal of central-difference chords of
    the hand-computed pitch points, over cam angles [lo_deg, hi_deg] (one phase)."""
    theta = np.radians(np.linspace(lo_deg, hi_deg, n))
    P, psi = _lever_points(theta, d=cam.centre_distance_mm, a=cam.a_mm, b=cam.b_mm, H=cam.stroke_mm,
                           Rb=cam.base_radius_mm, Rr=cam.roller_radius_mm, rise=cam.rise_deg, dwell=cam.dwell_deg,
                           ret=cam.return_deg, law=cam.law)
    chord = P[:, 2:] - P[:, :-2]
    th, ps = theta[1:-1], psi[1:-1]
    c, s = np.cos(th), np.sin(th)
    move = np.array([c * np.sin(ps) + s * np.cos(ps), -s * np.sin(ps) + c * np.cos(ps)])
    return float(np.degrees(np.arctan2(np.abs(np.sum(move * chord, axis=0)),
                                       np.abs(move[0] * chord[1] - move[1] * chord[0]))).max())


def test_the_scenes_cam_is_the_lift_cam_profiles(posed):
    """The geometry the synthesis holds is stop-impact/lift-cam-profile's (base, roller, centre
    distance, dwell) and its lever's arms are the cam's."""
    task, settings = posed
    lift = registry.find("stop-impact/lift-cam-profile").build()[0]
    for key in CAM:
        assert settings[f"cam_{key}"] == getattr(lift, key), key
    assert (task.a_mm, task.b_mm) == (lift.a_mm, lift.b_mm)


def test_the_synthesised_laws_cam_keeps_its_limits_by_an_independent_polygon(posed, run):
    """Pressure angle on the rise and the return from the polygon's chords (no derivatives, 1e-5
    rel: smooth) and the least convex and concave radii from circles through point triples (1e-3
    rel: the radius has corners at the cubic's knots, which the triples round off: see
    test_cam_shape.test_a_synthesised_laws_cam_is_checked_like_a_library_laws); each within its limit."""
    task, settings = posed
    assert run.status is Status.SOLVED
    v, t = run.values, run.values["t_deg"]
    cam = _cam(task, settings, law_of(run), t)
    rise = _polygon_pressure_deg(cam, 0.0, t)
    back = _polygon_pressure_deg(cam, t + cam.dwell_deg, 2 * t + cam.dwell_deg)
    convex, concave, phi = _polygon_checks(cam)
    assert v["max_pressure_angle_rise_deg"] == pytest.approx(rise, rel=1e-5)
    assert v["max_pressure_angle_return_deg"] == pytest.approx(back, rel=1e-5)
    assert max(rise, back) == pytest.approx(phi, rel=1e-5)
    assert v["min_radius_of_curvature_mm"] == pytest.approx(convex, rel=1e-3)
    assert v["min_concave_radius_mm"] == pytest.approx(concave, rel=1e-3)
    least = settings["cam_roller_radius_mm"] + settings["min_curvature_margin_mm"]
    assert phi <= settings["max_pressure_angle_deg"] + cam_rows.GEOMETRY_TOL_DEG
    assert min(convex, concave) >= least - cam_rows.GEOMETRY_TOL_MM


def test_the_synthesised_law_keeps_the_rebound_by_the_chain(posed, run):
    """The chain (CVODES rise, contact located, eq. (2)) every 10 rpm over the band, not only at
    the LP's samples: the rebound within the limit and the synthesis' agreement tolerance."""
    task, settings = posed
    law, t = law_of(run), run.values["t_deg"]
    each = dataclasses.replace(task, law=law)
    got = [float(rebound_amplitude_mm(each, n, t)) for n in np.arange(280.0, 421.0, 10.0)]
    assert max(got) <= task.amplitude_limit_mm * (1 + 2e-3)


def test_the_pressure_limit_binds_the_least_phase(posed, run):
    """The same question without the cam's limits: its law reaches a larger pressure angle than
    the limit (on the polygon) at a smaller phase angle, and the scene's says the pressure binds."""
    task, settings = posed
    free = synthesise_law(task, **(settings | {"geometry": False, "verify": False}))
    assert free.status is Status.SOLVED
    t_free = free.values["t_deg"]
    phi_free = _polygon_checks(_cam(task, settings, law_of(free), t_free))[2]
    assert phi_free > settings["max_pressure_angle_deg"] + 1.0
    assert t_free < run.values["t_deg"]
    assert run.values["pressure_angle_binds"] == 1.0 and run.values["curvature_binds"] == 0.0
    assert run.diagnostics["geometry_binds"] == ["pressure_angle"]


def test_a_pressure_limit_no_law_meets_is_infeasible_naming_the_least_angle(posed):
    """15 deg on the lift cam: no law at the bracket's top (45 deg). The least angle the steps
    reach is named, above the limit and no worse than the cycloid's on the same cam (its start)."""
    task, settings = posed
    out = synthesise_law(task, **(settings | {"max_pressure_angle_deg": 15.0, "verify": False}))
    assert out.status is Status.INFEASIBLE
    assert "pressure_angle" in out.violated
    least = out.values["least_pressure_angle_deg"]
    assert f"{least:.4g} deg > max_pressure_angle_deg=15" in out.message
    lift = registry.find("stop-impact/lift-cam-profile").build()[0]
    cycloid = summarise(dataclasses.replace(lift, stroke_mm=task.stroke_mm, rise_deg=45.0, return_deg=45.0))
    assert 15.0 < least <= cycloid.max_pressure_angle_deg


def test_the_steps_stop_at_their_count_with_limit(posed, monkeypatch):
    """A tolerance no law's exact check meets (negative): LIMIT naming the step count."""
    task, settings = posed
    monkeypatch.setattr(cam_rows, "GEOMETRY_TOL_DEG", -1.0)
    out = synthesise_law(task, **(settings | {"objective": "least_rebound", "geometry_steps": 2, "verify": False}))
    assert out.status is Status.LIMIT
    assert "after 2 sequential LPs" in out.message


def test_the_rows_are_the_first_order_terms_of_the_exact_geometry(posed):
    """The linearised rows at c against the exact rows at c + h dc: their gap falls as h^2 (the
    gradients are the geometry's own), on the rise and the return."""
    task, settings = posed
    lever = linear_lever(settings["coefficients"], settings["continuity"])
    from mechopt.models.cam_shape import CamShape
    shape = CamShape(base_radius_mm=60.0, roller_radius_mm=15.0, stroke_mm=task.stroke_mm, rise_deg=31.0,
                     return_deg=31.0, dwell_deg=60.0, centre_distance_mm=120.0, a_mm=task.a_mm, b_mm=task.b_mm,
                     follower="oscillating", closure="groove")
    geometry = cam_rows.CamGeometry(shape, 34.0, 5.0, 4)
    (s0, B), *_ = lever.kin
    rise = np.flatnonzero(lever.rise)
    c = np.linalg.lstsq(B[rise].toarray(), 0.5 * (1 - np.cos(math.pi * lever.xi[rise])) - s0[rise], rcond=None)[0]
    dc = np.random.default_rng(3).normal(size=c.size) * 1e-3
    here = geometry.linearised(lever, c, 31.0, {})
    gaps = []
    for h in (1.0, 0.5):
        there = geometry.linearised(lever, c + h * dc, 31.0, {})
        gaps.append(max(np.abs((u - G @ (c + h * dc)) - (u2 - G2 @ (c + h * dc))).max()
                        for (_, G, u), (_, G2, u2) in zip(here, there)))
    assert gaps[1] / gaps[0] == pytest.approx(0.25, abs=0.05)


@pytest.mark.parametrize("more, key", [({"cam_centre_distance_mm": 200.0}, "cam_centre_distance_mm"),
                                       ({"cam_dwell_deg": 300.0}, "phase_to_deg")])
def test_a_cam_that_cannot_be_made_is_refused_naming_the_setting(posed, more, key):
    task, settings = posed
    with pytest.raises(SettingError) as err:
        synthesise_law(task, **(settings | more))
    assert err.value.key == key and key in str(err.value)
