"""User text in figures drawn literally (mathtext never parses a name), and Ctrl-C honoured inside a
large HiGHS LP and during interpreter shutdown (exit 130, never death by SIGINT)."""
import csv
import json
import os
import signal
import subprocess
import sys
import time

import pytest
from matplotlib import cbook
from matplotlib.text import Text

from mechopt import cli, registry
from mechopt import sweep as sw
from mechopt.figures import figures
from mechopt.figures import sweep as sweep_figures
from mechopt.report import write_report

PACKAGING = registry.cases_dir() / "loom" / "packaging.toml"
HOSTILE = ("$x^$", r"$\frac{", "a_b", "100%")        # mathtext would fail on the first two, set the third


# --- figures -------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def hostile_scene(tmp_path_factory):
    """The packaging machine with every operation, group and one event named with mathtext specials."""
    folder = tmp_path_factory.mktemp("hostile-names")
    with (PACKAGING.parent / "packaging-ops.csv").open(encoding="utf-8") as f:
        rows = list(csv.reader(f))
    for k, row in enumerate(rows[1:]):
        row[2] = f"{HOSTILE[k % 4]} {row[2]}"                                  # name
        row[3] = f"{HOSTILE[(k + 1) % 4]}{row[3]}"                             # group
        row[:2] = [{"feed.back": "$y_$back"}.get(event, event) for event in row[:2]]
    with (folder / "packaging-ops.csv").open("w", newline="", encoding="utf-8") as f:
        csv.writer(f).writerows(rows)
    text = PACKAGING.read_text(encoding="utf-8").replace('id = "loom/packaging"', 'id = "mine/hostile-names"')
    (folder / "s.toml").write_text(text, encoding="utf-8")
    return folder / "s.toml"


def _drawn(fig) -> list[str]:
    """Every text of a figure as matplotlib draws it; none may be read as mathtext."""
    texts = [t.get_text() for t in fig.findobj(Text) if t.get_text()]
    assert not [t for t in texts if cbook.is_math_text(t)]
    return [t.replace(r"\$", "$") for t in texts]


def test_names_with_mathtext_specials_are_drawn_literally(hostile_scene):
    run = registry.run(registry.find(str(hostile_scene)))
    drawn = "\n".join(line for fig in figures(run).values() for line in _drawn(fig))
    for name in (*HOSTILE, "$y_$back"):
        assert name in drawn


def test_run_plot_writes_the_figure_of_a_scene_with_dollar_names(hostile_scene, tmp_path):
    assert cli.main(["run", str(hostile_scene), "--plot", str(tmp_path / "figs")]) == cli.OK
    assert [p.name for p in (tmp_path / "figs").iterdir()] == ["mine_hostile-names_cyclogram.png"]


def test_report_and_sweep_maps_draw_dollar_axis_names_literally(hostile_scene, tmp_path, monkeypatch):
    scene = registry.find(str(hostile_scene))
    out = tmp_path / "o.parquet"
    sw.sweep(scene, [sw.parse_grid("operations[from=feed.end,to=$y_$back].min_deg=50:60:2"),
                     sw.parse_grid("speed_rpm=50:60:2")], out=out, progress=False)
    drawn = []
    save = sweep_figures.save_figure
    monkeypatch.setattr(sweep_figures, "save_figure", lambda fig, path: drawn.extend(_drawn(fig)) or save(fig, path))
    page = write_report(tmp_path / "rep", runs=[registry.run(scene)], sweeps=[out])
    assert page.is_file() and "<img" in page.read_text(encoding="utf-8")
    assert any("$y_$back" in line for line in drawn)


# --- Ctrl-C inside a large HiGHS LP --------------------------------------------------------------

