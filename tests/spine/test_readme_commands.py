"""The command examples of the README and of the pages that took its manual (docs/commands.md,
docs/results.md): every one must work, each a test of its own (so that pytest-xdist spreads them), run
in a fresh folder per worker. Grids are shrunk to 3 points a key and random draws to 5 (the README's
sizes are for a designer's machine); the Dask example runs on a local cluster standing in for
`scheduler-host`. The `bench` lines run with `--repeats 1` (a missed timing target, exit 1, is a
measurement on a busy machine, not a fault), and the `dask scheduler` / `dask worker` lines start
services: those two are named here and left out. A command the pages give twice word for word (the
quick bench) is one test. A command that reads what an earlier one wrote (`my-scenes/` of `mechopt
new`, the report's `--bench` and `--sweep`) runs those first, once per worker, in the pages' order.
The commands run in this process (`main(argv)`), and a package scene solved as its file says is
solved once for them all and for the other tests (the `solved_once` fixture of conftest.py: validate
and two reports solve the whole registry); the what-ifs and sweeps solve what they ask."""
import re
import shlex
import shutil
from pathlib import Path

import pytest

from mechopt.cli import main

ROOT = Path(__file__).resolve().parents[2]
LEFT_OUT = ("dask scheduler", "dask worker")
# the front door, then the manual it links to: the README's commands before the move, in their order
PAGES = ("README.md", "docs/commands.md", "docs/results.md")
WRITES = ("--out", "--plot", "--json", "--csv", "--dxf")     # options naming what a command writes
READS = ("--bench", "--sweep", "--cases")                    # options naming what it reads


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


def mechopt_commands():
    """The pages' `mechopt` commands in order, each once, as the argv a test passes to main."""
    out = []
    for command in readme_commands():
        if command.startswith("mechopt ") and not command.startswith(LEFT_OUT):
            argv = shrunk(shlex.split(command)[1:])
            argv += ["--repeats", "1"] if argv[0] == "bench" else []
            if argv not in out:
                out.append(argv)
    return out


def _paths(argv):
    """(what argv reads, what it writes): file and folder arguments, trailing slashes dropped."""
    reads, writes = [], []
    for prev, arg in zip([None, *argv], argv):
        if prev in WRITES or (argv[0] == "new" and prev == argv[1]):
            writes.append(arg.rstrip("/"))
        elif prev in READS or (not arg.startswith("-") and prev not in (None, "--set", "--grid", "--random")
                               and re.search(r"\.(toml|csv|parquet)$|/$", arg)):
            reads.append(arg.rstrip("/"))
    return reads, writes


def needs(argv, commands):
    """The earlier commands that write what argv reads (a file, or a file in a folder it reads)."""
    reads = _paths(argv)[0]
    earlier = commands[:commands.index(argv)]
    return [c for c in earlier if any(w == r or w.startswith(r + "/") for w in _paths(c)[1] for r in reads)]


def _group(argv, commands):
    """A command's xdist group: named by the first of the commands it is tied to by needs (either
    way), so that the files one makes for another are made once, on one worker."""
    tied, grown = {commands.index(argv)}, True
    while grown:
        more = {commands.index(c) for i in tied for c in needs(commands[i], commands)}
        more |= {j for j, c in enumerate(commands) if any(commands.index(n) in tied for n in needs(c, commands))}
        grown, tied = not more <= tied, tied | more
    return f"readme-{min(tied):02d}"


def _param(argv, commands):
    name = f"{commands.index(argv):02d}-{'-'.join(a for a in argv[:2] if not a.startswith('-'))}"
    return pytest.param(argv, id=name, marks=pytest.mark.xdist_group(_group(argv, commands)))


COMMANDS = mechopt_commands()


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    """The fresh folder the commands run in (the examples copied in), and the commands done there."""
    folder = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples", folder / "examples")
    return folder, []


def _run(argv, done):
    for earlier in needs(argv, COMMANDS):
        if earlier not in done:
            _run(earlier, done)
    if argv[0] == "bench":
        assert main(argv) in (0, 1), argv
    elif "tcp://scheduler-host:8786" in argv:
        from distributed import LocalCluster
        with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
            assert main([cluster.scheduler_address if a == "tcp://scheduler-host:8786" else a for a in argv]) == 0
    else:
        assert main(argv) == 0, argv
    done.append(argv)


@pytest.mark.slow
@pytest.mark.parametrize("argv", [_param(argv, COMMANDS) for argv in COMMANDS])
def test_a_readme_command_runs(argv, walk, monkeypatch, solved_once):
    folder, done = walk
    monkeypatch.chdir(folder)
    if argv not in done:            # else it ran, and passed, as an earlier test's need
        _run(argv, done)
    if argv[0] == "bench":
        assert (folder / "out" / "bench" / "cam_cutter_work_precision.png").is_file()


def test_the_walk_covers_every_command_and_keeps_its_needs():
    assert {"cases", "describe", "run", "validate", "sweep", "report", "new", "fit-force", "bench"} <= {a[0] for a in COMMANDS}
    new = next(a for a in COMMANDS if a[0] == "new")
    assert all(new in needs(a, COMMANDS) for a in COMMANDS if a != new and any("my-scenes" in p for p in a))
    report = next(a for a in COMMANDS if a[0] == "report" and "--bench" in a)
    assert [c[0] for c in needs(report, COMMANDS)] == ["bench", "sweep"]
    assert all(_group(n, COMMANDS) == _group(a, COMMANDS) for a in COMMANDS for n in needs(a, COMMANDS))
    assert len({_group(a, COMMANDS) for a in COMMANDS}) > len(COMMANDS) / 2      # the rest spread


def test_the_validation_counts_are_stated_once_over():
    """README.md holds `mechopt validate`'s summary line (tests/spine/test_scenes.py checks it against a
    run); a page that quotes it quotes the same line."""
    today = re.findall(r"Today: `[^`]+`", (ROOT / "README.md").read_text(encoding="utf-8"))
    assert len(today) == 1
    for page in (ROOT / "docs").rglob("*.md"):
        quoted = re.findall(r"Today: `[^`]+`", " ".join(page.read_text(encoding="utf-8").split()))
        assert all(q == today[0] for q in quoted), page.name
