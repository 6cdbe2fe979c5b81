"""diagnostics["drivers"]: which assumed or calibrated input sets each headline value, and which inputs are steps."""
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mechopt import registry
from mechopt.cli import main
from mechopt.drivers import BISECTIONS, REL_STEP, elasticities, is_step, set_mostly_by, steps_of, uncertain_inputs
from mechopt.kit.result import Result, Status, Timing


def _fake(values):
    return Result(Status.SOLVED, values, Timing(0, 0))


def test_elasticity_of_a_power_law_and_the_ranking():
    """y = a^2 / b: e_a = 2, e_b = -1 (central differences of a power law: exact to O(step^2))."""
    from mechopt.drivers import Input
    base = {"a": 3.0, "b": 5.0}

    def solve(more):
        x = base | more
        return _fake({"y": x["a"] ** 2 / x["b"]})
    found = elasticities(solve, [Input("b", 5.0, "assumed"), Input("a", 3.0, "calibrated")], ["y", "nope"],
                         {"y": 9 / 5})
    (b,), (a,) = found["values"]["y"]["assumed"], found["values"]["y"]["calibrated"]
    assert a["elasticity"] == pytest.approx(2.0, abs=1e-12) and b["elasticity"] == pytest.approx(-1.0, rel=REL_STEP)
    assert found["set_mostly_by"]["y"]["input"] == "b"            # the assumed one, the calibrated shown beside it
    assert "nope" in found["skipped"]
    assert set_mostly_by(found) == ["y: set mostly by b (assumed, elasticity -1); of the calibrated inputs, a (+2)"]


def test_an_input_at_zero_is_skipped_with_why_not_divided_by():
    """An override of 0 (friction_torque_Nm = 0) made its +-1 % step 0 and the drivers divided by it."""
    from mechopt.drivers import Input
    found = elasticities(lambda more: _fake({"y": 1.0 + (more.get("a") or 0.0)}), [Input("a", 0.0, "assumed")], ["y"],
                         {"y": 1.0})
    assert found["skipped"]["a"].startswith("at 0: a step of +-1% of it is no step")
    assert found["values"]["y"]["assumed"] == [] and found["resolves"] == 0


def test_a_press_run_with_an_input_at_zero_writes_its_json_with_drivers(tmp_path):
    out = tmp_path / "r.json"
    assert main(["run", "press/kd2322", "--set", "friction_torque_Nm=0", "--json", str(out)]) == 0
    drivers = json.loads(out.read_text())["diagnostics"]["drivers"]
    assert drivers["skipped"]["friction_torque_Nm"].startswith("at 0:")


def _with_a_step(at=10.04, jump=5.0):
    """y = 2 x + 1, and `jump` more above x = `at` (a bound that starts crossing its limit)."""
    from mechopt.drivers import Input

    def solve(more):
        x = {"x": 10.0, "z": 4.0} | more
        return _fake({"y": 2 * x["x"] + 1 + (jump if x["x"] > at else 0.0) + x["z"]})
    return solve, [Input("x", 10.0, "assumed"), Input("z", 4.0, "assumed")], {"y": 25.0}


def test_a_jump_between_the_one_sided_differences_is_a_step_with_its_bracket_not_an_elasticity():
    solve, inputs, values = _with_a_step()
    found = elasticities(solve, inputs, ["y"], values)
    (step,) = found["steps"]["y"]
    assert step["input"] == "x" and step["kind"] == "step"
    assert step["slope_below"] == pytest.approx(2.0) and step["slope_above"] == pytest.approx(2.0 + 5.0 / 0.1)
    lo, hi = step["jump_between"]
    assert lo < 10.04 <= hi and hi - lo == pytest.approx(0.1 / 2 ** BISECTIONS)
    assert step["jump"] == pytest.approx(5.0, abs=0.01)
    assert [r["input"] for r in found["values"]["y"]["assumed"]] == ["z"]     # x is no elasticity
    assert found["resolves"] == 4 + BISECTIONS
    (sentence,) = steps_of(found)
    assert sentence.startswith("y: a step in x (assumed, 10): slope +2 below, +52 above; it jumps by +5")


def test_a_jump_below_the_input_is_bracketed_below_it():
    solve, inputs, values = _with_a_step(at=9.93, jump=-3.0)
    step = elasticities(solve, inputs, ["y"], {"y": 22.0})["steps"]["y"][0]
    lo, hi = step["jump_between"]
    assert lo < 9.93 <= hi and 9.9 <= lo and step["jump"] == pytest.approx(-3.0, abs=0.01)


def test_a_smooth_curved_input_is_no_step():
    """y = x^8: the one-sided differences differ by ~8 % at +-1 %, curvature, not a step."""
    from mechopt.drivers import Input
    found = elasticities(lambda more: _fake({"y": more["x"] ** 8}), [Input("x", 1.0, "assumed")],
                         ["y"], {"y": 1.0})
    assert found["steps"]["y"] == [] and found["values"]["y"]["assumed"][0]["elasticity"] == pytest.approx(8, rel=0.01)
    assert not is_step(8.0, 8.3) and is_step(0.03, 0.9) and not is_step(0.001, 0.015)


