"""The cam law library (`mechopt.laws`, models/cam_laws.py): peak coefficients against published
values and against independent closed forms, derivatives against finite differences, the ends'
values and continuity, the numpy and CasADi forms against each other, and the old laws' homes
(cam_follower, cam_shape) unchanged to the bit."""
import math

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from mechopt import ModelError, laws

REQUIRED = ("cycloidal", "harmonic", "modified_sine", "modified_trapezoid", "polynomial_345", "polynomial_4567",
            "double_harmonic")
XI = np.linspace(0.0, 1.0, 4001)


def test_the_library_holds_the_required_laws_and_at_least_ten():
    assert set(REQUIRED) <= set(laws.names()) and len(laws.names()) >= 10
    for name in laws.names():
        law = laws.law(name)
        assert law.name == name and set(law.peaks) == {"Cv", "Ca", "Cj"}
        assert all(v.shape == XI.shape and v.dtype == float for v in law.values(XI))


def test_an_unknown_name_is_refused_with_the_names():
    with pytest.raises(ModelError, match=r"law='parabolic': unknown motion law; allowed: cycloidal, harmonic, "
                                         r"modified_sine, .*polynomial_4567") as err:
        laws.law("parabolic")
    assert err.value.key == "law"


# -- published peak coefficients --------------------------------------------------------------------
# H.A. Rothbart (ed.), *Cam Design Handbook*, McGraw-Hill 2004, ch. 2 "Basic curves", prints each
# basic curve's y and its derivatives for a rise h over beta; at a unit rise their peaks are:
#   constant acceleration, eqs. (2.17)-(2.19), p. 35: velocity 4 h q / b^2 (2 at the mid-point),
#     acceleration 4 h / b^2, "jerk = inf at dwell ends and the midpoint";
#   cubic no. 2, eqs. (2.46)-(2.49), p. 40: velocity 6 h q / b^2 (1 - q / b) (3/2), acceleration
#     6 h / b^2 (1 - 2 q / b) (6 at the ends), jerk 12 h / b^3, constant;
#   cycloidal, eqs. (2.57)-(2.60), p. 45: velocity h / b (1 - cos 2 pi q / b) (2), acceleration
#     2 pi h / b^2 sin(.), jerk 4 pi^2 h / b^3 cos(.).
# The MechDesigner (PSMotion Ltd) user manual, "Modified-Sinusoid Motion-Law" (mechdesigner.support,
# motion-cam-law-modified-sinusoid.htm): Cv = 1.76, Ca = 5.53, Cj = 69.47; and "Sine-Constant-Cosine
# (SCCA) Motion-Law" (mt-motion-cam-law-sine-constant-cosine-cv.htm), its table of SCCA parameters
# (sine a, constant b, cosine c, zero-acceleration d) giving the traditional laws: modified
# trapezoidal (0.25, 0.5, 0.25) Cv 2, Ca 4.89; modified sine (0.25, 0, 0.75) Cv 1.760; modified sine
# CV 20% (0.2, 0, 0.6) Cv 1.528, Ca 5.999; modified sine CV 33% (0.1667, 0, 0.5) Cv 1.404, Ca 6.616.
# A printed number is matched to its last printed digit (half a unit of it, or one for a
# truncation); a printed formula to rounding (rel 1e-9).

