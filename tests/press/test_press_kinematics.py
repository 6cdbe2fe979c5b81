"""The press's crank-slider at constant crank speed (`press.kinematics`): every rate against central
differences of the model's own position functions (models.press_laws.travel_m, rod_angle_rad), and the
closed forms at the dead centres and at 90 deg; the scene's slider speed by a dense difference."""
import dataclasses
import math

import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Status
from mechopt.models.press_laws import rod_angle_rad, travel_m
from mechopt.solvers.press import kinematics
from mechopt.solvers.press.kinematics import slider_crank_rates


@pytest.fixture(scope="module")
def task():
    return registry.find("press/kd2322-kinematics").build()[0]


@pytest.mark.parametrize("form", ["exact", "paper"])
@pytest.mark.parametrize("lam", [0.071, 0.3, 0.6])
def test_every_rate_is_the_derivative_of_the_models_position(form, lam):
    r, h = 0.04, 1e-4
    phi = np.linspace(0.05, 2 * np.pi - 0.05, 97)
    X, dX, ddX, beta, db, ddb = slider_crank_rates(phi, r, lam, form)
    pos = lambda f: travel_m(phi + f * h, r, lam, form)               # noqa: E731
    ang = lambda f: rod_angle_rad(phi + f * h, lam, form)             # noqa: E731
    assert dX == pytest.approx((pos(1) - pos(-1)) / (2 * h), abs=1e-9)
    assert ddX == pytest.approx((pos(1) - 2 * pos(0) + pos(-1)) / h**2, abs=1e-6)
    assert db == pytest.approx((ang(1) - ang(-1)) / (2 * h), abs=1e-7)
    assert ddb == pytest.approx((ang(1) - 2 * ang(0) + ang(-1)) / h**2, abs=1e-5)


def test_the_closed_forms_at_the_dead_centres_and_at_90_degrees():
    r, lam, w = 0.025, 0.071, 25.0
    X, dX, ddX, beta, db, ddb = slider_crank_rates(np.array([0.0, np.pi / 2, np.pi]), r, lam, "exact")
    assert w * w * ddX[0] == pytest.approx(w * w * r * (1 + lam), rel=1e-12)        # top dead centre
    assert w * w * ddX[2] == pytest.approx(-w * w * r * (1 - lam), rel=1e-12)       # bottom dead centre
    assert w * db[0] == pytest.approx(w * lam, rel=1e-12) and w * db[2] == pytest.approx(-w * lam, rel=1e-12)
    assert w * w * ddb[1] == pytest.approx(-w * w * lam / math.sqrt(1 - lam * lam), rel=1e-12)
    assert dX[1] == pytest.approx(r, rel=1e-12)              # at 90 deg the slider moves as the crank pin


def test_the_scenes_slider_speed_by_a_dense_difference(task):
    phi = np.linspace(0.0, 2 * np.pi, 2_000_001)
    X = travel_m(phi, task.r_m, task.rod_ratio, "exact")
    dense = float(np.max(np.abs(np.gradient(X, phi[1] - phi[0])))) * task.nominal_speed_rad_s
    expected = registry.find("press/kd2322-kinematics").spec.expect["slider_velocity_max_m_s"]
    assert dense == pytest.approx(expected.value, rel=expected.rel)
    assert kinematics(task).values["slider_velocity_max_m_s"] == pytest.approx(dense, rel=1e-6)


def test_the_papers_form_differs_from_the_exact_by_order_lambda_cubed(task):
    exact, paper = (kinematics(dataclasses.replace(task, kinematics=k)) for k in ("exact", "paper"))
    assert exact.status is Status.SOLVED and "no dynamics solved" in exact.message
    a_exact, a_paper = (r.arrays["slider_acceleration_m_s2"] for r in (exact, paper))
    peak = np.max(np.abs(a_exact))
    assert np.max(np.abs(a_exact - a_paper)) / peak < 2 * task.rod_ratio**3


def test_a_sample_count_out_of_range_is_a_setting_error(task):
    with pytest.raises(SettingError, match=r"samples=2: allowed 3 \.\.\. 1,000,000"):
        registry.run("press/kd2322-kinematics", {"samples": 2})
