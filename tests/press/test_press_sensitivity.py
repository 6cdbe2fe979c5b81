"""press.sensitivity: d(output)/d(parameter) through the periodic orbit by AD, held to central
differences of re-solves and to the energy balance (the equations are the model's own: one build)."""
import dataclasses

import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.solvers.press import sensitivity
from mechopt.solvers.press.sensitivity import OUTPUTS

PAPER, _ = registry.find("press/kd2322").build()


@pytest.fixture(scope="module")
def checked():
    return sensitivity(PAPER, tol=1e-12, verify_step=1e-3)


def test_every_derivative_matches_central_differences_of_re_solves(checked):
    assert checked.status is Status.SOLVED
    assert checked.values["ad_fd_mismatch"] < 1e-5          # elasticities: 1e-5 of the output per relative change
    for name in OUTPUTS:
        assert checked.arrays[f"elasticity_{name}"].shape == (len(checked.diagnostics["parameters"]),)


def test_the_orbit_is_the_steady_state_and_its_extremes_are_located_not_sampled(checked):
    from mechopt.solvers.press import steady_state
    dense = steady_state(PAPER, tol=1e-12, samples=3000)
    v, a = checked.values, dense.arrays
    assert v["speed_fluctuation"] == pytest.approx(dense.values["speed_fluctuation"], rel=1e-7)
    assert v["omega_mean_rad_s"] == pytest.approx(dense.values["omega_mean_rad_s"], rel=1e-10)
    sampled = dense.values["peak_belt_torque_Nm"]        # the largest sample, 0.07 deg apart: at most the peak
    assert sampled - 1e-9 <= v["peak_belt_torque_Nm"] <= sampled * (1 + 1e-6)
    slowest = np.degrees(a["phi_rad"][np.argmin(a["omega_rad_s"])]) % 360
    assert v["omega_min_deg"] == pytest.approx(slowest, abs=0.07)         # one sample spacing
    start, end = np.degrees(PAPER.cut_window_rad())
    assert not start <= v["omega_min_deg"] <= end                          # the slowest speed is outside the cut


def test_the_derivatives_obey_the_energy_balance_and_the_motor_law(checked):
    rows = checked.diagnostics["parameters"]
    d, e = checked.arrays, checked.arrays
    # the cut's work is eq. (1) over fixed crank angles: no assumed parameter moves it
    assert np.max(np.abs(d["d_cut_work_J"])) < 1e-7
    # motor work per turn = cut + 2 pi M_tr + belt damping work: d/dM_tr = 2 pi (damping work barely moves)
    assert d["d_motor_work_J"][rows.index("friction_torque_Nm")] == pytest.approx(2 * np.pi, rel=1e-4)
    # the mean speed is omega_sync (1 - s) / i, with a small slip that changes little
    assert e["elasticity_omega_mean_rad_s"][rows.index("motor_sync_speed_rad_s")] == pytest.approx(1.0, abs=0.01)
    assert e["elasticity_omega_mean_rad_s"][rows.index("gear_ratio")] == pytest.approx(-1.0, abs=0.01)


def test_the_slide_weight_and_the_rod_weight_reading_are_reported(checked):
    v = checked.values
    assert v["slide_weight_swing_J"] == pytest.approx(PAPER.tool_mass_kg * 9.81 * 0.05, rel=1e-12)   # m g H
    assert v["rod_weight_reading_spread"] == pytest.approx(v["speed_fluctuation_rod_weight_opposing"]
                                                           / v["speed_fluctuation"] - 1, rel=1e-12)
    assert -0.3 < v["rod_weight_reading_spread"] < -0.1


def test_a_stalled_press_has_no_orbit_to_differentiate():
    r = sensitivity(dataclasses.replace(PAPER, motor_breakdown_torque_Nm=0.5))
    assert r.status is Status.INFEASIBLE and r.violated == ("stall",)
    assert r.message.startswith("no periodic orbit to differentiate: the motor cannot deliver the cycle's work")


def test_without_the_motor_the_sensitivity_is_refused_naming_the_key():
    ideal = dataclasses.replace(PAPER, effects=tuple(e for e in PAPER.effects if e != "motor_characteristic"),
                                motor_sync_speed_rad_s=None, motor_breakdown_torque_Nm=None,
                                motor_breakdown_slip=None)
    with pytest.raises(ModelError, match=r"effects lack 'motor_characteristic'"):
        sensitivity(ideal)


def test_the_elasticities_figure_has_a_bar_per_parameter_and_a_panel_per_output_that_moves(checked, tmp_path):
    from mechopt.figures.press import elasticities
    from mechopt.registry import Run
    run = Run(registry.find("press/sensitivity"), checked, [], task=PAPER)
    fig = elasticities(run)["elasticities"]
    assert len(fig.axes) == len(OUTPUTS) - 1                       # the cut work moves with none of them
    bars = fig.axes[0].patches
    assert len(bars) == len(checked.diagnostics["parameters"])
    assert sorted(abs(b.get_width()) for b in bars) == pytest.approx(
        sorted(np.abs(checked.arrays["elasticity_speed_fluctuation"])), rel=1e-12)
    fig.savefig(tmp_path / "e.png")
    assert (tmp_path / "e.png").stat().st_size > 20_000
