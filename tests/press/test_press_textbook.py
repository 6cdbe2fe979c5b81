"""Textbook presses posed from scene files: the loads (`constant_load`), the drives (a constant-torque
motor, flywheels on the motor and an intermediate shaft, the rigid ideal drive for kinetostatics) and
the values at chosen crank angles, each against an independent computation."""
import dataclasses

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from mechopt import registry
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.press import PressDrive
from mechopt.models.press_energy import crank_inertia, energy_swing_J, potential_J
from mechopt.solvers import press as pd
from mechopt.solvers.press.kinematics import kinetostatics

PAPER, _ = registry.find("press/kd2322").build()


def _exact_dX(phi, r, lam):
    """dX/dphi of the exact crank-slider, written out here (not the package's)."""
    s, c = np.sin(phi), np.cos(phi)
    return r * s + r * lam * s * c / np.sqrt(1 - (lam * s) ** 2)


def test_force_reading_energy_swing_by_independent_integration():
    """press/textbook-punch-force: a constant force F = E / 30 mm over the last 30 mm of a 100 mm stroke
    against the motor's mean torque M = E / 2 pi. The surplus M phi - W(phi) peaks where the punch
    starts (a) and bottoms where F X'(phi) falls back to M (inside the window, before bottom dead
    centre): Delta E = integral over [a, phi*] of (F X' - M), by quadrature of the written-out X'."""
    task, _ = registry.find("press/textbook-punch-force").build()
    E, r, lam = 22608.0, 0.05, 0.2
    F, M = E / 0.030, E / (2 * np.pi)
    a = np.radians(107.98064201085721)
    bottom = brentq(lambda p: F * _exact_dX(p, r, lam) - M, np.pi / 2 + 0.3, np.pi - 1e-9, xtol=1e-14)
    swing, _ = quad(lambda p: F * _exact_dX(p, r, lam) - M, a, bottom, epsabs=1e-10, epsrel=1e-12)
    assert task.load.force_N == pytest.approx(F, rel=1e-9)
    assert energy_swing_J(task) == pytest.approx(swing, rel=1e-6)
    run = pd.events(task, duration_s=10.5, max_step_s=0.05, samples=16)
    assert run.status is Status.SOLVED
    assert run.values["energy_swing_J"] == pytest.approx(swing, rel=1e-6)
    assert run.values["cut_work_J"] == pytest.approx(E, rel=1e-7)            # one punch: F x 30 mm
    # the book's reading (constant torque over 0.15 of the turn) gives up 19216.8 J: 5 % more
    assert swing == pytest.approx(18300.0, abs=1.0)


@pytest.mark.parametrize("scene", ["press/sarkar-punch", "press/textbook-punch"])
def test_rule_of_thumb_flywheel_against_the_simulated_one(scene):
    """Where the rule holds (a constant-torque motor, a constant inertia: no slide or rod mass), the
    flywheel I = Delta E / (C_s omega^2) is the simulated one exactly when omega is the mean of the
    extremes, (omega_max + omega_min) / 2: 1/2 I (w1^2 - w2^2) = I (w1 - w2) (w1 + w2) / 2. The
    reported rule takes the crank's time-mean speed instead (2 pi / period), which the punch's slow
    stretch pulls below the mean of the extremes: a gap of order C_s^2."""
    task, settings = registry.find(scene).build()
    run = pd.events(task, **settings)
    v = run.values
    middle = (v["omega_max_rad_s"] + v["omega_min_rad_s"]) / 2
    exact = v["energy_swing_J"] / ((v["omega_max_rad_s"] - v["omega_min_rad_s"]) * middle)
    assert exact == pytest.approx(v["inertia_at_crank_kgm2"], rel=1e-7)
    gap = v["inertia_rule_of_thumb_at_crank_kgm2"] / v["inertia_at_crank_kgm2"] - 1
    assert abs(gap) < (v["speed_fluctuation"] ** 2)
    assert gap == pytest.approx((middle / v["omega_mean_rad_s"]) ** 2 - 1, abs=1e-7)


