"""Check and repair after the LP: the linearised optimum of group 1 against the
exact rebound (the lever's chain: cam -> approach velocity -> impact -> eq. (2)) and the exact
contact stress, repaired by sequential LP with a safeguard for the wavy law.

Independent references: the crossing of a(t, 420 rpm) = 0.1 mm found from a dense scan of the
chain (every 0.1 deg over the stated range) and brentq in its last over-limit cell, not through
the LP or its walk; the stress root sigma_ref t_ref / [sigma_H] in closed form; the span as the
longest path by hand. The convex case (Newton steps only, quadratic convergence) on the earlier
fitted lever (tests/stop_impact_fitted.py), whose a is proportional to n / t."""
import dataclasses
import itertools
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq
from stop_impact_fitted import FREE, J_A_FITTED_KGM2, LEVER

import mechopt.solvers.loom.repair as loom_solver
from mechopt import clear_caches, registry
from mechopt.kit.errors import ModelError, SceneError
from mechopt.kit.result import Status
from mechopt.models.loom_limits import lever_stop
from mechopt.solvers.cyclogram import plan_cyclogram
from mechopt.solvers.loom import repair_cyclogram
from mechopt.solvers.stop_impact.law import chain_rebounds_mm, rebound_amplitude_mm

LIMIT_MM, SIGMA_H_MPA = 0.1, 800.0
FITTED_LEVER = {k: v for k, v in LEVER.items() if k != "t_deg"} | {
    "inertia_A_kgm2": J_A_FITTED_KGM2, "damping_ratio": 0.05, "effects": list(FREE)}


@pytest.fixture(scope="module")
def task():
    scene = registry.find("loom/group1-repaired")
    return registry._pose(scene, {})[0]


@pytest.fixture(scope="module")
def repaired(task):
    return repair_cyclogram(task, stress_form="linear", tol_mm=1e-9, tol_MPa=1e-6)


@pytest.fixture(scope="module")
def dense_root(task):
    """The smallest t beyond which a(t, 420 rpm) <= 0.1 mm on [30, 60] deg, from a 0.1 deg scan."""
    lever = lever_stop(task.lever)
    t = np.round(np.arange(30.0, 60.0 + 1e-9, 0.1), 9)
    a = rebound_amplitude_mm(lever, 420.0, t, lost=np.inf)
    last = np.flatnonzero(a > LIMIT_MM)[-1]
    root = brentq(lambda x: float(rebound_amplitude_mm(lever, 420.0, x)) - LIMIT_MM, t[last], t[last + 1], xtol=1e-13)
    return root, t, a


def test_repaired_lift_angle_is_the_last_crossing_of_a_dense_scan(task, repaired, dense_root):
    root, t, a = dense_root
    assert repaired.status is Status.SOLVED
    assert repaired.values["t_3_7_deg"] == pytest.approx(root, abs=1e-7)
    assert np.all(a[t > root] <= LIMIT_MM) and np.any(a[t < root - 1.0] > LIMIT_MM)   # wavy: over before, under after
    assert repaired.values["exact_amplitude_3_7_mm"] <= LIMIT_MM + 1e-9
    assert repaired.values["amplitude_holds_from_3_7_deg"] == pytest.approx(root, abs=1e-7)
    assert repaired.values["amplitude_holds_to_3_7_deg"] == 60.0
    assert "a <= limit for every t in [38.6655398, 60] deg at 420 rpm" in repaired.message
    # the returner cam's exact bound, closed form: 900 * 30 / 800
    assert repaired.values["t_9_10_deg"] == pytest.approx(900.0 * 30.0 / SIGMA_H_MPA, abs=1e-7)
    assert repaired.values["exact_sigma_9_10_MPa"] <= SIGMA_H_MPA + 1e-6
    # longest path 1-3-7-8-9-10 with the exact bounds; the other chains are shorter by hand
    assert repaired.values["span_deg"] == pytest.approx(20 + root + 10 + 15 + 33.75, abs=1e-7)


