"""Check and repair after the LP (issue 14, part 4): the linearised optimum of group 1 against the
exact rebound (eq. (2) on the lever) and the exact contact stress, repaired by sequential LP.

Independent references: the root of the exact law a(t, 420 rpm) = 0.1 mm by brentq (not through
the LP); the stress root sigma_ref t_ref / [sigma_H] in closed form; the span as the longest path
with those bounds, relaxed by hand."""
import dataclasses
import itertools

import numpy as np
import pytest
from scipy.optimize import brentq

from mechopt import registry
from mechopt.models.errors import ModelError, SceneError
from mechopt.models.loom import lever_stop
from mechopt.solvers.loom import plan_cyclogram, repair_cyclogram
from mechopt.solvers.result import Status
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm

LIMIT_MM, SIGMA_H_MPA = 0.1, 800.0


@pytest.fixture(scope="module")
def task():
    scene = registry.find("loom/group1-repaired")
    return scene.build(registry._derived_params(scene))[0]


@pytest.fixture(scope="module")
def repaired(task):
    return repair_cyclogram(task, stress_form="linear", tol_mm=1e-9, tol_MPa=1e-6)


def exact_root_deg(lever_table, speed_rpm=420.0, limit_mm=LIMIT_MM):
    lever = lever_stop(lever_table)
    return brentq(lambda t: rebound_amplitude_mm(lever, speed_rpm, t) - limit_mm, 1.0, 300.0, xtol=1e-13)


def test_repaired_lift_angle_is_the_root_of_the_exact_rebound_law(task, repaired):
    assert repaired.status is Status.SOLVED
    root = exact_root_deg(task.lever)
    assert repaired.values["t_3_7_deg"] == pytest.approx(root, abs=1e-7)
    assert repaired.values["exact_amplitude_3_7_mm"] <= LIMIT_MM + 1e-9
    # the returner cam's exact bound, closed form: 900 * 30 / 800
    assert repaired.values["t_9_10_deg"] == pytest.approx(900.0 * 30.0 / SIGMA_H_MPA, abs=1e-7)
    assert repaired.values["exact_sigma_9_10_MPa"] <= SIGMA_H_MPA + 1e-6
    # longest path 1-3-7-8-9-10 with the exact bounds; the other chains are shorter by hand
    assert repaired.values["span_deg"] == pytest.approx(20 + root + 10 + 15 + 33.75, abs=1e-7)


def test_round_one_is_the_linear_lp_and_its_error_is_the_convexity_gap(task, repaired):
    lp = plan_cyclogram(task, stress_form="linear")
    first = repaired.diagnostics["rounds"][0]
    assert first["span_deg"] == pytest.approx(lp.values["span_deg"], abs=1e-9)
    t_lin = (task.amplitude_intercept_mm - LIMIT_MM) / -task.amplitude_slope_mm_per_deg
    # without preload a ~ n / t, so at the tangent's bound the exact law reads 0.1 t* / t_lin
    gap = LIMIT_MM * (exact_root_deg(task.lever) / t_lin - 1.0)
    assert repaired.values["linearisation_error_amplitude_3_7_mm"] == pytest.approx(gap, rel=1e-6)
    assert gap > 1e-4                                   # the tangent under-estimates: a real violation
    # the stress tangent at t_ref = 30: sigma = 900 (2 - t/30) = 800 at 33.33 deg, exactly 810 there
    assert repaired.values["linearisation_error_sigma_9_10_MPa"] == pytest.approx(10.0, abs=1e-9)


def test_rounds_converge_quadratically_and_bounds_only_tighten(repaired):
    rounds = repaired.diagnostics["rounds"]
    assert repaired.values["rounds"] == len(rounds) == 4
    for limit, value in (("amplitude[3->7]", LIMIT_MM), ("contact_stress[9->10]", SIGMA_H_MPA)):
        excess = [next(r["excess"] for r in rnd["limits"] if r["limit"] == limit) / value for rnd in rounds]
        t = [next(r["t_deg"] for r in rnd["limits"] if r["limit"] == limit) for rnd in rounds]
        assert all(b >= a for a, b in itertools.pairwise(t))                      # never loosened
        assert all(b <= 2.0 * a * a for a, b in itertools.pairwise(excess))  # Newton: relative excess squares
        assert excess[0] > 1e-3 and abs(excess[-1]) < 1e-12


def test_a_cap_on_rounds_reports_limit_and_what_is_broken(task):
    r = repair_cyclogram(task, max_rounds=1)
    assert r.status is Status.LIMIT
    assert set(r.violated) == {"amplitude[3->7]", "contact_stress[9->10]"}
    assert "not converged in 1 round" in r.message
    assert r.values["exact_amplitude_3_7_mm"] > LIMIT_MM


def test_exact_stress_form_repairs_the_amplitude_only(task):
    r = repair_cyclogram(task, stress_form="exact")
    assert r.status is Status.SOLVED and r.values["rounds"] == 3
    assert r.values["linearisation_error_sigma_9_10_MPa"] == pytest.approx(0.0, abs=1e-9)
    assert r.values["t_3_7_deg"] == pytest.approx(exact_root_deg(task.lever), abs=1e-7)