def test_published_figures_of_the_textbook_scenes():
    """The books' figures (scene expectations, restated): power, energy swing, the least flywheel speed."""
    task, settings = registry.find("press/sarkar-punch").build()
    v = pd.events(task, **settings).values
    assert v["motor_mean_power_W"] == pytest.approx(3000.0, rel=1e-4)
    assert v["energy_swing_J"] == pytest.approx(9000.0, rel=1e-9)
    assert v["intermediate_omega_min_rad_s"] * 30 / np.pi == pytest.approx(200.0, rel=1e-4)
    task, settings = registry.find("press/textbook-punch").build()
    v = pd.events(task, **settings).values
    assert v["motor_mean_power_W"] == pytest.approx(2260.8, rel=1e-4)
    assert v["energy_swing_J"] == pytest.approx(19216.8, rel=1e-9)
    assert v["intermediate_omega_min_rad_s"] * 0.5 == pytest.approx(26.0, rel=1e-6)     # m/s at k = 0.5 m


RIGID = dataclasses.replace(PAPER, effects=tuple(e for e in PAPER.effects if e != "belt_elasticity"),
                            belt_stiffness_Nm_rad=None, belt_damping_Nms_rad=None)


def test_flywheel_on_the_motor_or_an_intermediate_shaft_equals_it_reduced_to_the_crank():
    """The KD2322's 5 kg m2 flywheel on the crank, then on the motor shaft as 5 / i^2, then on an
    intermediate shaft at 3 times the crank's speed as 5 / 9: the same periodic motion."""
    i = RIGID.gear_ratio
    runs = [pd.steady_state(task) for task in (
        RIGID,
        dataclasses.replace(RIGID, flywheel_inertia_kgm2=0.0, motor_flywheel_inertia_kgm2=5.0 / i**2),
        dataclasses.replace(RIGID, flywheel_inertia_kgm2=0.0, intermediate_inertia_kgm2=5.0 / 9, intermediate_ratio=3.0))]
    for run in runs:
        assert run.status is Status.SOLVED, run.message
    for key in ("omega_mean_rad_s", "speed_fluctuation", "period_s", "motor_work_J"):
        assert runs[1].values[key] == pytest.approx(runs[0].values[key], rel=1e-8)
        assert runs[2].values[key] == pytest.approx(runs[0].values[key], rel=1e-8)


# KD2322's cut as a constant force of the same work over the same travel (46 to 49 mm)
CONSTANT = dataclasses.replace(
    PAPER, effects=tuple(e for e in PAPER.effects if e != "cutting_force") + ("constant_load",),
    **{k: None for k in PressDrive.EFFECTS["cutting_force"].params}, force_fit_max_mm=None,
    load_from_mm=46.0, load_to_mm=49.0, load_energy_J=5.517558)


def test_a_constant_load_runs_in_every_method_with_its_work_per_stroke():
    assert CONSTANT.load.force_N == pytest.approx(5.517558 / 0.003, rel=1e-12)
    assert np.degrees(CONSTANT.cut_window_rad()) == pytest.approx([145.98495, 163.13946], abs=1e-4)
    steady = pd.steady_state(CONSTANT)
    assert steady.status is Status.SOLVED, steady.message
    assert steady.values["cut_work_J"] == pytest.approx(5.517558, rel=1e-9)
    period = steady.values["period_s"]
    events = pd.events(CONSTANT, duration_s=period * 1.001)
    assert events.status is Status.SOLVED
    assert events.values["cut_work_J"] == pytest.approx(5.517558, rel=1e-9)
    assert events.values["energy_residual"] < 1e-6
    for other in (pd.rk4(CONSTANT, duration_s=0.252, step_s=1e-4),
                  pd.ivp(CONSTANT, duration_s=period * 1.001)):
        assert other.status in (Status.SOLVED, Status.INACCURATE), other.message
        assert other.values["cut_work_J"] == pytest.approx(5.517558, rel=1e-3)