FORMULA = None              # the tolerance of a printed formula: relative 1e-9
PUBLISHED = [  # (law, key, printed value, absolute tolerance or FORMULA)
    (laws.law("constant_acceleration"), "Cv", 2.0, FORMULA), (laws.law("constant_acceleration"), "Ca", 4.0, FORMULA),
    (laws.law("constant_acceleration"), "Cj", math.inf, FORMULA),
    (laws.law("cubic"), "Cv", 1.5, FORMULA), (laws.law("cubic"), "Ca", 6.0, FORMULA),
    (laws.law("cubic"), "Cj", 12.0, FORMULA),
    (laws.law("cycloidal"), "Cv", 2.0, FORMULA), (laws.law("cycloidal"), "Ca", 2 * math.pi, FORMULA),
    (laws.law("cycloidal"), "Cj", 4 * math.pi**2, FORMULA),
    (laws.law("modified_sine"), "Cv", 1.76, 0.005), (laws.law("modified_sine"), "Ca", 5.53, 0.005),
    (laws.law("modified_sine"), "Cj", 69.47, 0.005), (laws.scca(0.25, 0.75), "Cv", 1.760, 0.0005),
    (laws.law("modified_trapezoid"), "Cv", 2.0, 1e-12), (laws.law("modified_trapezoid"), "Ca", 4.89, 0.005),
    (laws.scca(0.2, 0.6, cv=0.2), "Cv", 1.528, 0.0005), (laws.scca(0.2, 0.6, cv=0.2), "Ca", 5.999, 0.0005),
    (laws.scca(1 / 6, 0.5, cv=1 / 3), "Cv", 1.404, 0.0005), (laws.scca(1 / 6, 0.5, cv=1 / 3), "Ca", 6.616, 0.001),
]


@pytest.mark.parametrize(("law", "key", "printed", "tol"), PUBLISHED,
                         ids=[f"{law.name}-{key}" for law, key, _, _ in PUBLISHED])
def test_peak_coefficients_match_the_published_tables(law, key, printed, tol):
    if math.isinf(printed):
        assert law.peaks[key] == printed
    else:
        assert law.peaks[key] == (pytest.approx(printed, rel=1e-9) if tol is FORMULA
                                  else pytest.approx(printed, abs=tol))


# -- exact peak coefficients from independent closed forms ---------------------------------------

def _polynomial_peaks(coefficients):
    """Cv, Ca, Cj of the polynomial S (coefficients, lowest power first) on [0, 1], found from the
    roots of the next derivative by numpy.polynomial (independent of the library's forms)."""
    S = Polynomial(coefficients)
    out = []
    for k in (1, 2, 3):
        d = S.deriv(k)
        candidates = [0.0, 1.0] + [r.real for r in d.deriv().roots() if abs(r.imag) < 1e-12 and 0 <= r.real <= 1]
        out.append(max(abs(d(x)) for x in candidates))
    return dict(zip(("Cv", "Ca", "Cj"), out))


PI = math.pi
EXACT = {
    # S = x - sin(2 pi x)/(2 pi): S' = 1 - cos, peak 2 at 1/2; S'' = 2 pi sin; S''' = 4 pi^2 cos
    "cycloidal": {"Cv": 2.0, "Ca": 2 * PI, "Cj": 4 * PI**2},
    # S = (1 - cos pi x)/2: pi/2, pi^2/2, pi^3/2
    "harmonic": {"Cv": PI / 2, "Ca": PI**2 / 2, "Cj": PI**3 / 2},
    # Kloomok-Muffley: the cycloid's quarter of period 1/2 scaled by pi / (4 + pi): Ca = 4 pi^2 / (4 + pi),
    # Cj = 16 pi^3 / (4 + pi); the velocity's peak at 1/2 is pi (1 + 3 / 2) / (4 + pi) ... = 4 pi / (4 + pi) * 1.0
    "modified_sine": {"Cv": 4 * PI / (4 + PI), "Ca": 4 * PI**2 / (4 + PI), "Cj": 16 * PI**3 / (4 + PI)},
    # ramps over 1/8: the constant C = 8 pi / (pi + 2) makes the mid-point velocity C (1/4 + 1/(2 pi)) = 2
    "modified_trapezoid": {"Cv": 2.0, "Ca": 8 * PI / (PI + 2), "Cj": 32 * PI**2 / (PI + 2)},
    "polynomial_345": _polynomial_peaks([0, 0, 0, 10, -15, 6]),
    "polynomial_4567": _polynomial_peaks([0, 0, 0, 0, 35, -84, 70, -20]),
    "cubic": _polynomial_peaks([0, 0, 3, -2]),
    # two parabolas: S'' = 4 then -4; the step at 1/2 is an infinite jerk
    "constant_acceleration": {"Cv": 2.0, "Ca": 4.0, "Cj": math.inf},
    # linear ramps over 1/8 to C = 16/3: the mid-point velocity C (1/16 + 1/4 + 1/16) = 2, jerk C / (1/8)
    "trapezoid": {"Cv": 2.0, "Ca": 16 / 3, "Cj": 128 / 3},
    # (1 - cos pi x)/2 - (1 - cos 2 pi x)/8: S'' = pi^2/2 (cos pi x - cos 2 pi x) peaks at x = 1 (-pi^2)
    "double_harmonic": {"Ca": PI**2},
}


