"""Ctrl-C that a back end cannot swallow.

CasADi runs IPOPT, CVODES and its rootfinders in C++ and polls Python's signal handlers from
there: the KeyboardInterrupt the default handler raises is caught inside and comes back as a
failed or "inaccurate" solve (issue 21: an interrupted sweep stored such a variant, and a re-run
skipped it). While `honoured()` is active, SIGINT also sets a flag that no back end can clear;
`check()` turns it back into a KeyboardInterrupt. The spine (run, validate, sweep, report) calls
`check()` after every solver call, so an interrupted solve is never stored or reported; a solver
may call it after a CasADi call inside a loop, so that it stops at once rather than at its end.
"""
import signal
import threading
from contextlib import contextmanager

__all__ = ["honoured", "check", "pending"]

_flag = {"set": False}


def _record(signum, frame):
    _flag["set"] = True
    raise KeyboardInterrupt


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