def test_a_constant_torque_motor_is_refused_where_one_periodic_motion_is_needed():
    task, _ = registry.find("press/sarkar-punch").build()
    for solver in (pd.steady_state, pd.sensitivity):
        with pytest.raises(ModelError, match=r"constant_torque_motor.*sets no speed level.*events, rk4 or ivp"):
            solver(task)


@pytest.mark.parametrize("changes, match", [
    ({"load_from_mm": 1.0}, r"give the load's interval once"),
    ({"load_from_deg": 100.0, "load_to_deg": 50.0}, r"load_to_deg=50: allowed > load_from_deg=100"),
    ({"load_torque_Nm": 5.0}, r"give one of load_force_N, load_torque_Nm, load_energy_J"),
    ({"load_shape": "constant_force", "load_to_deg": 200.0}, r"load_to_deg=200: allowed <= 180 for a force"),
    ({"motor_torque_Nm": None, "effects": ("constant_load",)}, None),
])
def test_bad_loads_are_refused_naming_the_key(changes, match):
    task, _ = registry.find("press/sarkar-punch").build()
    if match is None:            # no motor: built (a rigid ideal drive), but no dynamic run
        rigid = dataclasses.replace(task, **changes)
        with pytest.raises(ModelError, match=r"use solver press\.kinematics"):
            pd.events(rigid, duration_s=1.0)
        return
    with pytest.raises(ModelError, match=match):
        dataclasses.replace(task, **changes)


def test_energy_per_stroke_shapes():
    task, _ = registry.find("press/sarkar-punch").build()
    assert task.load.torque_Nm == pytest.approx(15000 / np.radians(144), rel=1e-12)
    assert task.motor_torque_at_shaft_Nm() == pytest.approx(15000 / (2 * np.pi), rel=1e-12)


def test_kinetostatics_crank_torque_by_the_power_balance():
    """At a constant crank speed the torque the shaft gives the linkage is, by the power balance,
    1/2 dJ_k/dphi omega^2 (the linkage's kinetic energy) + F X' (the load) + dV/dphi (the weights):
    J_k by AD of the kinetic energy (models.press_energy.crank_inertia), V the potential, not the
    Newton-Euler joint forces the solver uses."""
    task = dataclasses.replace(PAPER, kinematics="exact", at_deg=(30.0, 150.0, 160.0, 300.0))
    result = pd.kinematics(task)
    _, dJ = crank_inertia(task)
    w = task.nominal_speed_rad_s
    for deg in task.at_deg:
        phi = np.radians(deg)
        h = 1e-6
        dV = (float(potential_J(task, phi + h)) - float(potential_J(task, phi - h))) / (2 * h)
        a = kinetostatics(task, np.array([phi]))
        load = a["load_force_N"][0] * (a["slider_velocity_m_s"][0] / w)
        expected = 0.5 * float(dJ(phi)) * w**2 + load + dV
        assert result.values[f"crank_torque_Nm_{deg:g}"] == pytest.approx(expected, rel=1e-6, abs=1e-6)
    # over a turn the drive gives the cut's work and the friction's, no more (trapezoid on 3601 samples)
    expected_work = 5.517558 + 2 * np.pi * task.friction_torque_Nm
    assert result.values["input_work_per_turn_J"] == pytest.approx(expected_work, rel=2e-3)


