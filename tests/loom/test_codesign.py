"""The machine's speed co-designed with the lift cam's synthesised law."""
import dataclasses
import math
import sys
from pathlib import Path
from types import SimpleNamespace

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


BOX = dict(box_frequency_low=0.9, box_frequency_high=1.1, box_zeta_low=0.03, box_zeta_high=0.08, box_speed_margin=0.05)
ROBUST_SCENE = "loom/machine-speed-codesign-robust"


def designed_lever(machine, result, factor, zeta):
    """The re-planned machine's lift lever rebuilt here: the result's law, the lever at (factor, zeta)
    of the box (both natural frequencies times factor: E times its square), the scene's closure."""
    closure = {}
    if result.diagnostics.get("lift_closure") == "groove":
        closure = dict(closure="groove", backlash_mm=registry.find(ROBUST_SCENE).build()[1]["lift_backlash_mm"])
    return dataclasses.replace(machine.lever_model, law=codesign_law(result), E_GPa=machine.lever_model.E_GPa * factor**2,
                               damping_ratio=zeta, **closure)


def test_the_robust_scenes_machine_keeps_the_limit_on_a_finer_grid_of_the_box(machine, solved_once):
    """The chain (solvers/stop_impact/law.py) at the scene's re-planned t(3,7) on levers between the
    box's grid points (frequency x0.9 ... 1.1 in 5, zeta 0.03 ... 0.08 in 4) at speeds 180 rpm ... the
    machine's + 5 % every 10 rpm, not the co-design's own box check (its 3 x 3 grid, a speed where
    its linear model peaks); the roller stays on its cam there."""
    result = registry.run(ROBUST_SCENE).result
    assert result.status is Status.SOLVED, result.message
    v, limit = result.values, machine.amplitude_limit_mm
    speeds = np.r_[np.arange(180.0, v["speed_rpm"] * 1.05, 10.0), v["speed_rpm"] * 1.05]
    worst = (-1.0, None)
    for factor in np.linspace(0.9, 1.1, 5):
        for zeta in np.linspace(0.03, 0.08, 4):
            a = rebound_amplitude_mm(designed_lever(machine, result, factor, zeta), speeds, v["t_3_7_deg"],
                                     lost=np.nan)
            assert not np.isnan(a).any(), (factor, zeta, speeds[np.isnan(a)])
            worst = max(worst, (float(a.max()), (factor, zeta, float(speeds[np.argmax(a)]))), key=lambda w: w[0])
    assert worst[0] <= limit * (1 + 1e-6), worst
    assert worst[0] == pytest.approx(v["rebound_worst_box_mm"], rel=1e-6)    # the box's corner at its top speed
    at = result.diagnostics["rebound_worst_box_at"]
    assert (at["frequency_factor"], at["zeta"], at["speed_rpm"]) == pytest.approx(worst[1])


def test_the_box_speed_is_the_least_of_each_levers_own_highest_speed():
    """The engine's box option on loom/machine-speed (the cycloid): each lever's bound is t >= c_k
    (1 + margin) n, so the feasible speeds are nested and the machine on the whole box runs at the
    least of the machines each on one lever (run 5 % fast); the lever named as binding is that one."""
    from mechopt.solvers.cyclogram.speed import max_machine_speed
    from mechopt.solvers.stop_impact.lever_box import LeverBox
    machine = registry.find("loom/machine-speed").build()[0]
    scan = dict(scan_to_deg=56.0, scan_step_deg=0.5)       # coarse: a short walk per lever (the scenes: 60, 0.25)
    whole = max_machine_speed(machine, **BOX, box_grid=2, **scan)
    assert whole.status is Status.SOLVED, whole.message
    own = {}
    for key in ((1.0, machine.lever_model.damping_ratio), (0.9, 0.03), (0.9, 0.08), (1.1, 0.03), (1.1, 0.08)):
        lever = {**machine.lever, "E_GPa": machine.lever_model.E_GPa * key[0] ** 2, "damping_ratio": key[1]}
        one = max_machine_speed(dataclasses.replace(machine, lever=lever), box=LeverBox(speed_margin=0.05), **scan)
        assert one.status is Status.SOLVED, one.message
        own[key] = one.values["max_speed_rpm"]
    least = min(own, key=own.get)
    assert whole.values["max_speed_rpm"] == pytest.approx(own[least], rel=1e-9)
    assert whole.values["max_speed_rpm"] < max(own.values())           # the box costs speed here
    binding = whole.diagnostics["amplitude_box"]["3->7"]
    assert (binding["frequency_factor"], binding["zeta"], binding["speed_factor"]) == (*least, 1.05)