def test_round_one_is_the_linear_lp_and_the_safeguard_cuts_at_the_exact_bound(task, repaired, dense_root):
    lp = plan_cyclogram(task, stress_form="linear")
    rounds = repaired.diagnostics["rounds"]
    assert rounds[0]["span_deg"] == pytest.approx(lp.values["span_deg"], abs=1e-9)
    t_lin = (task.amplitude_intercept_mm - LIMIT_MM) / -task.amplitude_slope_mm_per_deg        # 36 deg
    a_lin = float(rebound_amplitude_mm(lever_stop(task.lever), 420.0, t_lin))
    assert repaired.values["linearisation_error_amplitude_3_7_mm"] == pytest.approx(a_lin - LIMIT_MM, rel=1e-4)
    amp = [next(r for r in rnd["limits"] if r["limit"] == "amplitude[3->7]") for rnd in rounds]
    assert [r["cut"] for r in amp[:2]] == ["newton", "exact"]      # Newton from 36 deg, then no safe root
    assert amp[0]["cut_deg"] < dense_root[0] - 1.0                   # the tangent's root: far short of the bound
    assert amp[1]["cut_deg"] == pytest.approx(dense_root[0], abs=1e-7)
    assert all(b["t_deg"] >= a["t_deg"] for a, b in itertools.pairwise(amp))                   # never loosened
    assert repaired.values["rounds"] == len(rounds) == 4
    # the stress tangent at t_ref = 30: sigma = 900 (2 - t/30) = 800 at 33.33 deg, exactly 810 there
    assert repaired.values["linearisation_error_sigma_9_10_MPa"] == pytest.approx(10.0, abs=1e-9)


def test_on_a_convex_law_the_rounds_are_newton_steps_and_converge_quadratically(task):
    """The fitted lever (a ~ n / t, convex): every cut a Newton step, the excess squaring."""
    fitted = dataclasses.replace(task, lever=FITTED_LEVER)
    r = repair_cyclogram(fitted, stress_form="linear")
    root = brentq(lambda t: float(rebound_amplitude_mm(lever_stop(FITTED_LEVER), 420.0, t)) - LIMIT_MM, 1.0, 300.0,
                  xtol=1e-13)
    assert r.status is Status.SOLVED and r.values["t_3_7_deg"] == pytest.approx(root, abs=1e-7)
    rounds = r.diagnostics["rounds"]
    assert r.values["rounds"] == len(rounds) == 4
    for limit, value in (("amplitude[3->7]", LIMIT_MM), ("contact_stress[9->10]", SIGMA_H_MPA)):
        rows = [next(x for x in rnd["limits"] if x["limit"] == limit) for rnd in rounds]
        excess = [x["excess"] / value for x in rows]
        assert all(x["cut"] == "newton" for x in rows[:-1])
        assert all(b <= 2.0 * a * a for a, b in itertools.pairwise(excess))  # Newton: relative excess squares
        assert excess[0] > 1e-3 and abs(excess[-1]) < 1e-12


def test_a_newton_step_that_stops_at_a_wiggle_s_crossing_is_cut_at_the_range_bound(task, monkeypatch):
    """A law with a dip under the limit near 34 deg and over it again up to 40 deg: Newton from
    the tangent's bound (33 deg) lands in the dip, where a holds at t but not above it."""
    def wavy(lever, speed_rpm, t_deg, lost=None):
        t = np.asarray(t_deg, float) * 420.0 / np.asarray(speed_rpm, float)
        return 0.1 * 40.0 / t - 0.025 * np.exp(-((t - 34.0) / 0.8) ** 2)
    monkeypatch.setattr(loom_solver, "rebound_amplitude_mm", wavy)
    clear_caches()
    law = dataclasses.replace(task, amplitude_slope_mm_per_deg=-0.0025, amplitude_intercept_mm=0.1825)    # bound 33
    r = repair_cyclogram(law, stress_form="exact")
    clear_caches()
    amp = [next(x for x in rnd["limits"] if x["limit"] == "amplitude[3->7]") for rnd in r.diagnostics["rounds"]]
    assert r.status is Status.SOLVED
    assert amp[0]["cut"] == "newton" and amp[1]["excess"] < 0 and 33.5 < amp[1]["t_deg"] < 34.5   # in the dip
    assert amp[1]["cut"] == "exact"                                    # held at t, not on the range above it
    assert r.values["t_3_7_deg"] == pytest.approx(40.0, abs=1e-6)      # the law's last crossing: 0.1 * 40 / t
    assert amp[-1]["t_deg"] == pytest.approx(40.0, abs=1e-6)


def test_a_cap_on_rounds_reports_limit_and_what_is_broken(task):
    r = repair_cyclogram(task, max_rounds=1)
    assert r.status is Status.LIMIT
    assert set(r.violated) == {"amplitude[3->7]", "contact_stress[9->10]"}
    assert "not converged in 1 round" in r.message
    assert r.values["exact_amplitude_3_7_mm"] > LIMIT_MM