def test_a_conservative_linear_law_is_kept_and_reported_with_its_slack(task):
    r = repair_cyclogram(dataclasses.replace(task, amplitude_intercept_mm=0.25), stress_form="exact")
    assert r.status is Status.SOLVED and r.values["rounds"] == 1
    assert r.values["t_3_7_deg"] == pytest.approx(0.15 / -task.amplitude_slope_mm_per_deg, abs=1e-7)
    assert r.values["exact_amplitude_3_7_mm"] < LIMIT_MM


def test_lever_alone_converges_to_the_same_root_and_the_plain_lp_refuses_it(task):
    alone = dataclasses.replace(task, amplitude_slope_mm_per_deg=None, amplitude_intercept_mm=None)
    r = repair_cyclogram(alone, stress_form="exact")
    assert r.status is Status.SOLVED
    assert r.values["t_3_7_deg"] == pytest.approx(exact_root_deg(task.lever), abs=1e-7)
    with pytest.raises(ModelError, match="needs the linear amplitude law") as err:
        plan_cyclogram(alone)
    assert err.value.key == "amplitude_slope_mm_per_deg"


def test_a_window_the_repair_breaks_is_infeasible_with_its_round_and_chain(task):
    tight = dataclasses.replace(task, windows=[{"from": "3", "to": "7", "max_deg": 36.7}])
    r = repair_cyclogram(tight)
    assert r.status is Status.INFEASIBLE
    assert r.message.startswith("round 2: infeasible: conflicting chain")
    assert any("window" in v for v in r.violated) and len(r.diagnostics["rounds"]) == 1


def test_the_exact_law_needs_a_speed(task):
    with pytest.raises(ModelError, match="speed_rpm") as err:
        repair_cyclogram(dataclasses.replace(task, speed_rpm=None))
    assert err.value.key == "speed_rpm"


@pytest.mark.parametrize("override, match", [
    ({"lever.E_GPa.value": -1.0}, r"structure\.lever\.E_GPa: lever\.E_GPa=-1\.0 must be > 0"),
    ({"lever.colour": 1.0}, r"--set lever\.colour: no entry 'colour' here; there are effects, E_GPa"),
    ({"lever.mass_kg": {"value": 1.0, "mark": "assumed"}}, r"lever\.mass_kg: marked 'assumed' needs a 'why'"),
    ({"speed_rpm": 0.0}, r"speed_rpm=0\.0 must be a finite number > 0"),
])
def test_a_bad_lever_or_speed_is_one_error_naming_the_key(override, match):
    with pytest.raises(SceneError, match=match):
        registry.run(registry.find("loom/group1-repaired"), override)


def test_an_unknown_or_missing_lever_parameter_is_named(task):
    with pytest.raises(ModelError, match=r"lever: unknown colour; allowed: .*E_GPa") as err:
        lever_stop(task.lever | {"colour": 1.0})
    assert err.value.key == "lever"
    with pytest.raises(ModelError, match=r"lever: .*missing .*'mass_kg'"):
        lever_stop({k: v for k, v in task.lever.items() if k != "mass_kg"})


def test_lever_table_is_stop_impact_amplitude_law_s_lever(task):
    """The one copied table: every lever parameter equals stop-impact/amplitude-law's."""
    source = registry.find("stop-impact/amplitude-law").params()
    for key, entry in task.lever.items():
        if key != "effects":
            assert entry["value"] == source[key], key
    assert np.isclose(rebound_amplitude_mm(lever_stop(task.lever), 420.0, 35.0),
                      registry.run("stop-impact/amplitude-law").result.values["intercept_mm"] / 2, rtol=1e-9)


def test_at_another_speed_the_rebound_and_stress_scale_as_n_over_t(task):
    """At 300 rpm with the lever alone (the 420 rpm tangent would be kept: conservative there)."""
    slow = dataclasses.replace(task, speed_rpm=300.0, amplitude_slope_mm_per_deg=None, amplitude_intercept_mm=None)
    r = repair_cyclogram(slow, stress_form="exact")
    assert r.status is Status.SOLVED
    root = exact_root_deg(task.lever, 300.0)
    assert root == pytest.approx(exact_root_deg(task.lever) * 300 / 420, rel=1e-9)     # a = h(n / t)
    # the root 26.25 deg falls under the lift's [phi] = 30 deg, which then sets the angle
    assert r.values["t_3_7_deg"] == pytest.approx(30.0, abs=1e-9)
    assert r.values["exact_amplitude_3_7_mm"] == pytest.approx(LIMIT_MM * root / 30.0, rel=1e-9)
    # the returner's stress bound 33.75 deg at 420 rpm falls to 24.1 deg: its [phi] = 30 deg sets the angle
    assert r.values["t_9_10_deg"] == pytest.approx(30.0, abs=1e-9)
    assert r.values["exact_sigma_9_10_MPa"] == pytest.approx(900 * 30 / 30 * 300 / 420, rel=1e-9)
