"""The machine's speed co-designed with the lift cam's synthesised law."""
import dataclasses
import math

import numpy as np
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


COARSE = dict(coefficients=8, sample_speeds=2, phase_from_deg=30.0, phase_to_deg=42.0, phase_tol_deg=1.0,
              max_acceleration_mm_per_rad2=570.0)


@pytest.fixture(scope="module")
def coarse(machine):
    """A coarse co-design (few coefficients, a loose bracket): what it shows holds at any setting."""
    return codesign_machine_speed(machine, **COARSE)


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


CA_CYCLOID = 2 * math.pi    # max |S''| of the cycloidal unit rise: Norton, Cam Design and Motion Control (2009), Table 3-2


def second_difference_peak(law, points=2001):
    """max |S''| of a law by central second differences of S alone (not its spline derivative)."""
    xi = np.linspace(0.0, 1.0, points)
    s = law.values(xi)[0]
    h = xi[1] - xi[0]
    return float(np.abs((s[2:] - 2 * s[1:-1] + s[:-2]) / h**2).max())


def test_the_lift_stress_is_the_cycloids_scaled_by_the_root_of_the_peak_accelerations(machine, coarse):
    """Hertz: sigma ~ sqrt(F), F ~ Ca / t^2, so the synthesised law's lift stress is the cycloid's
    times sqrt(Ca_law / Ca_cycloid); Ca_law here by differences of S, sigma by the model's formula."""
    v = coarse.values
    ca_law = second_difference_peak(codesign_law(coarse))
    assert v["ca_own"] == pytest.approx(CA_CYCLOID, rel=1e-9)
    assert v["ca_law"] == pytest.approx(ca_law, rel=1e-7)
    assert v["stress_scale_lift"] == pytest.approx(math.sqrt(ca_law / CA_CYCLOID), rel=1e-7)
    model = machine.stress_models["lift_cam"]           # sigma_ref t_ref / t (n / n_ref), times the scale
    expected = model["sigma_ref_MPa"] * model["t_ref_deg"] / v["t_3_7_deg"] * v["speed_rpm"] / machine.stress_speed_rpm
    assert v["sigma_3_7_MPa"] == pytest.approx(expected * v["stress_scale_lift"], rel=1e-9)


def test_both_stress_readings_are_planned_and_the_lower_stress_is_never_slower(machine, coarse):
    """The law's own stress is the cycloid's scaled down (Ca_law < 2 pi), so its bound is lower and
    its machine no slower; the machine taken is the law-shape reading's."""
    v = coarse.values
    assert v["stress_scale_lift"] < 1
    assert v["speed_stress_law_shape_rpm"] >= v["speed_stress_given_rpm"] * (1 - 1e-9)
    assert v["speed_rpm"] == v["speed_stress_law_shape_rpm"]
    given = codesign_machine_speed(machine, lift_stress="given", **COARSE)
    assert given.values["speed_rpm"] == pytest.approx(v["speed_stress_given_rpm"], rel=1e-12)
    with pytest.raises(SettingError, match="lift_stress"):
        codesign_machine_speed(machine, lift_stress="hertz", **COARSE)


BOX = dict(box_frequency_low=0.9, box_frequency_high=1.1, box_zeta_low=0.03, box_zeta_high=0.08, box_speed_margin=0.05,
           box_grid=2)
SCAN = dict(scan_to_deg=50.0, scan_step_deg=0.5)       # coarse: a short walk per lever (the scenes: 60, 0.25)


@pytest.fixture(scope="module")
def robust(machine):
    """A coarse robust co-design on the box's corners (grid 2)."""
    return codesign_machine_speed(machine, robust=True, **COARSE, **BOX, **SCAN)


def designed_machine(machine, result, factor=1.0, zeta=None):
    """The re-planned machine rebuilt here: the result's law, the lift's stress scaled, the lever at
    (factor, zeta) of the box (both frequencies times factor: E times its square)."""
    lever = {**machine.lever, "law": codesign_law(result)}
    if zeta is not None:
        lever |= {"E_GPa": machine.lever_model.E_GPa * factor**2, "damping_ratio": zeta}
    lift = machine.stress_models["lift_cam"]
    models = machine.stress_models | {"lift_cam": lift | {"sigma_ref_MPa": lift["sigma_ref_MPa"]
                                                         * result.values["stress_scale_lift"]}}
    return dataclasses.replace(machine, lever=lever, stress_models=models)


def test_the_robust_codesign_keeps_the_limit_on_a_finer_grid_of_the_box(machine, robust):
    """The chain (solvers/stop_impact/law.py) at the re-planned t(3,7) on levers between the box's
    corners and at speeds up to the machine's + 5 %, not the co-design's own box check."""
    assert robust.status is Status.SOLVED, robust.message
    v, limit = robust.values, machine.amplitude_limit_mm
    assert v["rebound_worst_box_mm"] <= limit * (1 + 1e-6)
    speeds = np.r_[np.arange(180.0, v["speed_rpm"] * 1.05, 15.0), v["speed_rpm"] * 1.05]
    worst = -1.0
    for factor in (0.9, 0.95, 1.0, 1.05, 1.1):
        for zeta in (0.03, 0.08):
            lever = designed_machine(machine, robust, factor, zeta).lever_model
            a = rebound_amplitude_mm(lever, speeds, v["t_3_7_deg"], lost=np.nan)
            assert not np.isnan(a).any(), (factor, zeta, speeds[np.isnan(a)])
            worst = max(worst, float(a.max()))
    assert worst <= limit * (1 + 1e-6)


def test_the_box_speed_is_the_least_of_each_levers_own_highest_speed(machine, robust):
    """Each lever's bound is t >= c_k (1 + margin) n: the feasible speeds are nested, so the machine on
    the whole box runs at the least of the machines each on one lever (run 5 % fast), and the lever
    the co-design names as binding is that one."""
    from mechopt.solvers.loom.speed import max_machine_speed
    from mechopt.solvers.stop_impact.lever_box import LeverBox
    own = {}
    for key in ((1.0, machine.lever_model.damping_ratio), (0.9, 0.03), (0.9, 0.08), (1.1, 0.03), (1.1, 0.08)):
        one = max_machine_speed(designed_machine(machine, robust, *key), box=LeverBox(speed_margin=0.05), **SCAN)
        assert one.status is Status.SOLVED, one.message
        own[key] = one.values["max_speed_rpm"]
    least = min(own, key=own.get)
    assert robust.values["speed_rpm"] == pytest.approx(own[least], rel=1e-9)
    binding = robust.diagnostics["box_binding"]
    if robust.diagnostics["lift_bound"].startswith("amplitude"):
        assert (binding["frequency_factor"], binding["zeta"]) == least
        assert binding["speed_rpm"] == pytest.approx(1.05 * robust.values["speed_rpm"])
