"""Result.warnings: a model used outside what its source or derivation supports says so, in the
Result, the run's JSON, the CLI and sweep tables."""
import json
from dataclasses import replace

import numpy as np
import pytest

from mechopt import registry
from mechopt.cli import main
from mechopt.kit.errors import SolverError
from mechopt.kit.result import Result, Status, Timing
from mechopt.models.press_laws import PAPER_KINEMATICS_TOLERANCE, cutting_force_N, paper_kinematics_error, travel_m
from mechopt.models.validity import out_of_range


def test_result_keeps_warnings_once_as_sentences():
    r = Result(Status.SOLVED, {}, Timing(0, 0), warnings=("a", "b", "a"))
    assert r.warnings == ("a", "b")
    assert r.with_warnings(["c"]).warnings == ("a", "b", "c")
    with pytest.raises(SolverError, match="sentences"):
        Result(Status.SOLVED, {}, Timing(0, 0), warnings="one string")


def test_thick_blank_warns_of_eq1_extrapolation_in_the_json(tmp_path, capsys):
    out = tmp_path / "out.json"
    assert main(["run", "press/kd2322", "--set", "blank_thickness_mm=5", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    warnings = json.loads(out.read_text())["warnings"]
    assert len(warnings) == 1 and "eq. (1) extrapolated beyond X = 3 mm" in warnings[0]
    assert f"warning: {warnings[0]}" in printed
    # the sentence's figures against eq. (1) evaluated here
    coeffs = (1075.68, -406.8, -4.0, 90.93)
    f5, f3 = cutting_force_N(5.0, *coeffs), cutting_force_N(3.0, *coeffs)
    assert f"{f5 / 1000:.3g} kN" in warnings[0] and f"{f5 / f3:.2g}x" in warnings[0]


def test_the_published_setting_has_no_warning():
    assert registry.run("press/kd2322").result.warnings == ()


def test_a_force_law_without_its_fitted_range_warns_that_it_is_unchecked():
    """A scene (an older template's) that gives eq. (1)'s coefficients but not the range they were
    fitted on: its 5 mm blank was run with no word; now the unchecked range is said."""
    task = registry.find("press/kd2322").build()[0]
    loose = replace(task, force_fit_max_mm=None, blank_thickness_mm=5.0)
    assert loose.warnings({}) == ["eq. (1)'s fitted range is not stated (force_fit_max_mm): whether X = "
                                  "blank_thickness_mm = 5 mm lies inside it is not checked"]


def test_paper_kinematics_error_against_finite_differences():
    """The closed-form error of the paper's X'' against second differences of both X(phi)."""
    for lam in (0.071, 0.3):
        phi = np.linspace(0, 2 * np.pi, 20001)
        h = phi[1] - phi[0]
        acc = {k: np.gradient(np.gradient(travel_m(phi, 1.0, lam, k), h), h)[5:-5] for k in ("paper", "exact")}
        brute = np.max(np.abs(acc["paper"] - acc["exact"])) / np.max(np.abs(acc["exact"]))
        assert paper_kinematics_error(lam) == pytest.approx(brute, rel=1e-3)
    assert paper_kinematics_error(0.071) < PAPER_KINEMATICS_TOLERANCE < paper_kinematics_error(0.35)


def test_large_rod_ratio_under_paper_kinematics_warns():
    run = registry.run("press/kd2322", {"rod_ratio": 0.35})
    assert any("kinematics = 'paper'" in w and "rod_ratio = 0.35" in w for w in run.result.warnings)
    assert not registry.run("press/kd2322", {"rod_ratio": 0.35, "kinematics": "exact"}).result.warnings


def test_machine_speed_above_the_lever_laws_speeds_warns():
    run = registry.run("loom/machine-speed")
    assert run.values["max_speed_rpm"] > 420
    assert any("lever_law_max_rpm = 420" in w for w in run.result.warnings)


def test_slow_lever_warns():
    # a lever 210 times softer and 5000 times heavier: its first mode (about 0.3 Hz) drops below the 7 Hz cycle
    scene = registry.find("stop-impact/frequencies")
    task, _ = scene.build({"E_GPa": 1.0, "mass_kg": 4000.0})
    assert any("first mode" in w for w in out_of_range(replace(task, speeds_rpm=(420.0,)), {}))
    task, _ = scene.build({})
    assert not out_of_range(replace(task, speeds_rpm=(420.0,)), {})


def test_sweep_table_has_a_warnings_column(tmp_path):
    from mechopt import sweep
    table = sweep.sweep(registry.find("press/kd2322"), [sweep.parse_grid("blank_thickness_mm=2:4:2")],
                        out=tmp_path / "t.parquet", progress=False)
    column = dict(zip(table.column("blank_thickness_mm").to_pylist(), table.column("warnings").to_pylist()))
    assert column[2.0] == "" and "extrapolated beyond X = 3 mm" in column[4.0]


def test_each_model_states_its_own_warnings_and_the_core_names_none():
    """The warnings are each model's method: models/validity.py asks the task, naming no model."""
    import ast
    from pathlib import Path

    import mechopt.models.validity as validity
    tree = ast.parse(Path(validity.__file__).read_text(encoding="utf-8"))
    assert not [n for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and "models." in (n.module or "")]

    class Quiet:
        pass

    class Loud:
        def warnings(self, values):
            return [f"x = {values['x']}"]
    assert out_of_range(Quiet(), {"x": 1}) == () and out_of_range(Loud(), {"x": 1}) == ("x = 1",)
