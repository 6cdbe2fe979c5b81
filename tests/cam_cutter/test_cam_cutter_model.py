"""Cam-cutting linkage model (paper 000, Podchasov 2021, Secs. III-IV): geometry and validation.

Every geometric check below restates the paper's equation in the test, or differentiates
numerically, instead of calling the model a second time.
"""
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mechopt.kit.errors import ModelError
from mechopt.models.cam_cutter import (
    LinkageFit,
    decimal_reading,
    finish_angle,
    ideal_normal,
    ideal_point,
    limacon_implicit,
    matched_linkage,
    real_acceleration,
    real_point,
    real_velocity,
)

PROPERTY = settings(max_examples=40, deadline=None)
T_FINISH_PUBLISHED_RAD = 2.7329      # Podchasov (2021), Sec. IV: "t_FINISH = 2.7329 rad" (a = 25 mm, h = 2 mm)


def paper_task(**changes):
    """The paper's task (Sec. IV), with the given parameters changed."""
    params = dict(a_mm=25.0, h_mm=2.0, err_width_mm=0.075, step_mm=0.01,
                  H_min_mm=55.0, H_max_mm=65.0, L_min_mm=45.0, L_max_mm=50.0) | changes
    return LinkageFit(**params)


def cardioid_eq1(t, a):
    """Eq. (1) of the paper, written out: the cam profile before any shift."""
    return 2 * a * np.cos(t) + a * np.cos(2 * t) + a, 2 * a * np.sin(t) + a * np.sin(2 * t)


def cardioid_eq1_derivative(t, a):
    """d/dt of eq. (1)."""
    return -2 * a * np.sin(t) - 2 * a * np.sin(2 * t), 2 * a * np.cos(t) + 2 * a * np.cos(2 * t)


# ---------------------------------------------------------------- ideal path, eqs. (1)-(3), (9)

@PROPERTY
@given(a=st.floats(0.5, 200.0), t=st.floats(0.0, np.pi, exclude_max=True))
def test_ideal_point_without_offset_is_cardioid_eq1_shifted_by_4a(a, t):
    x1, y1 = cardioid_eq1(t, a)
    x, y = ideal_point(t, a, 0.0)
    assert x == pytest.approx(x1 - 4 * a, abs=1e-12 * a)
    assert y == pytest.approx(y1, abs=1e-12 * a)


@PROPERTY
@given(a=st.floats(0.5, 200.0), frac=st.floats(0.0, 0.99), t=st.floats(0.0, np.pi, exclude_max=True))
def test_ideal_point_matches_paper_eq9(a, frac, t):
    h = frac * a
    X = a * (2 * np.cos(t) + np.cos(2 * t) + 1) + h * np.cos(1.5 * t) - (4 * a + h)
    Y = a * (2 * np.sin(t) + np.sin(2 * t)) + h * np.sin(1.5 * t)
    assert ideal_point(t, a, h) == pytest.approx((X, Y), abs=1e-12 * a)


@PROPERTY
@given(a=st.floats(0.5, 200.0), frac=st.floats(0.001, 0.99), t=st.floats(0.0, np.pi - 1e-3))
def test_offset_path_lies_at_distance_h_along_ideal_normal(a, frac, t):
    # Undo the h-dependent shift of eq. (9), -(4a + h), to compare with eq. (1) shifted by -4a:
    # the parallel curve (3) is the cardioid moved by h along its unit normal (2).
    h = frac * a
    xh, yh = ideal_point(t, a, h)
    x0, y0 = ideal_point(t, a, 0.0)
    dx, dy = xh + h - x0, yh - y0
    assert np.hypot(dx, dy) == pytest.approx(h, rel=1e-9)
    assert (dx / h, dy / h) == pytest.approx(ideal_normal(t), abs=1e-9)


@PROPERTY
@given(a=st.floats(0.5, 200.0), frac=st.floats(0.0, 0.99), t=st.floats(0.0, np.pi - 1e-3))
def test_offset_path_is_paper_eq2_parallel_curve(a, frac, t):
    h = frac * a
    x, y = cardioid_eq1(t, a)
    vx, vy = cardioid_eq1_derivative(t, a)
    speed = np.hypot(vx, vy)
    X, Y = x + h * vy / speed, y - h * vx / speed           # eq. (2)
    assert ideal_point(t, a, h) == pytest.approx((X - 4 * a - h, Y), abs=1e-9 * a)