def test_exact_stress_form_repairs_the_amplitude_only(task, dense_root):
    r = repair_cyclogram(task, stress_form="exact")
    assert r.status is Status.SOLVED and r.values["rounds"] == 3
    assert r.values["linearisation_error_sigma_9_10_MPa"] == pytest.approx(0.0, abs=1e-9)
    assert r.values["t_3_7_deg"] == pytest.approx(dense_root[0], abs=1e-7)


def test_a_conservative_linear_law_is_kept_and_reported_with_its_slack(task, dense_root):
    r = repair_cyclogram(dataclasses.replace(task, amplitude_intercept_mm=0.25), stress_form="exact")
    assert r.status is Status.SOLVED and r.values["rounds"] == 1
    assert r.values["t_3_7_deg"] == pytest.approx(0.15 / -task.amplitude_slope_mm_per_deg, abs=1e-7)   # 50 deg
    assert r.values["exact_amplitude_3_7_mm"] < LIMIT_MM
    assert r.values["amplitude_holds_from_3_7_deg"] == pytest.approx(dense_root[0], abs=1e-7)


def test_lever_alone_converges_to_the_same_bound_and_the_plain_lp_refuses_it(task, dense_root):
    alone = dataclasses.replace(task, amplitude_slope_mm_per_deg=None, amplitude_intercept_mm=None)
    r = repair_cyclogram(alone, stress_form="exact")
    assert r.status is Status.SOLVED
    assert r.values["t_3_7_deg"] == pytest.approx(dense_root[0], abs=1e-7)
    with pytest.raises(ModelError, match="needs the linear amplitude law") as err:
        plan_cyclogram(alone)
    assert err.value.key == "amplitude_slope_mm_per_deg"


def test_a_window_the_repair_breaks_is_infeasible_with_its_round_and_chain(task):
    tight = dataclasses.replace(task, windows=[{"from": "3", "to": "7", "max_deg": 36.2}])
    r = repair_cyclogram(tight)
    assert r.status is Status.INFEASIBLE
    assert r.message.startswith("round 2: infeasible: conflicting chain")
    assert any("window" in v for v in r.violated) and len(r.diagnostics["rounds"]) == 1


def test_a_range_on_which_no_angle_keeps_the_limit_is_infeasible_with_the_best_reading(task):
    r = repair_cyclogram(task, stress_form="exact", scan_to_deg=35.0)
    assert r.status is Status.INFEASIBLE
    assert "exceeds the limit at the top of the stated range [30, 35] deg" in r.message
    a35 = float(chain_rebounds_mm(lever_stop(task.lever), 420.0, 35.0))         # the loom's law: the batch path
    assert f"{a35:.6g} mm" in r.message and r.violated == ("amplitude[3->7]",) and r.values == {}
    assert r.diagnostics["best_amplitude_mm"] == a35 and r.diagnostics["best_t_deg"] == 35.0
    assert a35 == pytest.approx(float(rebound_amplitude_mm(lever_stop(task.lever), 420.0, 35.0)), rel=1e-9)  # CVODES


def test_the_exact_law_needs_a_speed(task):
    with pytest.raises(ModelError, match="speed_rpm") as err:
        repair_cyclogram(dataclasses.replace(task, speed_rpm=None))
    assert err.value.key == "speed_rpm"


