"""Crank press model (paper 001): kinematics, the table's coefficients, J_k by AD, effects, bad input."""
import dataclasses

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mechopt import registry
from mechopt.kit.errors import ModelError
from mechopt.models.press import PressDrive
from mechopt.models.press_energy import crank_inertia, mean_crank_inertia_kgm2
from mechopt.models.press_equations import dynamics
from mechopt.models.press_laws import (
    coefficient_b,
    coefficient_d,
    coefficient_k,
    cutting_force_N,
    kloss_torque_Nm,
    rod_middle_m,
    travel_m,
)

PAPER, _ = registry.find("press/kd2322").build()
EQ1 = (1075.68, -406.8, -4.0, 90.93)           # eq. (1): c1 .. c4, N / mm^k


def _task(**changes):
    fields = {f.name: getattr(PAPER, f.name) for f in dataclasses.fields(PAPER)}
    return PressDrive(**(fields | changes))


def _without(effect, **changes):
    drop = {k: None for k in PressDrive.EFFECTS[effect].params}
    return _task(effects=tuple(e for e in PAPER.effects if e != effect), **(drop | changes))


# --- kinematics and the table ------------------------------------------------------------------

def test_paper_travel_is_within_r_lambda_cubed_over_8_of_the_exact_crank_slider():
    r, lam = 0.025, 0.071
    phi = np.linspace(0, 2 * np.pi, 2001)
    l = r / lam
    exact = (r + l) - (r * np.cos(phi) + np.sqrt(l**2 - (r * np.sin(phi)) ** 2))   # law of cosines, from TDC
    assert np.max(np.abs(travel_m(phi, r, lam, "exact") - exact)) < 1e-15
    gap = np.abs(travel_m(phi, r, lam, "paper") - exact)
    assert gap.max() <= r * lam**3 / 8 * 1.01 and gap.max() > r * lam**3 / 8 * 0.9    # the neglected term


@given(phi=st.floats(-7.0, 7.0), lam=st.floats(0.01, 0.5))
def test_table_b_is_the_paper_travels_derivative_over_r(phi, lam):
    h = 1e-6
    numeric = (travel_m(phi + h, 1.0, lam) - travel_m(phi - h, 1.0, lam)) / (2 * h)
    assert coefficient_b(phi, lam) == pytest.approx(numeric, abs=1e-8)


@given(phi=st.floats(-7.0, 7.0), lam=st.floats(0.01, 0.5))
def test_d_is_the_rod_middles_vertical_velocity_ratio_and_k_its_squared_angular_ratio(phi, lam):
    h = 1e-6
    y = lambda p: rod_middle_m(p, 1.0, lam)[1]
    assert coefficient_d(phi, lam) == pytest.approx((y(phi + h) - y(phi - h)) / (2 * h), abs=1e-8)
    beta = lambda p: np.arcsin(lam * np.sin(p))          # rod angle of the exact mechanism
    rate = (beta(phi + h) - beta(phi - h)) / (2 * h)
    assert coefficient_k(phi, lam) == pytest.approx(rate**2, abs=2 * lam**4)   # lambda << 1 form


def test_inertia_by_ad_equals_table_row_1_with_d_read_as_a_velocity_ratio():
    J, dJ = crank_inertia(PAPER)
    phi = np.linspace(0, 2 * np.pi, 37)
    r, lam = PAPER.r_m, PAPER.rod_ratio
    table = (r**2 * (PAPER.crank_mass_kg + PAPER.tool_mass_kg * coefficient_b(phi, lam) ** 2
                     + PAPER.rod_mass_kg * (coefficient_d(phi, lam) ** 2 + np.cos(phi) ** 2 / 4))
             + PAPER.flywheel_inertia_kgm2)
    got = np.asarray(J(phi.reshape(1, -1))).ravel()
    assert np.max(np.abs(got - table)) < 1e-14
    h = 1e-6
    fd = (np.asarray(J((phi + h).reshape(1, -1))) - np.asarray(J((phi - h).reshape(1, -1)))).ravel() / (2 * h)
    assert np.max(np.abs(np.asarray(dJ(phi.reshape(1, -1))).ravel() - fd)) < 1e-9


