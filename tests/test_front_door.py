"""The package as a new user first meets it: the commands' streams, the numbers as printed, the
values and fields of a run, the sweep's axes and the pages that say how."""
import subprocess
import sys

import pytest

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
    import re

    from mechopt import registry
    from mechopt.answers import values_html
    from mechopt.cli import _print_run
    run = registry.run(registry.find("cam-cutter/other-profile"))
    _print_run(run)
    printed = capsys.readouterr().out.split("\nvalue ", 1)[1].split("\n\n", 1)[0].splitlines()[1:]
    cells = re.findall(r"<tr><td>([^<]+)</td><td title='[^']*'>([^<]+)</td>", values_html(run))
    assert cells == [tuple(line.split()) for line in printed] and ("L_mm", "52.1528") in cells
