"""diagnostics["drivers"]: which assumed or calibrated input sets each headline value (issue 26, part 3)."""
import json

import pytest

from mechopt import registry
from mechopt.cli import main
from mechopt.drivers import REL_STEP, elasticities, set_mostly_by, uncertain_inputs
from mechopt.solvers.result import Result, Status, Timing


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


def test_validate_sweeps_and_a_plain_run_do_not_pay_for_drivers(capsys):
    assert "drivers" not in registry.run("loom/group1").result.diagnostics
    assert main(["run", "loom/group1"]) == 0 and "drivers:" not in capsys.readouterr().out
    assert main(["run", "loom/group1", "--drivers"]) == 0
    assert "drivers: span_deg: set mostly by" in capsys.readouterr().out