def test_values_at_crank_angles_against_the_closed_form():
    """Slider speed and acceleration, rod rates at 90 deg: omega r, -omega^2 r lambda / sqrt(1 - lambda^2)
    (exact crank-slider; u = lambda), beta' = 0, beta'' = -omega^2 lambda / sqrt(1 - lambda^2)."""
    task = dataclasses.replace(PAPER, kinematics="exact", at_deg=(90.0,))
    v = pd.kinematics(task).values
    w, r, lam = task.nominal_speed_rad_s, task.r_m, task.rod_ratio
    assert v["slider_velocity_m_s_90"] == pytest.approx(w * r, rel=1e-12)
    assert v["slider_acceleration_m_s2_90"] == pytest.approx(-w**2 * r * lam / np.sqrt(1 - lam**2), rel=1e-12)
    assert v["rod_angular_velocity_rad_s_90"] == pytest.approx(0.0, abs=1e-12)
    assert v["rod_angular_acceleration_rad_s2_90"] == pytest.approx(-w**2 * lam / np.sqrt(1 - lam**2), rel=1e-12)
    with pytest.raises(ModelError, match=r"at_deg=\[400\.0\]: allowed crank angles in \[0, 360\]"):
        dataclasses.replace(PAPER, at_deg=(400.0,))


def test_textbook_kinetostatics_at_chosen_angles():
    """press/textbook-punch-kinetostatics: no masses, so the crank torque is F X'(phi) and the rod
    force F / cos(beta) inside the punch's window, zero outside; the drive gives F x 30 mm a turn."""
    task, settings = registry.find("press/textbook-punch-kinetostatics").build()
    v = pd.kinematics(task, **settings).values
    F, r, lam = 22608.0 / 0.030, 0.05, 0.2
    for deg in (120.0, 150.0, 175.0):
        phi = np.radians(deg)
        assert v[f"crank_torque_Nm_{deg:g}"] == pytest.approx(F * _exact_dX(phi, r, lam), rel=1e-12)
        assert v[f"rod_force_N_{deg:g}"] == pytest.approx(F / np.sqrt(1 - (lam * np.sin(phi)) ** 2), rel=1e-12)
    assert v["crank_torque_Nm_90"] == 0.0                  # before the punch
    assert v["input_work_per_turn_J"] == pytest.approx(22608.0, rel=1e-6)


def test_values_at_crank_angles_of_a_dynamic_run_against_the_energy_balance():
    """press/sarkar-punch asked at 72 and 200 deg: with a constant inertia I, 1/2 I (w0^2 - w^2) is the
    load's work minus the motor's from 0 to phi (no masses, so no kinetic energy elsewhere)."""
    task, settings = registry.find("press/sarkar-punch").build()
    task = dataclasses.replace(task, at_deg=(72.0, 200.0))
    v = pd.events(task, **(settings | {"samples": 400})).values
    I, w0 = task.intermediate_inertia_kgm2 * task.intermediate_ratio**2, task.nominal_speed_rad_s
    M_load, M_motor = task.load.torque_Nm, task.motor_torque_at_shaft_Nm()
    for deg, loaded in ((72.0, np.radians(72.0)), (200.0, np.radians(144.0))):
        w = np.sqrt(w0**2 - 2 * (M_load * loaded - M_motor * np.radians(deg)) / I)
        assert v[f"omega_rad_s_{deg:g}"] == pytest.approx(w, rel=1e-7)
    assert v["alpha_rad_s2_72"] == pytest.approx((M_motor - M_load) / I, rel=1e-9)


def test_a_force_table_from_a_csv_against_eq_1():
    """press/kd2322-force-table: eq. (1) every 0.25 mm as a CSV; the cut's work is the table's
    trapezoid (numpy's, on the file's rows), and the motion is press/kd2322's but for that work."""
    from pathlib import Path
    rows = np.loadtxt(Path(registry.find("press/kd2322-force-table").path).parent / "kd2322-force-table.csv",
                      delimiter=",", skiprows=1)
    task, settings = registry.find("press/kd2322-force-table").build()
    run = pd.steady_state(task, **settings)
    assert run.status is Status.SOLVED
    assert run.values["cut_work_J"] == pytest.approx(np.trapezoid(rows[:, 1], rows[:, 0]) / 1000, rel=1e-8)
    assert run.values["peak_force_N"] == pytest.approx(6823.17, rel=1e-9)          # the last row, eq. (1) at 3 mm
    paper = pd.steady_state(PAPER)
    assert run.values["speed_fluctuation"] == pytest.approx(paper.values["speed_fluctuation"], rel=2e-3)


