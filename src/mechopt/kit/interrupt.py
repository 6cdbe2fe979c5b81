"""Ctrl-C that a back end cannot swallow.

CasADi runs IPOPT, CVODES and its rootfinders in C++ and polls Python's signal handlers from
there: the KeyboardInterrupt the default handler raises is caught inside and comes back as a
failed or "inaccurate" solve (an interrupted sweep once stored such a variant, and a re-run
skipped it). While `honoured()` is active, SIGINT also sets a flag that no back end can clear;
`check()` turns it back into a KeyboardInterrupt. The spine (run, validate, sweep, report) calls
`check()` after every solver call, so an interrupted solve is never stored or reported; a solver
may call it after a CasADi call inside a loop, so that it stops at once rather than at its end.

A back end that polls for Ctrl-C from its own loop (HiGHS' interrupt callback, src/mechopt/kit/highs.py)
runs inside `polled()`: there SIGINT only records itself, the back end stops at its next poll of
`pending()`, and the KeyboardInterrupt is raised when the block ends.
"""
import signal
import threading
from contextlib import contextmanager

__all__ = ["honoured", "check", "pending", "polled", "abandon", "abandoned"]

_flag = {"set": False}
_abandoned: list[threading.Thread] = []     # workers left running in C code after a Ctrl-C


def _record(signum, frame):
    _flag["set"] = True
    raise KeyboardInterrupt


def _note(signum, frame):
    _flag["set"] = True


def pending() -> bool:
    """Whether a Ctrl-C arrived that has not yet been raised by `check()`."""
    return _flag["set"]


def check() -> None:
    """Raise KeyboardInterrupt if Ctrl-C arrived since the last check (a back end may have eaten
    the one raised at the time)."""
    if _flag["set"]:
        _flag["set"] = False
        raise KeyboardInterrupt


@contextmanager
def honoured():
    """Record every SIGINT while the block runs (main thread only; elsewhere a no-op, as there
    is no signal to catch). Re-entrant; the previous handler is restored at the end."""
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is _record:
        yield
        return
    previous = signal.signal(signal.SIGINT, _record)
    _flag["set"] = False
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextmanager
def polled():
    """Inside the block SIGINT only sets the flag that `pending()` reads (a back end written in C++
    polls it from a Python callback, and an exception raised there would unwind through C++).
    On leaving it, a Ctrl-C that arrived is raised as the handler in force before would have:
    KeyboardInterrupt (the flag kept for the spine when `honoured()` is active), or that handler
    called. Main thread only (elsewhere no signal arrives), and not while SIGINT is ignored or
    handled outside Python: there the block runs as it is."""
    in_c = signal.getsignal(signal.SIGINT) is None          # a handler set outside Python: left alone
    if threading.current_thread() is not threading.main_thread() or in_c or \
            signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        yield
        return
    outer = signal.signal(signal.SIGINT, _note)
    arrived = _flag["set"]
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, outer)
    if _flag["set"] and not arrived:
        _pass_on(outer)


def _pass_on(outer) -> None:
    """Hand a Ctrl-C recorded by `polled()` to the handler that was in force outside it."""
    if outer is _record:
        raise KeyboardInterrupt
    _flag["set"] = False
    if outer is signal.SIG_DFL:
        signal.raise_signal(signal.SIGINT)
    elif callable(outer):
        outer(signal.SIGINT, None)


def abandon(worker: threading.Thread) -> None:
    """Record a worker thread left running in C code after Ctrl-C (its result is never read)."""
    _abandoned.append(worker)


def abandoned() -> bool:
    """Whether a worker left behind by Ctrl-C is still running: the process should then end with
    os._exit, as the interpreter's clean-up would run beside it."""
    return any(worker.is_alive() for worker in _abandoned)
