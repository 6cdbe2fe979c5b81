"""The package as a new user first meets it: the commands' streams, the numbers as printed, the
values and fields of a run, the sweep's axes and the pages that say how."""
import re
import subprocess
import sys

import pytest

from mechopt.kit.errors import SceneError

BANNER = ("Running HiGHS", "Copyright (c)", "THIRD_PARTY_NOTICES")


def _mechopt(*args, code=None):
    command = [sys.executable, "-c", code] if code else [sys.executable, "-m", "mechopt", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("args", [("cases",), ("describe", "loom/group1")])
def test_a_command_that_solves_nothing_prints_no_highs_banner(args):
    done = _mechopt(*args)
    assert done.returncode == 0 and done.stdout
    assert not [b for b in BANNER if b in done.stdout or b in done.stderr]


def test_a_run_and_a_python_solve_print_no_highs_banner(tmp_path):
    """HiGHS prints its banner when a process makes its first Highs object: that one is made quietly."""
    done = _mechopt("run", "loom/group1", "--json", str(tmp_path / "r.json"))
    assert done.returncode == 0 and done.stdout.startswith("loom/group1: ")
    assert not [b for b in BANNER if b in done.stdout or b in done.stderr]
    solved = _mechopt(code="import mechopt; print(mechopt.solve('loom/group1').status.value)")
    assert solved.stdout == "SOLVED\n" and not [b for b in BANNER if b in solved.stderr]


def test_a_sweep_into_a_pipe_draws_no_bar(tmp_path):
    """A bar redraws itself with carriage returns: on a pipe or a log file they stay as garbage."""
    done = _mechopt("sweep", "loom/group1", "--grid", "amplitude_limit_mm=0.08:0.14:2", "--chunk", "1",
                    "--out", str(tmp_path / "s.parquet"))
    assert done.returncode == 0 and "2 variants (2 SOLVED)" in done.stdout
    assert "\r" not in done.stderr and "variant/s" not in done.stderr


def test_a_sweep_draws_its_bar_when_asked(capsys):
    from mechopt import registry
    from mechopt.sweep import parse_grid, sweep
    sweep(registry.find("loom/group1"), [parse_grid("amplitude_limit_mm=0.08:0.14:2")], progress=True)
    assert "2/2" in capsys.readouterr().err


def test_the_reports_values_read_as_the_command_prints_them(capsys):
    """52.1528 on the command line is 52.1528 in the report and a notebook, not 52.15."""
    from mechopt import registry
    from mechopt.answers import values_html
    from mechopt.cli import _print_run
    run = registry.run(registry.find("cam-cutter/other-profile"))
    _print_run(run)
    printed = capsys.readouterr().out.split("\nvalue ", 1)[1].split("\n\n", 1)[0].splitlines()[1:]
    cells = re.findall(r"<tr><td>([^<]+)</td><td title='[^']*'>([^<]+)</td>", values_html(run))
    assert cells == [tuple(line.split()) for line in printed] and ("L_mm", "52.1528") in cells


def test_a_list_is_a_grid_axis_of_those_values_and_a_tuple_stays_a_range(tmp_path):
    import mechopt
    from mechopt.sweep import read_table
    out = tmp_path / "listed.parquet"
    table = mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": [0.14, 0.08, 0.1]}, out=out)
    assert table.column("amplitude_limit_mm").to_pylist() == [0.14, 0.08, 0.1]
    assert table.column("status").to_pylist() == ["SOLVED"] * 3
    _, meta = read_table(out)                                   # its metadata reads back, said as given
    assert mechopt.sweep.describe_axes(meta["spec"]) == ["amplitude_limit_mm=0.14,0.08,0.1"]
    again = mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": [0.14, 0.08, 0.1]}, out=out)   # resumes
    assert again.column("span_deg").to_pylist() == table.column("span_deg").to_pylist()
    ranged = mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": (0.08, 0.14, 3)})
    assert ranged.column("amplitude_limit_mm").to_pylist() == [0.08, 0.11, 0.14]


@pytest.mark.parametrize("values, said", [([0.1, 0.1], "0.1 is listed twice"), ([], "an empty list"),
                                          ([0.1, float("nan")], "nan is not a finite number"),
                                          ([1e13], "is beyond ±1e+12"), ([0.1, "0.2"], "'0.2' is not a number")])
def test_a_listed_axis_is_checked_like_a_range(values, said):
    import mechopt
    with pytest.raises(mechopt.SceneError, match=re.escape(said)):
        mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": values})


def test_the_command_takes_a_listed_axis_too():
    from mechopt.sweep import Axis, grid_values, parse_grid
    axis = parse_grid("amplitude_limit_mm=0.2,0.05")
    assert axis == Axis("amplitude_limit_mm", 0.05, 0.2, 2, (0.2, 0.05)) and grid_values(axis) == [0.2, 0.05]
    with pytest.raises(SceneError, match="0.05 is listed twice"):
        parse_grid("amplitude_limit_mm=0.05,0.05")
    with pytest.raises(SceneError, match="value 2 = 'x' is not a finite number"):
        parse_grid("amplitude_limit_mm=0.05,x")


def test_a_range_axis_is_stored_as_before_so_older_tables_still_resume():
    import json

    from mechopt.sweep import SweepSpec, parse_grid
    stored = json.loads(SweepSpec("loom/group1", (parse_grid("amplitude_limit_mm=0.08:0.14:3"),)).as_json())
    assert stored["grid"] == [{"key": "amplitude_limit_mm", "low": 0.08, "high": 0.14, "num": 3}]


def test_help_of_the_callable_sweep_shows_its_call():
    import inspect
    import pydoc

    import mechopt
    assert str(inspect.signature(mechopt.sweep)).startswith("(scene, grid: dict | None = None, random")
    page = pydoc.render_doc(mechopt.sweep, renderer=pydoc.plaintext)
    assert "mechopt.sweep(scene, grid" in page and "{key: [v1, v2, ...]}" in page


def test_a_runs_values_are_plain_python_numbers_and_its_fields_are_on_the_run():
    """stop-impact/cam-dynamics' solver hands numpy floats over; a run's values are Python's."""
    import mechopt
    run = mechopt.solve("stop-impact/cam-dynamics")
    assert run.values and {type(v) for v in run.values.values()} <= {float, int}
    assert "contact_angle_deg" in run.values
    assert (run.message, run.warnings, run.diagnostics, run.violated) == (
        run.result.message, run.result.warnings, run.result.diagnostics, run.result.violated)


def test_a_result_made_of_numpy_numbers_holds_python_numbers():
    import numpy as np

    from mechopt.kit.result import Result, Status, Timing
    r = Result(Status.SOLVED, {"a_mm": np.float64(1.5), "n": np.int64(3), "b_mm": 2.0}, Timing(0.0, 0.0))
    assert [(type(v), v) for v in r.values.values()] == [(float, 1.5), (int, 3), (float, 2.0)]


HEAVY = ("numpy", "scipy", "cvxpy", "casadi", "highspy", "matplotlib", "pyarrow", "pandas", "dask", "numba",
         "mechopt.registry", "mechopt.cli")


@pytest.mark.parametrize("how", ["module", "entry point"])
def test_the_version_imports_nothing_heavy(how):
    """`mechopt --version` answers before the command's modules load (it took seconds under load)."""
    code = ("import sys; from mechopt.__main__ import main; main(['--version']); "
            f"print(sorted(m for m in sys.modules if m.startswith({HEAVY!r})))")
    done = (_mechopt(code=code) if how == "entry point"
            else subprocess.run([sys.executable, "-X", "importtime", "-m", "mechopt", "--version"],
                                capture_output=True, text=True, timeout=120))
    import mechopt
    assert done.stdout.startswith(f"mechopt {mechopt.__version__}\n")
    loaded = (eval(done.stdout.splitlines()[1]) if how == "entry point"
              else [line.rsplit("|", 1)[1].strip() for line in done.stderr.splitlines() if "|" in line])
    assert not [m for m in loaded if m.startswith(HEAVY)]


def test_the_command_is_installed_at_its_light_entry_point():
    import tomllib
    from pathlib import Path
    pyproject = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text("utf-8"))
    assert pyproject["project"]["scripts"]["mechopt"] == "mechopt.__main__:main"