@PROPERTY
@given(a=st.floats(0.5, 200.0), frac=st.floats(0.0, 0.99), t=st.floats(0.01, 3.0))
def test_ideal_normal_is_outward_unit_normal_of_the_path(a, frac, t):
    h = frac * a
    dt = 1e-6
    xp, yp = ideal_point(t + dt, a, h)
    xm, ym = ideal_point(t - dt, a, h)
    tx, ty = (xp - xm) / (2 * dt), (yp - ym) / (2 * dt)
    speed = np.hypot(tx, ty)
    nx, ny = ideal_normal(t)
    assert np.hypot(nx, ny) == pytest.approx(1.0, abs=1e-14)
    assert abs(tx * nx + ty * ny) <= 1e-7 * speed                # orthogonal to the tangent
    # the path runs counter-clockwise round the cam, so outward is to the right: T x n = -|T|
    assert tx * ny - ty * nx == pytest.approx(-speed, rel=1e-7)


@PROPERTY
@given(a=st.floats(0.5, 200.0), t=st.floats(0.0, 2.8))
def test_ideal_normal_points_out_of_the_plain_cardioid(a, t):
    # the plain cardioid is the limaçon H = L = 2a (eq. (1) is eq. (7) with those lengths): a step
    # along +n leaves its interior, a step along -n enters it
    x, y = ideal_point(t, a)
    nx, ny = ideal_normal(t)
    eps = 1e-3 * a
    assert limacon_implicit(x + eps * nx, y + eps * ny, 2 * a, 2 * a) > 0
    assert limacon_implicit(x - eps * nx, y - eps * ny, 2 * a, 2 * a) < 0


# ---------------------------------------------------------------- real path, eqs. (7), (10)

@PROPERTY
@given(s=st.floats(0.0, 2 * np.pi), H=st.floats(1.0, 200.0), L=st.floats(1.0, 200.0))
def test_real_point_lies_on_limacon_implicit(s, H, L):
    x, y = real_point(s, H, L)
    assert abs(limacon_implicit(x, y, H, L)) <= 1e-12 * (L + H) ** 4


@PROPERTY
@given(s=st.floats(0.0, 2 * np.pi), H=st.floats(1.0, 200.0), L=st.floats(1.0, 200.0))
def test_real_point_matches_paper_eq10(s, H, L):
    X = L * np.cos(s) + H / 2 * np.cos(2 * s) + H / 2 - (L + H)
    Y = L * np.sin(s) + H / 2 * np.sin(2 * s)
    assert real_point(s, H, L) == pytest.approx((X, Y), abs=1e-12 * (L + H))


@PROPERTY
@given(s=st.floats(0.0, 2 * np.pi), H=st.floats(1.0, 200.0), L=st.floats(1.0, 200.0))
def test_real_velocity_and_acceleration_match_central_differences(s, H, L):
    ds = 1e-5
    xp, yp = real_point(s + ds, H, L)
    xm, ym = real_point(s - ds, H, L)
    x0, y0 = real_point(s, H, L)
    scale = 1e-7 * (L + 2 * H)
    assert real_velocity(s, H, L) == pytest.approx(((xp - xm) / (2 * ds), (yp - ym) / (2 * ds)), abs=scale)
    vp, vm = real_velocity(s + ds, H, L), real_velocity(s - ds, H, L)
    assert real_acceleration(s, H, L) == pytest.approx(
        ((vp[0] - vm[0]) / (2 * ds), (vp[1] - vm[1]) / (2 * ds)), abs=scale)
    # and the second difference of the position (a wider step: roundoff grows as 1/ds^2)
    ds = 1e-3
    (xp, yp), (xm, ym) = real_point(s + ds, H, L), real_point(s - ds, H, L)
    assert real_acceleration(s, H, L) == pytest.approx(
        ((xp - 2 * x0 + xm) / ds**2, (yp - 2 * y0 + ym) / ds**2), abs=1e-5 * (L + H))


def test_limacon_implicit_is_negative_inside_and_positive_outside():
    H, L = 59.45, 47.52
    assert limacon_implicit(-L, 0.0, H, L) < 0          # between the vertex (0, 0) and the far side -2L
    assert limacon_implicit(1.0, 0.0, H, L) > 0         # beyond the vertex
    assert limacon_implicit(-(L + H), 0.0, H, L) == pytest.approx(0.0, abs=1e-9)   # the double point


# ---------------------------------------------------------------- t_FINISH and its reading

@PROPERTY
@given(a=st.floats(0.5, 200.0), frac=st.floats(0.001, 0.99))
def test_finish_angle_is_first_axis_crossing_of_offset_path(a, frac):
    h = frac * a
    t_f = finish_angle(a, h)
    assert 0 < t_f < np.pi
    assert abs(ideal_point(t_f, a, h)[1]) <= 1e-10 * a
    inner = np.linspace(0.0, t_f, 2001)[1:-1]
    assert np.all(ideal_point(inner, a, h)[1] > 0)


