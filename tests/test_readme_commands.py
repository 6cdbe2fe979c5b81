"""The command examples of the README and of the pages that took its manual (docs/commands.md,
docs/results.md), run in order as written, in a fresh folder: every one must work. Grids are shrunk to 3 points a key and random draws to 5 (the README's sizes are for a
designer's machine); the Dask example runs on a local cluster standing in for `scheduler-host`.
The `bench` lines run with `--repeats 1` (a missed timing target, exit 1, is a measurement on a
busy machine, not a fault), and the `dask scheduler` / `dask worker` lines start services: those
two are named here and left out. The commands run in this process (`main(argv)`), and a package
scene solved as its file says is solved once for them all (validate, then three reports: the
`solved_once` fixture of conftest.py); the what-ifs and sweeps solve what they ask. A command the
pages give twice word for word (the quick bench) runs the first time only."""
import re
import shlex
import shutil
from pathlib import Path

import pytest

from mechopt.cli import main

ROOT = Path(__file__).resolve().parents[1]
LEFT_OUT = ("dask scheduler", "dask worker")
# the front door, then the manual it links to: the README's commands before the move, in their order
PAGES = ("README.md", "docs/commands.md", "docs/results.md")


def readme_commands():
    text = "\n".join((ROOT / page).read_text(encoding="utf-8") for page in PAGES)
    lines = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            command = line.split("  #", 1)[0].split(" # ", 1)[0].strip()
            if command:
                lines.append(command)
    return lines


def shrunk(argv):
    out = []
    for arg in argv:
        grid = re.fullmatch(r"(\w+=[^:]+:[^:]+):(\d+)", arg)
        out.append(f"{grid.group(1)}:{min(int(grid.group(2)), 3)}" if grid else arg)
    return ["5" if prev == "--samples" else a for prev, a in zip([None, *out], out)]


def test_the_readme_names_its_commands():
    commands = readme_commands()
    assert len(commands) >= 20 and commands[0].startswith("python -m pip install")
    assert sum(c.startswith(LEFT_OUT) for c in commands) == 2


@pytest.mark.slow
def test_every_readme_command_runs_in_order(tmp_path, monkeypatch, solved_once):
    from distributed import LocalCluster
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0")
    ran = []
    try:
        for command in readme_commands():
            if not command.startswith("mechopt ") or command.startswith(LEFT_OUT):
                continue
            command = command.replace("tcp://scheduler-host:8786", cluster.scheduler_address)
            argv = shrunk(shlex.split(command)[1:])
            if argv[0] == "bench":
                argv += ["--repeats", "1"]
                if argv in ran:         # given twice word for word: measured once
                    continue
                assert main(argv) in (0, 1), command
            else:
                assert main(argv) == 0, command
            ran.append(argv)
    finally:
        cluster.close()
    assert {"cases", "describe", "run", "validate", "sweep", "report", "new", "fit-force", "bench"} <= {a[0] for a in ran}
    assert (tmp_path / "out" / "bench" / "cam_cutter_work_precision.png").is_file()


def test_the_validation_counts_are_stated_once_over():
    """README.md holds `mechopt validate`'s summary line (tests/test_scenes.py checks it against a
    run); a page that quotes it quotes the same line."""
    today = re.findall(r"Today: `[^`]+`", (ROOT / "README.md").read_text(encoding="utf-8"))
    assert len(today) == 1
    for page in (ROOT / "docs").rglob("*.md"):
        quoted = re.findall(r"Today: `[^`]+`", " ".join(page.read_text(encoding="utf-8").split()))
        assert all(q == today[0] for q in quoted), page.name