def test_a_table_with_a_jump_stops_every_method_at_it():
    """A crank-angle table with a drop at 155 deg: the jump is an event of its own in events, ivp and
    steady_state (the cut's work to the integration's tolerance, against the by-parts closed form);
    rk4 crosses it (first order); the design's NLP and the sensitivity refuse it."""
    from mechopt.models.press_energy import cut_work_J
    table = ((146.0, 0.0), (155.0, 2000.0), (155.0, 500.0), (163.0, 800.0))
    task = dataclasses.replace(CONSTANT, load_from_mm=None, load_to_mm=None, load_energy_J=None, load_table=table)
    assert np.degrees(task.load.jumps_rad) == pytest.approx([155.0])
    # the work by quadrature of F(phi) X'(phi) on each side of the jump, X' written out here
    r, lam = task.r_m, task.rod_ratio
    dX = lambda p: r * (np.sin(p) + lam / 2 * np.sin(2 * p))             # noqa: E731  (the paper's X)
    force = lambda p, a0, a1, f0, f1: f0 + (f1 - f0) * (p - a0) / (a1 - a0)    # noqa: E731
    a, j, b = np.radians([146.0, 155.0, 163.0])
    work = quad(lambda p: force(p, a, j, 0.0, 2000.0) * dX(p), a, j, epsrel=1e-13)[0] \
        + quad(lambda p: force(p, j, b, 500.0, 800.0) * dX(p), j, b, epsrel=1e-13)[0]
    assert cut_work_J(task) == pytest.approx(work, rel=1e-10)
    steady = pd.steady_state(task)
    period = steady.values["period_s"] * 1.001
    for run in (steady, pd.events(task, duration_s=period), pd.ivp(task, duration_s=period)):
        assert run.status is Status.SOLVED, run.message
        assert run.values["cut_work_J"] == pytest.approx(work, rel=1e-7)
    assert any(e[0] == "load_jump" for e in pd.events(task, duration_s=period).diagnostics["events"])
    design_task, _ = registry.find("press/flywheel-design").build()
    jumpy = dataclasses.replace(design_task, effects=CONSTANT.effects, **{k: None for k in
                                PressDrive.EFFECTS["cutting_force"].params}, force_fit_max_mm=None, load_table=table)
    with pytest.raises(ModelError, match=r"load_table jumps at 155 deg and press\.design"):
        pd.design(jumpy)
    with pytest.raises(ModelError, match=r"load_table jumps at 155 deg and press\.sensitivity"):
        pd.sensitivity(task)


def test_a_constant_load_in_the_design_the_secant_and_the_sensitivity():
    """The constant force over the KD2322's cut travel in the methods above the simulators: the NLP and
    the secant find the same least flywheel (their extremes exact and sampled: to 1e-6), the
    sensitivity's orbit has steady_state's fluctuation."""
    design_task, _ = registry.find("press/flywheel-design").build()
    task = dataclasses.replace(design_task, effects=CONSTANT.effects, force_fit_max_mm=None,
                               **{k: None for k in PressDrive.EFFECTS["cutting_force"].params},
                               load_from_mm=46.0, load_to_mm=49.0, load_energy_J=5.517558)
    nlp, secant = pd.design(task), pd.flywheel(task)
    assert nlp.status is Status.SOLVED and secant.status is Status.SOLVED
    assert secant.values["flywheel_inertia_kgm2"] == pytest.approx(nlp.values["flywheel_inertia_kgm2"], rel=1e-6)
    sens = pd.sensitivity(CONSTANT)
    assert sens.status is Status.SOLVED
    assert sens.values["speed_fluctuation"] == pytest.approx(pd.steady_state(CONSTANT).values["speed_fluctuation"],
                                                             rel=1e-6)
