"""The machine's speed co-designed with the lift cam's synthesised law."""
import dataclasses

import pytest

from mechopt import registry
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Status
from mechopt.solvers.loom.codesign import codesign_machine_speed
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.synthesis import law_of


@pytest.fixture(scope="module")
def machine():
    return registry.find("loom/machine-speed-codesign").build()[0]


@pytest.fixture(scope="module")
def coarse(machine):
    """A coarse co-design (few coefficients, a loose bracket): what it shows holds at any setting."""
    return codesign_machine_speed(machine, coefficients=8, sample_speeds=2, phase_from_deg=30.0, phase_to_deg=42.0,
                                  phase_tol_deg=1.0, max_acceleration_mm_per_rad2=570.0)


def test_the_codesigned_machine_is_no_slower_and_its_lift_keeps_the_limit_on_the_chain(machine, coarse):
    assert coarse.status is Status.SOLVED, coarse.message
    v = coarse.values
    assert v["speed_rpm"] >= v["speed_baseline_rpm"] * (1 - 1e-9)
    assert v["gain_percent"] == pytest.approx(100 * (v["speed_rpm"] / v["speed_baseline_rpm"] - 1))
    lever = dataclasses.replace(machine.lever_model, law=codesign_law(coarse))
    assert float(rebound_amplitude_mm(lever, v["speed_rpm"], v["t_3_7_deg"])) <= machine.amplitude_limit_mm * (1 + 1e-6)
    assert coarse.diagnostics["limiting_constraint"] != "-"


def codesign_law(result):
    return law_of(result)


def test_a_band_reaching_the_reference_speed_is_refused(machine):
    with pytest.raises(SettingError, match="band_low_rpm=500.*below speed_rpm"):
        codesign_machine_speed(machine, band_low_rpm=500.0)