@pytest.mark.parametrize("a", [0.5, 25.0, 40.0, 300.0])
def test_finish_angle_of_plain_cardioid_is_the_cusp(a):
    assert finish_angle(a, 0.0) == pytest.approx(np.pi, abs=1e-12)


def test_decimal_reading_reproduces_published_t_finish():
    # Podchasov (2021), Sec. IV: t_FINISH = 2.7329 rad, read until |Y| <= 0.001 mm (a = 25, h = 2)
    def y(t):
        return ideal_point(t, 25.0, 2.0)[1]
    assert decimal_reading(y, finish_angle(25.0, 2.0), 0.001) == T_FINISH_PUBLISHED_RAD
    assert paper_task().t_finish_read_rad == T_FINISH_PUBLISHED_RAD


def test_decimal_reading_stops_at_first_digit_count_meeting_the_tolerance():
    # a root of a straight line f(t) = t - root: the reading has as many digits as the tolerance needs
    root = 1.23456789
    assert decimal_reading(lambda t: t - root, root, 1e-3) == 1.234
    assert decimal_reading(lambda t: t - root, root, 1e-5) == 1.23456


def test_exact_finish_angle_of_paper_task_rounds_to_published_value():
    assert paper_task().t_finish_rad == pytest.approx(T_FINISH_PUBLISHED_RAD, abs=1e-4)


# ---------------------------------------------------------------- matched linkage and bounds

@pytest.mark.parametrize("a", [0.5, 1.0, 25.0, 40.0, 123.4])
def test_matched_linkage_of_plain_cardioid_is_2a_2a(a):
    H, L = matched_linkage(a, 0.0)
    assert H == pytest.approx(2 * a, abs=1e-9)
    assert L == pytest.approx(2 * a, abs=1e-9)


def test_matched_linkage_matches_double_point_and_vertex_curvature():
    a, h = 25.0, 2.0
    H, L = matched_linkage(a, h)
    span = -ideal_point(finish_angle(a, h), a, h)[0]
    assert L + H == pytest.approx(span, rel=1e-12)                       # double point at -(L + H)
    assert (L + H) ** 2 / (L + 2 * H) == pytest.approx(8 * a / 3 + h, rel=1e-12)   # vertex radius


def test_bounds_fill_missing_limits_with_matched_linkage_plus_minus_half_a():
    H0, L0 = matched_linkage(25.0, 2.0)
    task = LinkageFit(a_mm=25.0, h_mm=2.0, err_width_mm=0.075, H_max_mm=70.0)
    assert task.bounds() == pytest.approx((H0 - 12.5, 70.0, L0 - 12.5, L0 + 12.5), abs=1e-12)
    assert paper_task().bounds() == (55.0, 65.0, 45.0, 50.0)


# ---------------------------------------------------------------- validation: every ModelError message

@pytest.mark.parametrize("key, allowed", [("a_mm", r"1e-06 \.\.\. 1e\+06"), ("err_width_mm", "> 0"),
                                          ("step_mm", "> 0"), ("y_tol_mm", "> 0")])
@pytest.mark.parametrize("value", [0.0, -1.0])
def test_non_positive_size_is_rejected(key, allowed, value):
    with pytest.raises(ModelError, match=rf"^{key}={value}: allowed {allowed}$") as err:
        paper_task(**{key: value})
    assert err.value.key == key


def test_negative_a_mm_is_rejected():
    with pytest.raises(ModelError, match=r"a_mm=-25\.0: allowed 1e-06 \.\.\. 1e\+06"):
        LinkageFit(a_mm=-25.0, err_width_mm=0.075)


def test_negative_kerf_offset_is_rejected():
    with pytest.raises(ModelError, match=r"h_mm=-0\.5: allowed >= 0") as err:
        paper_task(h_mm=-0.5)
    assert err.value.key == "h_mm"


@pytest.mark.parametrize("h", [25.0, 30.0])
def test_kerf_offset_not_below_a_is_rejected(h):
    with pytest.raises(ModelError, match=rf"h_mm={h}: allowed < a_mm=25\.0 \(a wider kerf") as err:
        paper_task(h_mm=h)
    assert err.value.key == "h_mm"


@pytest.mark.parametrize("key", ["H_min_mm", "H_max_mm", "L_min_mm", "L_max_mm"])
def test_non_positive_bound_is_rejected(key):
    with pytest.raises(ModelError, match=rf"{key}=-1\.0: allowed > 0 \.\.\. 100 a_mm = 2500 \(the matched links") as err:
        paper_task(**{key: -1.0})
    assert err.value.key == key


@pytest.mark.parametrize("lo, hi", [("H_min_mm", "H_max_mm"), ("L_min_mm", "L_max_mm")])
def test_reversed_bounds_are_rejected(lo, hi):
    with pytest.raises(ModelError, match=rf"bounds reversed: {lo}=70\.0 > {hi}=60\.0") as err:
        paper_task(**{lo: 70.0, hi: 60.0})
    assert err.value.key == lo