def test_the_nominal_scenes_lift_is_set_by_the_rebound_with_the_backlash_in_the_groove(machine, solved_once):
    """loom/machine-speed-codesign, its figures by independent means, under both closure readings.
    Groove (the scene's): the lift's t(3,7) is where the chain, with the groove's backlash (its rise
    crosses to the other wall once before C meets its plate), reaches 0.1 mm: the hybrid model's
    rebound at t(3,7) is the limit and a hair below it exceeds it; the stress (the cycloid's x
    sqrt(Ca_law / 2 pi)) stays below. Force (its figure before): t(3,7) is the chain's contact edge
    (below it the roller leaves its cam, the 1500 N closure short), not 0.1 mm. Each speed is the
    critical chain's closed form with its t(3,7); the stress as calibrated (blind to the law) gives
    the scene's earlier 485.1005 rpm."""
    result = registry.run("loom/machine-speed-codesign").result
    v = result.values
    fixed = 900 * 30 / (800 * 420) + 0.36      # the returner's stress bound and the chain's other arcs [deg/rpm]
    assert v["speed_stress_given_rpm"] == pytest.approx(250 / (700 * 36 / 800 / 420 + fixed), rel=1e-9)
    law = codesign_law(result)
    for closure in ("groove", "force"):
        n, t37 = v[f"speed_closure_{closure}_rpm"], v[f"t_3_7_closure_{closure}_deg"]
        assert n == pytest.approx(250 / (t37 / n + fixed), rel=1e-9)
        assert 700 * 36 / t37 * n / 420 * v["stress_scale_lift"] < 800
    assert (v["speed_rpm"], v["t_3_7_deg"]) == (v["speed_closure_groove_rpm"], v["t_3_7_closure_groove_deg"])
    assert_the_groove_sets_t37_by_the_backlash(machine, result)
    force = dataclasses.replace(machine.lever_model, law=law)
    n, t37 = v["speed_closure_force_rpm"], v["t_3_7_closure_force_deg"]
    held = float(rebound_amplitude_mm(force, n, t37 * (1 + 1e-6), lost=np.nan))
    assert held <= machine.amplitude_limit_mm
    assert np.isnan(rebound_amplitude_mm(force, n, t37 * (1 - 1e-4), lost=np.nan))


def assert_the_groove_sets_t37_by_the_backlash(machine, result):
    """The hybrid model with the 0.05 mm backlash (solvers/stop_impact/groove.py, checked against a
    hand DOP853 in tests/stop_impact/test_groove.py) at the scene's speed and t(3,7): one crossing
    before C meets its plate, the rebound (eq. (2) closed form) at the limit, over it a hair below."""
    from mechopt.solvers.stop_impact.groove import rebound_with_backlash_mm
    v = result.values
    n, t37 = v["speed_rpm"], v["t_3_7_deg"]
    groove = dataclasses.replace(machine.lever_model, law=codesign_law(result), closure="groove", backlash_mm=0.05)
    at, rise = rebound_with_backlash_mm(groove, n, t37)
    assert len(rise.flights) == 1 and rise.flights[0][0] < rise.contact_xi
    assert at == pytest.approx(machine.amplitude_limit_mm, rel=1e-6)
    assert rebound_with_backlash_mm(groove, n, t37 * (1 - 1e-4))[0] > machine.amplitude_limit_mm


def test_the_geometry_scenes_law_keeps_its_cam_and_the_groove_sets_t37(machine, solved_once):
    """loom/machine-speed-codesign-geometry: the speed is the critical chain's closed form with its
    t(3,7); that t(3,7) is the groove's rebound with the backlash at the limit; the law's cam (its
    rise and mirrored return over t) keeps the 34 deg pressure angle and roller + 5 mm radius at
    t_min, where the synthesis held them, and is gentler at the re-planned t(3,7): by the
    independent pitch polygon of tests/stop_impact/test_cam_shape.py (the lever's positions alone)."""
    sys.path.insert(0, str(Path(__file__).parents[1] / "stop_impact"))
    from test_cam_shape import _polygon_checks
    scene = registry.find("loom/machine-speed-codesign-geometry")
    settings = scene.build()[1]
    result = registry.run(scene.id).result
    assert result.status is Status.SOLVED, result.message
    v = result.values
    fixed = 900 * 30 / (800 * 420) + 0.36
    assert v["speed_rpm"] == pytest.approx(250 / (v["t_3_7_deg"] / v["speed_rpm"] + fixed), rel=1e-9)
    assert v["t_3_7_deg"] > v["t_min_synthesized_deg"]
    assert_the_groove_sets_t37_by_the_backlash(machine, result)
    lever = machine.lever_model

    def cam(t_deg):
        return SimpleNamespace(base_radius_mm=settings["cam_base_radius_mm"],
                               roller_radius_mm=settings["cam_roller_radius_mm"],
                               centre_distance_mm=settings["cam_centre_distance_mm"], dwell_deg=settings["cam_dwell_deg"],
                               a_mm=lever.a_mm, b_mm=lever.b_mm, stroke_mm=lever.stroke_mm, rise_deg=t_deg,
                               return_deg=t_deg, law=codesign_law(result))
    (convex, concave, phi), (convex37, _, phi37) = (_polygon_checks(cam(t)) for t in (v["t_min_synthesized_deg"],
                                                                                      v["t_3_7_deg"]))
    assert phi == pytest.approx(v["max_pressure_angle_return_deg"], rel=1e-5)
    assert phi <= 34.0 + 0.1 and min(convex, concave) >= 20.0 - 0.01
    assert phi37 < phi and convex37 > convex