@pytest.mark.parametrize("override, match", [
    ({"lever.E_GPa.value": -1.0}, r"structure\.lever\.E_GPa=-1\.0: allowed 0\.001 \.\.\. 10,000"),
    ({"lever.colour": 1.0}, r"lever\.colour: no entry 'colour' here; there are effects, law, E_GPa"),
    ({"lever.mass_kg": {"value": 1.0, "mark": "assumed"}}, r"lever\.mass_kg: marked 'assumed' needs a 'why'"),
    ({"lever.law": "square"}, r"lever\.law=.*square.*: unknown motion law; allowed: cycloidal"),
    ({"speed_rpm": 0.0}, r"params\.speed_rpm=0\.0: allowed > 0 \.\.\. 1e\+06"),
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


@pytest.mark.parametrize("scene_id", ["loom/group1-repaired", "loom/machine-speed"])
def test_lever_table_is_read_from_stop_impact_amplitude_law(scene_id):
    """The table read from stop-impact/amplitude-law when the scene loads: every lever parameter,
    the effects and the law equal that scene's (its question's two left out), and so does its rebound."""
    source = registry.find("stop-impact/amplitude-law")
    lever = registry.find(scene_id).build()[0].lever
    params = source.params()
    for key, entry in lever.items():
        if key not in ("effects", "law"):
            assert entry["value"] == params[key], key
    assert set(params) - set(lever) == {"speed_nominal_rpm", "amplitude_limit_mm"}
    chain = source.build()[0]
    assert tuple(lever["effects"]) == chain.effects and lever["law"] == chain.law
    assert float(rebound_amplitude_mm(lever_stop(lever), 420.0, 36.0)) == float(rebound_amplitude_mm(chain, 420.0, 36.0))


def test_at_another_speed_the_rebound_is_h_of_n_over_t(task, dense_root):
    """At 300 rpm with the lever alone: a(t, 300) = a(t 420 / 300, 420); the bound 38.67 * 300 / 420
    = 27.6 deg falls under the lift's [phi] = 30 deg, which then sets the angle."""
    slow = dataclasses.replace(task, speed_rpm=300.0, amplitude_slope_mm_per_deg=None, amplitude_intercept_mm=None)
    r = repair_cyclogram(slow, stress_form="exact")
    assert r.status is Status.SOLVED
    assert r.values["t_3_7_deg"] == pytest.approx(30.0, abs=1e-9)
    lever = lever_stop(task.lever)
    assert r.values["exact_amplitude_3_7_mm"] == pytest.approx(float(chain_rebounds_mm(lever, 420.0, 42.0)), rel=1e-13)
    assert r.values["exact_amplitude_3_7_mm"] == pytest.approx(float(rebound_amplitude_mm(lever, 420.0, 42.0)), rel=1e-9)
    assert r.values["amplitude_holds_from_3_7_deg"] == 30.0          # a holds on the whole stated range
    # the returner's stress bound 33.75 deg at 420 rpm falls to 24.1 deg: its [phi] = 30 deg sets the angle
    assert r.values["t_9_10_deg"] == pytest.approx(30.0, abs=1e-9)
    assert r.values["exact_sigma_9_10_MPa"] == pytest.approx(900 * 30 / 30 * 300 / 420, rel=1e-9)


def _scenes_folder(tmp_path, lever):
    """A copy of loom/group1-repaired whose lever table is `lever`, beside copies of its sources."""
    root = Path(registry.find("loom/group1-repaired").path).parents[1]
    (tmp_path / "loom").mkdir()
    shutil.copytree(root / "stop-impact", tmp_path / "stop-impact")
    shutil.copy(root / "loom" / "group1.toml", tmp_path / "loom" / "group1.toml")       # its base
    text = (root / "loom" / "group1-repaired.toml").read_text(encoding="utf-8")
    start = text.index("[structure.lever]")
    end = text.index("\n[", start + 1)
    path = tmp_path / "loom" / "mine.toml"
    path.write_text(text[:start] + "[structure.lever]\n" + lever + text[end:], encoding="utf-8")
    return path


def test_the_lever_is_read_from_its_scene_so_an_edit_there_reaches_the_loom(tmp_path):
    path = _scenes_folder(tmp_path, 'scene = "../stop-impact/amplitude-law.toml"\n'
                                    'drop = ["speed_nominal_rpm", "amplitude_limit_mm"]\n')
    source = tmp_path / "stop-impact" / "amplitude-law.toml"
    source.write_text(source.read_text(encoding="utf-8").replace("mass_kg = { value = 0.81792",
                                                                  "mass_kg = { value = 0.9"), encoding="utf-8")
    lever = registry.find(str(path)).build()[0].lever
    assert lever["mass_kg"] == {"value": 0.9, "mark": "calibrated", "on": "f_free_Hz",
                                "why": lever["mass_kg"]["why"]} and "speed_nominal_rpm" not in lever


@pytest.mark.parametrize("lever, match", [
    ('scene = "../stop-impact/nowhere.toml"\n', r"nowhere\.toml: no such scene file"),
    ('scene = "../stop-impact/amplitude-law.toml"\ndrop = ["colour"]\n', r"structure\.lever\.drop: colour not in"),
    ('scene = "../stop-impact/amplitude-law.toml"\nkeep = 1\n', r"structure\.lever: a model from another scene is"),
    ('scene = "mine.toml"\n', r"structure\.lever: mine\.toml leads back to a scene being read"),
])
def test_a_bad_reference_to_another_scene_is_named(tmp_path, lever, match):
    with pytest.raises(SceneError, match=match):
        registry.find(str(_scenes_folder(tmp_path, lever)))