def test_equal_bounds_are_accepted():
    assert paper_task(H_min_mm=59.45, H_max_mm=59.45).bounds()[:2] == (59.45, 59.45)


def test_nan_size_is_rejected():
    with pytest.raises(ModelError, match=r"a_mm=nan: expected a finite number"):
        paper_task(a_mm=float("nan"))


@pytest.mark.parametrize("value, allowed", [(float("inf"), "expected a finite number"),
                                            *((v, r"allowed 1e-06 \.\.\. 1e\+06") for v in (1e300, 1e7, 1e-9))])
def test_cam_size_outside_its_physical_range_is_rejected(value, allowed):
    with pytest.raises(ModelError, match=rf"^a_mm={re.escape(str(value))}: {allowed}$") as err:
        LinkageFit(a_mm=value, err_width_mm=1e-10)
    assert err.value.key == "a_mm"


@pytest.mark.parametrize("key, value, message", [
    ("err_width_mm", 2501.0, r"err_width_mm=2501\.0: allowed <= 100 a_mm = 2500 \(a band a hundred cams wide\)"),
    ("err_width_mm", float("inf"), r"err_width_mm=inf: expected a finite number"),
    ("y_tol_mm", 26.0, r"y_tol_mm=26\.0: allowed <= a_mm=25\.0 \(a reading must be finer than the cam\)"),
    ("step_mm", float("inf"), r"step_mm=inf: expected a finite number"),
    ("step_mm", 26.0, r"step_mm=26\.0: allowed <= a_mm=25\.0 \(the lattice must be finer than the cam\)"),
    ("H_max_mm", float("inf"), r"H_max_mm=inf: expected a finite number"),
    ("H_max_mm", 2600.0, r"H_max_mm=2600\.0: allowed > 0 \.\.\. 100 a_mm = 2500 \(the matched links are"),
    ("L_min_mm", 1e6, r"L_min_mm=1000000\.0: allowed > 0 \.\.\. 100 a_mm = 2500"),
])
def test_huge_or_infinite_length_is_rejected_naming_its_range(key, value, message):
    with pytest.raises(ModelError, match=rf"^{message}") as err:
        paper_task(**{key: value})
    assert err.value.key == key


@pytest.mark.parametrize("key", ["H_mm", "L_mm"])
def test_huge_link_of_a_checked_linkage_is_rejected(key):
    from mechopt.models.cam_cutter import LinkageCheck
    fields = {"a_mm": 25.0, "err_width_mm": 0.075, "H_mm": 59.45, "L_mm": 47.52} | {key: 2501.0}
    with pytest.raises(ModelError, match=rf"^{key}=2501\.0: allowed > 0 \.\.\. 100 a_mm = 2500") as err:
        LinkageCheck(**fields)
    assert err.value.key == key


@pytest.mark.parametrize("a", [1e-3, 1.0, 25.0, 1e3])
def test_step_and_reading_defaults_keep_the_papers_ratio_to_the_cam(a):
    # Sec. IV: STEP 0.01 mm and t_FINISH to 0.001 mm, for a = 25 mm
    task = LinkageFit(a_mm=a, err_width_mm=0.003 * a)
    assert task.step_mm == pytest.approx(0.01 * a / 25, rel=1e-15)
    assert task.y_tol_mm == pytest.approx(0.001 * a / 25, rel=1e-15)
    if a == 25.0:
        assert (task.step_mm, task.y_tol_mm) == (0.01, 0.001)        # exactly the paper's values


@pytest.mark.parametrize("a", [1e-3, 1.0, 25.0, 1e3])
def test_default_box_is_matched_linkage_plus_minus_half_a_at_every_size(a):
    # once clamped to at least step_mm: a 1 um cam got the box 0.01 .. 0.01 mm
    H0, L0 = matched_linkage(a, 0.0)
    box = LinkageFit(a_mm=a, err_width_mm=0.003 * a).bounds()
    assert box == pytest.approx((H0 - a / 2, H0 + a / 2, L0 - a / 2, L0 + a / 2), rel=1e-12)
    assert box[0] < 2 * a < box[1] and box[2] < 2 * a < box[3]


def test_widened_default_box_keeps_links_positive():
    box = LinkageFit(a_mm=25.0, h_mm=2.0, err_width_mm=0.075).bounds(pad_per_a=8.0)
    assert box[0] == box[2] == pytest.approx(0.01 * 25.0)         # floor: MIN_LINK_PER_A a
    H0, L0 = matched_linkage(25.0, 2.0)
    assert (box[1], box[3]) == pytest.approx((H0 + 200.0, L0 + 200.0))