def test_mean_inertia_is_the_average_over_a_revolution():
    J, _ = crank_inertia(PAPER)
    dense = np.linspace(0, 2 * np.pi, 100001)
    assert mean_crank_inertia_kgm2(PAPER) == pytest.approx(np.trapezoid(np.asarray(J(dense.reshape(1, -1))).ravel(),
                                                                        dense) / (2 * np.pi), rel=1e-12)


def test_cut_window_matches_the_closed_form_of_the_papers_travel():
    # X / r = 1 - c + lambda/2 (1 - c^2), c = cos(phi): a quadratic in c
    r, lam = 25.0, 0.071

    def angle(x_mm):
        xi = x_mm / r
        c = (-1 + np.sqrt(1 - 2 * lam * (xi - 1 - lam / 2))) / lam
        return np.degrees(np.arccos(c))

    start, end = np.degrees(PAPER.cut_window_rad())
    assert start == pytest.approx(angle(50 - 3 - 1), abs=1e-9) and end == pytest.approx(angle(50 - 1), abs=1e-9)
    assert (start, end) == pytest.approx((145.98495, 163.13946), abs=1e-5)


def test_eq1_peaks_at_the_blank_thickness_with_the_published_coefficients():
    x = np.linspace(0, 3, 30001)
    f = cutting_force_N(x, *EQ1)
    assert np.all(np.diff(f) > 0)                                       # increasing on [0, 3] mm
    assert f[-1] == pytest.approx(90.93 * 81 - 4 * 27 - 406.8 * 9 + 1075.68 * 3, rel=1e-15)
    assert f[-1] == pytest.approx(6823.17, abs=1e-9)


def test_kloss_characteristic_peaks_at_the_breakdown_slip_and_vanishes_at_synchronous_speed():
    s = np.linspace(0, 1, 10001)
    m = kloss_torque_Nm(s, 43.0, 0.2)
    assert m[0] == 0 and s[np.argmax(m)] == pytest.approx(0.2, abs=1e-4) and m.max() == pytest.approx(43.0, rel=1e-6)
    assert kloss_torque_Nm(1.0, 43.0, 0.2) == pytest.approx(2 * 43 / (1 / 0.2 + 0.2))   # starting torque


# --- effects: the model is assembled from the listed ones only -----------------------------------

@pytest.mark.parametrize("drop, states", [
    ((), ("twist_rad", "omega_p_rad_s", "phi_rad", "omega_rad_s")),
    (("belt_elasticity",), ("phi_rad", "omega_rad_s")),
    (("motor_characteristic",), ("twist_rad", "phi_rad", "omega_rad_s")),
])
def test_states_follow_the_effects(drop, states):
    task = PAPER
    for effect in drop:
        task = _without(effect) if task is PAPER else task
    assert task.state_names == states
    assert dynamics(task).n_states == len(states)


def test_an_unlisted_effect_adds_no_term():
    x = ca.SX.sym("x", 8)
    mode = ca.SX.sym("mode", 3)
    for effect, symbol in (("cutting_force", mode[0]), ("friction", mode[1])):
        rhs = dynamics(_without(effect)).rhs(x, mode)
        assert not ca.depends_on(rhs, symbol), effect
        assert ca.depends_on(dynamics(PAPER).rhs(x, mode), symbol), effect
    phi = x[2]
    bare = _task(effects=("belt_elasticity", "motor_characteristic"), gravity_m_s2=None, friction_torque_Nm=None,
                 **{k: None for k in PressDrive.EFFECTS["cutting_force"].params})
    assert not ca.depends_on(dynamics(bare).rhs(x, mode)[:4], phi)       # constant J, no weights: phi-free
    varying = _task(effects=("belt_elasticity", "motor_characteristic", "variable_inertia"), gravity_m_s2=None,
                    friction_torque_Nm=None, **{k: None for k in PressDrive.EFFECTS["cutting_force"].params})
    assert ca.depends_on(dynamics(varying).rhs(x, mode)[:4], phi)