@pytest.mark.parametrize("name", sorted(EXACT))
def test_peak_coefficients_match_their_closed_forms(name):
    got = laws.law(name).peaks
    for key, value in EXACT[name].items():
        assert got[key] == pytest.approx(value, rel=1e-9), key


def test_the_polynomials_closed_forms_are_the_textbook_ones():
    """The roots-of-derivatives computation above reproduces the printed 3-4-5 and 4-5-6-7 figures:
    15/8, 10/sqrt(3), 60 and 35/16, 16.8/sqrt(5), 52.5 (the derivatives' extremes by hand)."""
    assert EXACT["polynomial_345"] == pytest.approx({"Cv": 15 / 8, "Ca": 10 / math.sqrt(3), "Cj": 60.0})
    assert EXACT["polynomial_4567"] == pytest.approx({"Cv": 35 / 16, "Ca": 16.8 / math.sqrt(5), "Cj": 52.5})


def _norton_scca_ca(b, c):
    """The SCCA family's peak acceleration for sine fraction b, cosine fraction c (Norton, Design of
    Machinery, ch. 8: Ca = 4 pi^2 / ((pi^2 - 8)(b^2 - c^2) - 2 pi (pi - 2) b + pi^2))."""
    return 4 * PI**2 / ((PI**2 - 8) * (b * b - c * c) - 2 * PI * (PI - 2) * b + PI**2)


@pytest.mark.parametrize(("b", "c"), [(0.25, 0.25), (0.5, 0.5), (0.25, 0.75), (0.0, 1.0), (0.0, 0.0), (0.1, 0.3),
                                      (0.4, 0.2), (0.6, 0.1)])
def test_the_scca_family_meets_nortons_closed_form(b, c):
    assert laws.scca(b, c).peaks["Ca"] == pytest.approx(_norton_scca_ca(b, c), rel=1e-9)


@pytest.mark.parametrize(("b", "c", "name"), [(0.5, 0.5, "cycloidal"), (0.0, 1.0, "harmonic"),
                                              (0.25, 0.75, "modified_sine")])
def test_the_scca_family_holds_the_laws_written_on_their_own(b, c, name):
    """Three laws written each in its own closed form are members of the family built from
    acceleration pieces: two independent constructions agree everywhere."""
    for mine, family in zip(laws.law(name).values(XI), laws.scca(b, c).values(XI)):
        np.testing.assert_allclose(mine, family, atol=1e-11)


# -- derivatives, ends, continuity ---------------------------------------------------------------

@pytest.mark.parametrize("name", laws.names())
def test_each_derivative_is_the_finite_difference_of_the_one_before(name):
    law = laws.law(name)
    h = 1e-6
    x = np.linspace(0.003, 0.997, 499)
    x = x[np.min(np.abs(x[:, None] - np.array(law.breaks or (2.0,))[None, :]), axis=1) > 10 * h]
    up, down, here = law.values(x + h), law.values(x - h), law.values(x)
    for k in (1, 2, 3):
        scale = max(1.0, float(np.abs(here[k]).max()))
        np.testing.assert_allclose((up[k - 1] - down[k - 1]) / (2 * h), here[k], atol=1e-5 * scale)


@pytest.mark.parametrize("name", laws.names())
def test_a_unit_rise_from_rest_to_rest_and_its_continuity_order_at_the_ends(name):
    """S(0) = 0, S(1) = 1, S' = 0 at both ends; below `end_order` every derivative is 0 at both
    ends, and derivative `end_order` (<= 3) is not, at one end at least: the order of the first
    step against a dwell."""
    law = laws.law(name)
    ends = law.continuity()
    assert ends["start"][0] == pytest.approx(0.0, abs=1e-14) and ends["end"][0] == pytest.approx(1.0, abs=1e-14)
    for k in range(1, min(law.end_order, 4)):
        assert ends["start"][k] == pytest.approx(0.0, abs=1e-9) and ends["end"][k] == pytest.approx(0.0, abs=1e-9)
    if law.end_order <= 3:
        assert max(abs(ends["start"][law.end_order]), abs(ends["end"][law.end_order])) > 1e-3