def test_the_budget_is_a_count_of_resolves_and_the_clock_decides_nothing(monkeypatch):
    """The same answer when every reading of the clock says a minute has passed; an input past the
    count budget is named with the budget."""
    solve, inputs, values = _with_a_step()
    quiet = elasticities(solve, inputs, ["y"], values)
    ticks = iter(range(0, 10 ** 9, 60))
    monkeypatch.setattr(time, "perf_counter", lambda: float(next(ticks)))
    monkeypatch.setattr(time, "monotonic", lambda: float(next(ticks)))
    assert elasticities(solve, inputs, ["y"], values) == quiet and quiet["skipped"] == {}
    short = elasticities(solve, inputs, ["y"], values, max_resolves=3)
    assert short["skipped"] == {"z": "beyond the count budget of 3 re-solves"}
    assert short["steps"]["y"][0]["bracket_note"] == "the count budget of re-solves was spent"
    assert short["resolves"] == 3 and short["steps"]["y"][0]["bisections"] == 1
    assert "at most 3 re-solves" in short["method"]


def test_press_drivers_against_the_sensitivity_scenes_ad():
    """The generic re-solves against press/sensitivity's elasticities through the periodic motion (CasADi AD)."""
    drivers = registry.run("press/kd2322", drivers=True).result.diagnostics["drivers"]
    ad = registry.run("press/sensitivity").values
    rows = {r["input"]: r["elasticity"] for mark in ("assumed", "calibrated")
            for r in drivers["values"]["speed_fluctuation"][mark]}
    for key in ("motor_sync_speed_rad_s", "flywheel_inertia_kgm2", "tool_mass_kg", "gear_ratio"):
        assert rows[key] == pytest.approx(ad[f"speed_fluctuation_elasticity_{key}"], abs=0.01), key
    assert drivers["set_mostly_by"]["speed_fluctuation"]["input"] == "motor_sync_speed_rad_s"


def test_structure_entries_are_reached_and_fixed_inputs_are_not():
    keys = {i.key for i in uncertain_inputs(registry.find("loom/machine-speed"))}
    assert "operations[from=10.1,to=10.2].min_ms" in keys
    assert "stress_models.lift_cam.sigma_ref_MPa" in keys and "lever.E_GPa.value" in keys
    assert "cycle_deg" not in keys                       # headline_fixed: one turn per pick, a count
    assert "amplitude_limit_mm" not in keys              # given


def test_machine_speed_is_set_mostly_by_the_flight_time(tmp_path, solved_once):
    out = tmp_path / "run.json"
    assert main(["run", "loom/machine-speed", "--json", str(out)]) == 0
    drivers = json.loads(out.read_text())["diagnostics"]["drivers"]
    top = drivers["set_mostly_by"]["max_speed_rpm"]
    assert top["input"] == "operations[from=10.1,to=10.2].min_ms"
    # dn/d(flight) against two solves here, 1 ms apart
    n = [registry.run("loom/machine-speed", {top["input"]: v}).values["max_speed_rpm"] for v in (59.5, 60.5)]
    assert top["derivative"] == pytest.approx(n[1] - n[0], rel=0.02)
    assert top["elasticity"] == pytest.approx(-0.676, abs=0.01)
    # every input evaluated within the count budget; the lever's lengths are steps, not elasticities: the
    # wavy rebound's local minimum, 0.2 % above the limit, starts to cross it and t(3,7) jumps
    assert drivers["skipped"] == {} and drivers["resolves"] <= drivers["max_resolves"]
    steps = {r["input"]: r for r in drivers["steps"]["max_speed_rpm"]}
    ranked = {r["input"] for mark in ("assumed", "calibrated") for r in drivers["values"]["max_speed_rpm"][mark]}
    step = steps["lever.b_mm.value"]
    assert "lever.b_mm.value" not in ranked and step["jump"] > 3.0 and abs(step["slope_below"]) < 1.0
    lo, hi = step["jump_between"]
    assert 0 < hi - lo <= 1.2 / 2 ** BISECTIONS * (1 + 1e-9)
    ends = [registry.run("loom/machine-speed", {"lever.b_mm.value": v}).values["max_speed_rpm"] for v in (lo, hi)]
    assert ends[1] - ends[0] == pytest.approx(step["jump"], rel=1e-6)


def test_validate_sweeps_and_a_plain_run_do_not_pay_for_drivers(capsys):
    assert "drivers" not in registry.run("loom/group1").result.diagnostics
    assert main(["run", "loom/group1"]) == 0 and "drivers:" not in capsys.readouterr().out
    assert main(["run", "loom/group1", "--drivers"]) == 0
    assert "drivers: span_deg: set mostly by" in capsys.readouterr().out


# a solver's own time limit, or a branch on the clock: what a busy machine would answer differently
# (HiGHS' status kTimeLimit read as a status is no rule)
WALL_CLOCK_RULES = re.compile(r"max_wall_time|max_cpu_time|time_limit|\bTimeLimit\b|(if|while)\b[^\n]*"
                              r"(perf_counter|monotonic|time\.time)\(")


def test_no_wall_clock_rule_decides_an_answer():
    root = Path(__file__).resolve().parents[2]
    found = [f"{path.relative_to(root)}:{text[:m.start()].count(chr(10)) + 1}: {m.group(0)}"
             for folder in ("src", "models", "solvers") for path in sorted((root / folder).rglob("*.py"))
             for text in [path.read_text()] for m in WALL_CLOCK_RULES.finditer(text)]
    assert found == []


def test_drivers_are_bit_identical_with_four_cpu_burners_beside_them():
    """Counts, never seconds: every row of the drivers the same on a loaded machine as on a quiet one."""
    quiet = registry.run("loom/group1", drivers=True).result.diagnostics["drivers"]
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(4)]
    try:
        loaded = registry.run("loom/group1", drivers=True).result.diagnostics["drivers"]
    finally:
        for p in burners:
            p.kill()
            p.wait()
    assert quiet["skipped"] == {} and quiet["resolves"] > 0
    assert json.dumps(loaded, sort_keys=True) == json.dumps(quiet, sort_keys=True)
