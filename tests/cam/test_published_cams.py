"""Printed cam sizing figures against the package. A figure counts here only when it was read in a
stored source, quoted below with its address; each is matched to half a unit of its last printed
digit, and the reading it needs is named with the other readings computed beside it.

The source: the documentation of the Python package `mechanism` (Gabe Morris), readme.md, section
"Cams" (github.com/gabemorris12/mechanism; https://pypi.org/project/mechanism, releases 1.1.7 and
1.1.8): "Design a cam using cycloidal motion that has the following motion description: Dwell at
zero displacement for 90 degrees, Rise 1 inch in 90 degrees, Dwell for 90 degrees, Fall 1 inch in
90 degrees ... Also size the cam for a flat faced follower", "the radius of curvature at the
point of contact should be positive (or greater than 0.25")", and "The base circle radius was
found to be 1.893" and the minimum face width for the follower was found to be 2.55"". A
program's printed output (its code, mechanism/cams.py Cam.get_base_circle, says how it got them),
not a textbook's. The hand computations here use the closed-form cycloid of cam_closed_forms.py,
not the package's law library.
"""
import math

import numpy as np
import pytest
from cam_closed_forms import cycloid, piecewise

from mechopt import registry
from mechopt.models.cam_followers import CamFollower

INCH_MM = 25.4
PRINTED_BASE_IN, BASE_DIGIT_IN = 1.893, 0.001      # 'The base circle radius was found to be 1.893"'
PRINTED_FACE_IN, FACE_DIGIT_IN = 2.55, 0.01        # 'the minimum face width ... was found to be 2.55"'
RHO_MIN_IN = 0.25                                  # '(or greater than 0.25")'
LIFT_IN = 1.0
PIECES_IN = [(None, 90.0, 0.0), (cycloid, 90.0, LIFT_IN), (None, 90.0, 0.0), (cycloid, 90.0, -LIFT_IN)]
THETA = np.linspace(0, 2 * math.pi, 1_000_000, endpoint=False)
LEAST, WIDTH = "cam/printed-flat-face-least-base", "cam/printed-flat-face-width"


def expected(scene_id, name):
    return registry.find(scene_id).spec.expect[name]


def within_printed(got_mm, printed_in, digit_in):
    return abs(got_mm / INCH_MM - printed_in) <= digit_in / 2


def test_the_scenes_state_the_printed_figures_in_mm():
    for scene, name, printed, digit in ((LEAST, "least_base_radius_mm", PRINTED_BASE_IN, BASE_DIGIT_IN),
                                        (WIDTH, "face_travel_mm", PRINTED_FACE_IN, FACE_DIGIT_IN),
                                        (WIDTH, "face_width_needed_mm", PRINTED_FACE_IN, FACE_DIGIT_IN)):
        row = expected(scene, name)
        assert row.kind == "published"
        assert row.value == pytest.approx(printed * INCH_MM, abs=1e-9)
        assert row.abs == pytest.approx(digit / 2 * INCH_MM, abs=1e-9)
    assert registry.find(WIDTH).spec.params["base_radius_mm"].value == pytest.approx(PRINTED_BASE_IN * INCH_MM)
    assert registry.find(LEAST).spec.params["min_profile_radius_mm"].value == pytest.approx(RHO_MIN_IN * INCH_MM)


# -- reading A (the scene's): rho = Rb + s + s'' >= 0.25 in, Rb the cam's least radius ----------------

def test_the_least_base_radius_reproduces_the_printed_1_893_in():
    got = registry.run(LEAST).values["least_base_radius_mm"]
    s, _, dds = piecewise(THETA, PIECES_IN)
    by_hand_in = RHO_MIN_IN - float(np.min(s + dds))              # the source's own branch, in closed form
    assert got / INCH_MM == pytest.approx(by_hand_in, abs=1e-5)
    assert within_printed(got, PRINTED_BASE_IN, BASE_DIGIT_IN), f"{got / INCH_MM:.5f} in against 1.893 in"


def test_at_the_printed_base_radius_the_profile_keeps_the_0_25_in_it_was_sized_for():
    run = registry.run(WIDTH).values
    # 1.893 in rounds the answer: the least radius there is 0.25 in plus that rounding (< 0.0005 in)
    assert 0 <= run["min_profile_radius_mm"] / INCH_MM - RHO_MIN_IN <= BASE_DIGIT_IN / 2


# -- reading B (not the scene's): the source's conservative branch -----------------------------------

def polar_rho_in(base_in, theta):
    """The source's conservative branch (conservative_flat=True): the radius of curvature of the
    polar curve r = Rb + s, as the package computes it for a radial roller's pitch curve whose
    prime radius is Rb (the roller's own radius drops out) [in]."""
    roller_mm = 1.0
    cam = CamFollower(base_radius_mm=base_in * INCH_MM - roller_mm, face="roller", roller_radius_mm=roller_mm,
                      segments=registry.find(LEAST).spec.structure["segments"])
    return float(np.min(cam.curves(theta).pitch_radius_mm)) / INCH_MM


def test_the_conservative_reading_gives_another_base_radius_than_the_printed_one():
    theta = np.linspace(0, 2 * math.pi, 7200, endpoint=False)
    lo, hi = PRINTED_BASE_IN, 3.0                      # too small under this reading; large enough
    assert polar_rho_in(lo, theta) < RHO_MIN_IN <= polar_rho_in(hi, theta)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if polar_rho_in(mid, theta) >= RHO_MIN_IN else (mid, hi)
    # by hand, the polar curve's radius of curvature (R^2 + R'^2)^1.5 / (R^2 + 2 R'^2 - R R''): the
    # search stops where its concave stretch vanishes (there the least radius jumps from large
    # negative to above 0.25 in), as the source's loop stepping Rb up by 0.001 in does
    s, ds, dds = piecewise(theta, PIECES_IN)

    def hand_rho(base_in):
        R = base_in + s
        return float(np.min((R**2 + ds**2) ** 1.5 / (R**2 + 2 * ds**2 - R * dds)))
    assert hand_rho(hi) >= RHO_MIN_IN > hand_rho(lo)
    assert hi == pytest.approx(2.2086, abs=1e-3)
    assert hi - PRINTED_BASE_IN > 0.3                  # the printed 1.893 in is reading A's, not this one's


# -- the face width: the contact's travel (the source's max y' - min y') or a centred face ------------

def test_the_face_width_reproduces_the_printed_2_55_in_under_both_readings():
    run = registry.run(WIDTH).values
    closed_in = 2 * 2 * LIFT_IN / (math.pi / 2)         # the cycloid's s' runs 0 ... 2 h / beta, rise and fall
    for name in ("face_travel_mm", "face_width_needed_mm"):
        assert run[name] / INCH_MM == pytest.approx(closed_in, rel=1e-6)
        assert within_printed(run[name], PRINTED_FACE_IN, FACE_DIGIT_IN), f"{name}: {run[name] / INCH_MM:.4f} in"
    assert run["face_contact_min_mm"] == pytest.approx(-run["face_contact_max_mm"], abs=1e-9)