def test_gravity_moment_is_minus_the_derivative_of_the_weights_potential():
    dyn = dynamics(PAPER)
    x = np.array([0.0, 0.0, 1.0, 0.0, 0, 0, 0, 0])
    h = 1e-6
    V = lambda p: float(dyn.outputs(np.r_[0, 0, p, 0, 0, 0, 0, 0], [0, 0, 1])[7])
    moment = float(dyn.outputs(x, [0, 0, 1])[8])          # drive torque at rest, untwisted belt: weights only
    assert moment == pytest.approx(-(V(1 + h) - V(1 - h)) / (2 * h), rel=1e-7)
    assert moment > 0       # on the way down both weights help


# --- bad input: refused with the key, the value and what is allowed -----------------------------

@pytest.mark.parametrize("changes, match", [
    ({"rod_ratio": 1.0}, r"^rod_ratio=1\.0: allowed > 0 \.\.\. 1 \(excl\.\)$"),
    ({"rod_ratio": -0.1}, r"rod_ratio=-0\.1: allowed > 0 \.\.\. 1 \(excl\.\)"),
    ({"tool_mass_kg": -1.0}, r"tool_mass_kg=-1\.0: allowed 0 \.\.\. 100,000"),
    ({"rod_mass_kg": -6.0}, r"rod_mass_kg=-6\.0: allowed 0 \.\.\. 100,000"),
    ({"belt_stiffness_Nm_rad": -2e4}, r"belt_stiffness_Nm_rad=-20000\.0: allowed 0 \.\.\. 1e\+12"),
    ({"belt_stiffness_Nm_rad": 0.0}, r"belt_stiffness_Nm_rad=0\.0: allowed > 0 with effect 'belt_elasticity' \(an elastic belt\)"),
    ({"belt_damping_Nms_rad": -1.0}, r"belt_damping_Nms_rad=-1\.0: allowed 0 \.\.\. 1e\+06"),
    ({"blank_thickness_mm": 49.5}, r"blank_thickness_mm=49\.5 plus shortfall_mm=1\.0 is 50\.5 mm, more than the "
                                   r"stroke H = 2 crank_radius_mm = 50\.0 mm"),
    ({"crank_radius_mm": 0.0}, r"crank_radius_mm=0\.0: allowed > 0 \.\.\. 1,000"),
    ({"gear_ratio": 0.0}, r"gear_ratio=0\.0: allowed > 0 \.\.\. 1,000"),
    ({"motor_breakdown_slip": 1.5}, r"motor_breakdown_slip=1\.5: allowed > 0 \.\.\. 1 \(excl\.\)"),
    ({"motor_breakdown_torque_Nm": 0.0}, r"motor_breakdown_torque_Nm=0\.0: allowed > 0 \.\.\. 1e\+06"),
    ({"motor_inertia_kgm2": 0.0}, r"motor_inertia_kgm2=0\.0: allowed > 0 with an elastic belt"),
    ({"flywheel_inertia_kgm2": 0.0, "crank_mass_kg": 0.0}, r"flywheel_inertia_kgm2=0\.0, intermediate_inertia_kgm2 and crank_mass_kg are all 0"),
    ({"effects": ("belt_elasticity", "wind")},
     r"effects=\['belt_elasticity', 'wind'\]: unknown \['wind'\]; known: belt_elast"),
    ({"kinematics": "approx"}, r"kinematics='approx': allowed paper, exact"),
])
def test_bad_input_is_refused_naming_the_key(changes, match):
    with pytest.raises(ModelError, match=match):
        _task(**changes)


def test_effect_parameters_must_match_the_effects():
    with pytest.raises(ModelError, match=r"friction_torque_Nm=5\.0 belongs to effect 'friction', which is not listed"):
        _task(effects=tuple(e for e in PAPER.effects if e != "friction"))
    with pytest.raises(ModelError, match=r"friction_torque_Nm missing: effect 'friction' needs it"):
        _task(friction_torque_Nm=None)
    # a rigid ideal drive (no belt, no motor) is a press for kinematics and kinetostatics: built, but every
    # dynamic method refuses it, naming what to add or the solver that takes it
    rigid = _task(effects=("gravity",), belt_stiffness_Nm_rad=None, belt_damping_Nms_rad=None, friction_torque_Nm=None,
                  motor_sync_speed_rad_s=None, motor_breakdown_torque_Nm=None, motor_breakdown_slip=None,
                  **{k: None for k in PressDrive.EFFECTS["cutting_force"].params})
    from mechopt.solvers.press import events
    with pytest.raises(ModelError, match=r"lack 'belt_elasticity', 'motor_characteristic' and 'constant_torque_motor'"
                                         r".*use solver press\.kinematics"):
        events(rigid, duration_s=0.1)