def test_the_continuity_orders_are_the_textbooks():
    order = {name: laws.law(name).end_order for name in laws.names()}
    assert order == {"cycloidal": 3, "harmonic": 2, "modified_sine": 3, "modified_trapezoid": 3,
                     "polynomial_345": 3, "polynomial_4567": 4, "double_harmonic": 2,
                     "constant_acceleration": 2, "trapezoid": 3, "cubic": 2}


def test_a_step_inside_a_law_is_found():
    assert laws.law("constant_acceleration").interior_jumps() == [(0.5, 2, pytest.approx(-8.0))]
    assert all(laws.law(n).interior_jumps() == [] for n in laws.names() if n != "constant_acceleration")


# -- numpy and CasADi, and the old laws' homes ----------------------------------------------------

@pytest.mark.parametrize("name", laws.names())
def test_the_casadi_form_is_the_numpy_form(name):
    import casadi as ca
    x = ca.SX.sym("x")
    f = ca.Function("f", [x], list(laws.law(name).expression(x)))
    got = [np.asarray(v).ravel() for v in f.map(XI.size)(XI[None, :])]
    for a, b in zip(got, laws.law(name).values(XI)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


def _old_displacement(law, xi):
    """The four laws as models/cam_follower.py wrote them before the library (a frozen copy)."""
    import casadi as ca
    if law == "cycloidal":
        return xi - ca.sin(2 * math.pi * xi) / (2 * math.pi)
    if law == "polynomial_345":
        return xi**3 * (10 - 15 * xi + 6 * xi**2)
    if law == "harmonic":
        return (1 - ca.cos(math.pi * xi)) / 2
    k = 4 + math.pi
    first = (math.pi * xi - ca.sin(4 * math.pi * xi) / 4) / k
    middle = (2 + math.pi * xi - 9 * ca.sin(math.pi * (4 * xi + 1) / 3) / 4) / k
    last = (4 + math.pi * xi - ca.sin(4 * math.pi * xi) / 4) / k
    return ca.if_else(xi < 0.125, first, ca.if_else(xi < 0.875, middle, last))


@pytest.mark.parametrize("name", ["cycloidal", "modified_sine", "polynomial_345", "harmonic"])
def test_the_old_laws_integrators_see_the_same_bits(name):
    """cam_follower.law_values (CasADi's AD of the library's S) and cam_shape.library_law give
    exactly what the old copies gave: the validate figures of the lift cannot move."""
    import casadi as ca

    from mechopt.models.cam_follower import LAWS, law_values
    from mechopt.models.cam_shape import library_law
    x = ca.SX.sym("xi")
    s = _old_displacement(name, x)
    ds = ca.gradient(s, x)
    old = ca.Function("old", [x], [s, ds, ca.gradient(ds, x)])
    xi = np.r_[np.linspace(0.0, 1.0, 2001), 0.125, 0.875]
    want = [np.asarray(v).ravel() for v in old.map(xi.size)(xi[None, :])]
    assert name in LAWS
    for got in (law_values(name, xi), library_law(name)(xi)):
        for a, b in zip(got, want):
            assert np.array_equal(a, b)
    # and the library's own closed-form derivatives agree with that AD to rounding
    for a, b in zip(laws.law(name).values(xi)[:3], want):
        np.testing.assert_allclose(a, b, atol=1e-12)


def test_the_old_homes_take_every_library_law_and_refuse_others_by_the_library():
    from mechopt.models.cam_follower import law_values
    from mechopt.models.cam_shape import library_law
    S, dS, ddS = law_values("trapezoid", XI)
    np.testing.assert_allclose(np.c_[S, dS, ddS], np.c_[laws.law("trapezoid").values(XI)[:3]], atol=1e-11)
    with pytest.raises(ModelError, match="unknown motion law; allowed: cycloidal"):
        library_law("parabolic")


# -- a polynomial from its conditions -------------------------------------------------------------

def test_a_polynomial_from_its_boundary_conditions_is_the_textbooks():
    rest = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (1, 0, 1), (1, 1, 0), (1, 2, 0)]
    p5 = laws.polynomial(rest)
    p7 = laws.polynomial(rest + [(0, 3, 0), (1, 3, 0)])
    assert (p5.name, p7.name, p5.end_order, p7.end_order) == ("polynomial_deg5", "polynomial_deg7", 3, 4)
    for made, book in ((p5, "polynomial_345"), (p7, "polynomial_4567")):
        for a, b in zip(made.values(XI), laws.law(book).values(XI)):
            np.testing.assert_allclose(a, b, atol=1e-9)


