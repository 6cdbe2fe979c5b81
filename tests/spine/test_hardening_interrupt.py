"""Ctrl-C is honoured everywhere, also when a back end (CasADi's IPOPT,
CVODES, rootfinder) swallows the KeyboardInterrupt and returns a failed or inaccurate solve; the
interrupted variant is never stored; the command exits 130, also during interpreter exit."""
import dataclasses
import functools
import os
import signal
import subprocess
import sys
import time

import pyarrow.parquet as pq
import pytest

from mechopt import cli, registry
from mechopt import sweep as sw
from mechopt.kit import interrupt
from mechopt.kit.errors import SolverError
from mechopt.kit.result import Result, Status

LOOM = "loom/group1"


def _swallowing(after=0, then=None):
    """A solver that, from its (after+1)-th call, gets Ctrl-C and swallows it as CasADi does:
    an INACCURATE result (or `then`, an exception) instead of the KeyboardInterrupt."""
    real = registry.find(LOOM).solver
    calls = []

    @functools.wraps(real)                         # the real one's settings and their defaults
    def solver(task, **settings):
        calls.append(1)
        if len(calls) <= after:
            return real(task, **settings)
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)                       # the handler runs here, as it would in a CasADi callback
        except KeyboardInterrupt:
            pass                                   # ... and is eaten by the back end
        if then:
            raise then
        return Result(status=Status.INACCURATE, message="the ODE cross-check gave FAILED")
    return solver


def _scene(solver):
    return dataclasses.replace(registry.find(LOOM), solver=solver)


def test_an_interrupt_a_back_end_swallowed_is_raised_after_the_solve():
    with pytest.raises(KeyboardInterrupt):
        registry.run(_scene(_swallowing()))
    assert not interrupt.pending()
    assert registry.run(LOOM).status is Status.SOLVED           # the next run is not interrupted


def test_outside_honoured_the_previous_handler_is_back():
    before = signal.getsignal(signal.SIGINT)
    with interrupt.honoured():
        assert signal.getsignal(signal.SIGINT) is not before
    assert signal.getsignal(signal.SIGINT) is before


def test_a_sweep_stores_nothing_of_the_interrupted_variant(tmp_path):
    out = tmp_path / "o.parquet"
    with pytest.raises(sw.SweepInterrupted, match=r"2 of 3 variants done"):
        sw.sweep(_scene(_swallowing(after=2)), [sw.parse_grid("amplitude_limit_mm=0.1:0.12:3")], out=out, chunk=1,
                 progress=False)
    parts = sorted((tmp_path / "o.parquet.parts").glob("part-*.parquet"))
    statuses = [s for p in parts for s in pq.read_table(p).column("status").to_pylist()]
    assert statuses == ["SOLVED", "SOLVED"]


@pytest.mark.parametrize("then", [None, SolverError("IPOPT: User_Requested_Stop")], ids=["inaccurate", "error"])
def test_the_command_exits_130_when_a_back_end_ate_the_interrupt(monkeypatch, capsys, then):
    scene = _scene(_swallowing(then=then))
    monkeypatch.setattr(registry, "find", lambda ref: scene)
    assert cli.main(["run", LOOM]) == cli.INTERRUPTED
    assert "interrupted" in capsys.readouterr().err


def test_a_signal_during_interpreter_exit_returns_130():
    code = ("import os, signal, time\nfrom mechopt import cli\ncli._exit_on_interrupt()\n"
            "os.kill(os.getpid(), signal.SIGINT)\ntime.sleep(10)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 130 and "Traceback" not in done.stderr


def test_ctrl_c_during_a_real_casadi_sweep_stores_no_variant_it_interrupted(tmp_path):
    out = tmp_path / "o.parquet"
    proc = subprocess.Popen([sys.executable, "-m", "mechopt", "sweep", "stop-impact/amplitude-law", "--grid",
                             "damping_ratio=0.05:0.06:40", "--chunk", "1", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    parts = tmp_path / "o.parquet.parts"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(parts.glob("part-*.parquet"))) < 2:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-2000:]
    rows = [r for p in sorted(parts.glob("part-*.parquet")) for r in pq.read_table(p).to_pylist()]
    assert rows and all(r["status"] == "SOLVED" for r in rows), [(r["status"], r["message"]) for r in rows]