MARKED_COMMAND = """
import sys
from highspy._core import _Highs
from mechopt import cli
real = _Highs.run
def run(self):                      # markers on stderr around every HiGHS solve of a large LP
    large = self.getNumRow() >= 5000
    print("LP running" if large else "", file=sys.stderr, flush=True)
    try:
        return real(self)
    finally:                        # also when the KeyboardInterrupt is raised as the LP returns
        print(f"LP ended: {self.getModelStatus().name}" if large else "", file=sys.stderr, flush=True)
_Highs.run = run
sys.argv = ["mechopt", *sys.argv[1:]]
sys.exit(cli.main())
"""


def _large_lp_scene(folder, events=6000):
    """A cyclogram of `events` events and about 5 operations each, planned by cvxpy's HiGHS LP
    (method lp): about 35,000 rows, some seconds of HiGHS' presolve on a quiet machine."""
    import numpy as np
    rng = np.random.default_rng(1)
    tails = rng.integers(0, events - 1, 4 * events)
    heads = np.minimum(tails + rng.integers(1, 50, 4 * events), events - 1)
    tails = np.r_[np.zeros(events - 1, int), tails, np.arange(1, events - 1)]        # start -> every event,
    heads = np.r_[np.arange(1, events), heads, np.full(events - 2, events - 1)]      # every event -> end
    arcs = {(a, b): d for a, b, d in zip(tails, heads, rng.uniform(1, 5, len(tails))) if a != b}
    lines = ["from,to,min_deg", *(f"e{a},e{b},{d:.3f}" for (a, b), d in arcs.items())]
    (folder / "ops.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    scene = folder / "large.toml"
    scene.write_text('id = "mine/large-lp"\ntitle = "a large event-time LP"\nsource = "a test"\n'
                     'task = "loom.Cyclogram"\nsolver = "loom.plan_cyclogram"\n[params]\n'
                     '[solver_settings]\nmethod = "lp"\n[structure]\n'
                     'operations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }\n', encoding="utf-8")
    return scene


def test_ctrl_c_inside_a_large_highs_lp_exits_130_at_once_and_writes_nothing(tmp_path):
    scene, out = _large_lp_scene(tmp_path), tmp_path / "r.json"
    proc = subprocess.Popen([sys.executable, "-c", MARKED_COMMAND, "run", str(scene), "--json", str(out)],
                            stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    said = []
    for line in proc.stderr:
        said.append(line)
        if line.startswith("LP running"):
            break
    time.sleep(0.5)                 # inside HiGHS now
    assert proc.poll() is None, "".join(said)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == cli.INTERRUPTED, err[-2000:]
    assert "LP ended: kOptimal" not in err      # the command did not wait for the LP to end
    assert "Traceback" not in err and not out.exists() and not list(tmp_path.glob("r.json*"))


# --- Ctrl-C at any moment of a short command, interpreter exit included ----------------------------

LATE_SIGNAL = """
import os, signal, sys
from mechopt import cli
class Late:                         # torn down with the module, after the interpreter let go of signals
    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
late = Late()
sys.argv = ["mechopt", "describe", "loom/packaging"]
sys.exit(cli.main())
"""


def test_a_sigint_while_the_interpreter_tears_down_does_not_kill_the_command():
    done = subprocess.run([sys.executable, "-c", LATE_SIGNAL], capture_output=True, text=True, timeout=300)
    assert done.returncode in (cli.OK, cli.INTERRUPTED), (done.returncode, done.stderr[-2000:])


FORKED_COMMANDS = """
import json, os, signal, sys, time
from mechopt import cli
out, delays = sys.argv[1], json.loads(sys.argv[2])
argv = ["run", "loom/packaging", "--json", out]
cli.main(argv)                      # warm: the forks below spend their life solving, writing and exiting


def command(delay):
    ready, go = os.pipe()
    pid = os.fork()
    if pid == 0:                    # the command, as `mechopt ...` runs it, to its interpreter's very end
        parser = cli._parser
        cli._parser = lambda: os.write(go, b"!") and parser()       # it has started: its first step
        sys.argv = ["mechopt", *argv]
        sys.exit(cli.main())
    os.read(ready, 1)
    time.sleep(delay)
    try:
        os.kill(pid, signal.SIGINT)
    except ProcessLookupError:
        pass
    return os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])


print(json.dumps([command(d) for d in delays]))
"""


def test_ctrl_c_at_any_moment_of_a_command_exits_0_or_130_never_by_the_signal(tmp_path):
    """SIGINT sent at spread moments of `mechopt run loom/packaging --json` (solve, write and the
    interpreter's exit: about 2 s here, mostly tearing the modules down): never death by SIGINT."""
    delays = [0.0, 0.1, 0.5, 1.2]
    done = subprocess.run([sys.executable, "-c", FORKED_COMMANDS, str(tmp_path / "r.json"), str(delays)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]           # the forking script itself ran to its end
    codes = json.loads(done.stdout.strip().splitlines()[-1])
    assert set(codes) <= {cli.OK, cli.INTERRUPTED}, list(zip(delays, codes))


def test_inside_polled_a_ctrl_c_waits_for_the_block_end_then_goes_to_the_handler_outside():
    from mechopt.kit import interrupt
    seen = []
    before = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    try:
        with interrupt.polled():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)                    # the handler runs here: it only records
            assert interrupt.pending() and not seen
        assert seen == [signal.SIGINT] and not interrupt.pending()
        with pytest.raises(KeyboardInterrupt), interrupt.honoured(), interrupt.polled():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
    finally:
        signal.signal(signal.SIGINT, before)
    assert interrupt.pending()                  # for the spine's check(), as honoured() keeps it
    with pytest.raises(KeyboardInterrupt):
        interrupt.check()


def test_a_held_model_whose_run_was_abandoned_solves_again(monkeypatch):
    """After Ctrl-C left a large run behind, the next run of the same model waits for it and is not
    itself stopped (the held LP of a bisection is reused)."""
    import numpy as np
    from highspy._core import _Highs

    from mechopt.kit import highs, interrupt
    monkeypatch.setattr(highs, "THREADED_ROWS", 1)               # this small LP runs beside the main thread
    calls = []

    def slow_run(self):                     # the first run gets Ctrl-C and is still busy when it is abandoned
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.5)
        calls.append(1)
        return _Highs.run(self)
    monkeypatch.setattr(highs.RealHighs, "run", slow_run, raising=False)
    h = highs.InterruptibleHighs()
    h.setOptionValue("output_flag", False)
    h.addVars(2, np.zeros(2), np.full(2, 10.0))
    h.changeColsCost(2, np.arange(2, dtype=np.int32), np.array([-1.0, -1.0]))
    h.addRows(1, np.array([-np.inf]), np.array([4.0]), 2, np.array([0], dtype=np.int32),
              np.arange(2, dtype=np.int32), np.ones(2))
    with pytest.raises(KeyboardInterrupt), interrupt.honoured():
        h.run()
    assert not calls and h.worker is not None                  # raised while the first run was still busy
    with pytest.raises(KeyboardInterrupt):
        interrupt.check()                                       # the spine consumes the Ctrl-C
    h.run()
    assert len(calls) == 2 and h.getModelStatus().name == "kOptimal"
    assert h.getInfo().objective_function_value == pytest.approx(-4.0)


def test_a_fork_after_a_highs_solve_stops_its_workers_first(monkeypatch):
    """A child forked while a HiGHS worker held its executor's mutex hangs at exit (the fork of
    `test_ctrl_c_at_any_moment...` was once found so: HighsTaskExecutor::ExecutorHandle::dispose on a
    futex, one thread). Before every fork the parent stops HiGHS' workers (kit/forking.py)."""
    import highspy

    import mechopt  # noqa: F401  (registers the hook)
    stopped = []
    monkeypatch.setattr(highspy.Highs, "resetGlobalScheduler", staticmethod(lambda blocking: stopped.append(blocking)))
    pid = os.fork()
    if pid == 0:
        os._exit(0)
    os.waitpid(pid, 0)
    assert stopped == [True]