def test_a_polynomial_meets_conditions_no_library_law_does():
    """A rise that leaves at a velocity (S'(1) = 1.5, into a following segment) meets each condition."""
    conditions = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (1, 0, 1), (1, 1, 1.5), (1, 2, 0)]
    law = laws.polynomial(conditions, name="rise_into_motion")
    values = law.values(np.array([0.0, 1.0]))
    for xi, order, value in conditions:
        assert values[order][int(xi)] == pytest.approx(value, abs=1e-12)
    assert law.name == "rise_into_motion" and law.end_order == 1


@pytest.mark.parametrize(("conditions", "match"), [
    ([(0, 0, 0)], "expected two or more"),
    ([(0, 0, 0), (0, 0, 1)], "not independent"),
    ([(0, 4, 0), (1, 0, 1)], "order allowed 0..3"),
    ([(0, 0, 0), (1, 0, math.nan)], "finite"),
    ([(0, 0, 0), (1, 0, "one")], "finite numbers"),
    ([(0, 0, 0), 1.0], "expected two or more"),
    ([(0, k, 0) for k in range(4)] + [(1, k, 1 - bool(k)) for k in range(4)] + [(0.5, 0, 0.5)] * 5, "at most 12"),
])
def test_bad_polynomial_conditions_are_refused(conditions, match):
    with pytest.raises(ModelError, match=match):
        laws.polynomial(conditions)


@pytest.mark.parametrize(("b", "c", "cv"), [(-0.1, 0.5, 0.0), (0.6, 0.6, 0.0), (0.2, 0.2, 0.7), (math.nan, 0.1, 0.0),
                                          (0.0, 0.0, 1.0)])
def test_bad_scca_fractions_are_refused(b, c, cv):
    with pytest.raises(ModelError, match="allowed 0 <= b, c, cv and b \\+ c \\+ cv <= 1, cv < 1"):
        laws.scca(b, c, cv)


def test_an_scca_member_is_a_law_by_name_in_the_integrators_and_the_cam():
    """"scca(b, c[, cv])" names a family member wherever a law name goes: the library, the lift's
    integrators (CasADi's AD of its S) and a cam's segments."""
    from mechopt.models.cam_follower import law_values
    from mechopt.models.cam_motion import CamMotion
    named = laws.law("scca(0.2, 0.6, 0.2)")
    assert named.name == "scca(0.2, 0.6, 0.2)" and named is laws.law("scca(0.2,0.6,0.2)")
    assert named.peaks == pytest.approx(laws.scca(0.2, 0.6, cv=0.2).peaks)
    np.testing.assert_allclose(np.c_[law_values("scca(0.25, 0.25)", XI)],
                               np.c_[laws.law("modified_trapezoid").values(XI)[:3]], atol=1e-11)
    cam = CamMotion([dict(segment="rise", law="scca(0.25, 0.75)", angle_deg=180, lift_mm=1.0),
                     dict(segment="return", law="modified_sine", angle_deg=180, lift_mm=-1.0)])
    assert cam.steps() == []
    with pytest.raises(ModelError, match=r"law=scca\(b=0.7, c=0.7, cv=0.0\): allowed"):
        laws.law("scca(0.7, 0.7)")
    with pytest.raises(ModelError, match=r"law='scca\(a, b\)': unknown motion law; allowed: cycloidal, .* or "
                                         r"scca\(b, c\[, cv\]\)"):
        laws.law("scca(a, b)")