def test_a_refused_scene_override_names_the_key_and_changes_nothing():
    from mechopt.kit.errors import SceneError
    scene = registry.find("press/kd2322")
    before = scene.params()
    with pytest.raises(SceneError, match=r"params\.rod_ratio=1\.2: allowed > 0 \.\.\. 1 \(excl\.\)"):
        scene.build({"rod_ratio": 1.2})
    assert scene.params() == before


@settings(max_examples=30, deadline=None)
@given(phi=st.floats(0.0, np.pi), lam=st.floats(0.01, 0.9))
def test_exact_travel_stays_within_the_stroke(phi, lam):
    x = travel_m(phi, 0.025, lam, "exact")
    assert -1e-15 <= x <= 0.05 + 1e-15


@pytest.mark.parametrize("scene_id", ["press/kd2322", "press/kd2322-rigid-belt", "press/start-up"])
def test_scene_hands_its_effects_to_the_task(scene_id):
    scene = registry.find(scene_id)
    assert scene.build()[0].effects == tuple(scene.spec.effects)


@pytest.mark.parametrize("changes, match", [
    ({"crank_radius_mm": float("inf")}, r"crank_radius_mm=inf: expected a finite number"),
    ({"belt_stiffness_Nm_rad": 1e13}, r"belt_stiffness_Nm_rad=10000000000000\.0: allowed 0 \.\.\. 1e\+12"),
    ({"force_c4_N_mm4": -float("inf")}, r"force_c4_N_mm4=-inf: expected a finite number"),
    ({"motor_breakdown_torque_Nm": 1e300}, r"motor_breakdown_torque_Nm=1e\+300: allowed > 0 \.\.\. 1e\+06"),
    ({"flywheel_inertia_kgm2": float("nan")}, r"flywheel_inertia_kgm2=nan: expected a finite number"),
    ({"nominal_speed_rad_s": 1e6}, r"nominal_speed_rad_s=1000000\.0: allowed > 0 \.\.\. 1,000"),
])
def test_infinite_or_huge_parameters_are_refused_naming_the_range(changes, match):
    with pytest.raises(ModelError, match=match):
        _task(**changes)


def test_mean_load_torque_and_breakdown_torque_at_the_crank():
    from mechopt.models.press_energy import breakdown_torque_at_crank_Nm, cut_work_J, required_mean_torque_Nm
    work = (90.93 * 3**5 / 5 - 4 * 3**4 / 4 - 406.8 * 3**3 / 3 + 1075.68 * 3**2 / 2) / 1000   # integral of eq. (1)
    assert cut_work_J(PAPER) == pytest.approx(work, rel=1e-12)
    assert required_mean_torque_Nm(PAPER) == pytest.approx(work / (2 * np.pi) + 5.0, rel=1e-12)
    assert breakdown_torque_at_crank_Nm(PAPER) == pytest.approx(6.2608 * 33.0, rel=1e-12)


def test_belt_mode_is_the_two_inertia_eigenfrequency():
    from scipy.linalg import eigh

    from mechopt.models.press_energy import belt_mode_rad_s, mean_crank_inertia_kgm2
    k = PAPER.belt_stiffness_Nm_rad
    M = np.diag([PAPER.motor_inertia_kgm2 * PAPER.gear_ratio**2, mean_crank_inertia_kgm2(PAPER)])
    squares = eigh(k * np.array([[1.0, -1.0], [-1.0, 1.0]]), M, eigvals_only=True)   # 0 (rigid turning) and the mode
    assert belt_mode_rad_s(PAPER) == pytest.approx(np.sqrt(squares.max()), rel=1e-12)
    assert belt_mode_rad_s(PAPER) / (2 * np.pi) == pytest.approx(59.0, abs=0.1)        # the scene's "59 Hz"
