"""HiGHS as the package runs it.

Banner: HiGHS writes its licence banner ("Running HiGHS ... Copyright ...") to the C-level stdout
when the first Highs object of a process is made, before any option (output_flag, log_to_console)
can be set on it. Stdout is for results (`mechopt run ... | grep`, `--json -`) and stderr for what
the user must read, so the banner is printed nowhere: the first object is made with descriptor 1
on the null device (`quiet_banner`), when the first InterruptibleHighs is made (cvxpy's too, see
below), so a command that solves no LP makes no HiGHS object at all. The licence notice is in the
README's third-party notices.

Ctrl-C: a large LP runs for tens of seconds inside HiGHS' C++, where Python's signal handlers
cannot run, so Ctrl-C used to be honoured only when the LP returned. `InterruptibleHighs` asks
HiGHS to call back at every simplex, IPM and MIP iteration (its user-interrupt callbacks); the
callback runs Python, so the SIGINT handler runs there, and the callback stops the solve when a
Ctrl-C is pending. SIGINT meanwhile only records itself (`interrupt.polled`: an exception raised
inside the callback would unwind through C++), and the KeyboardInterrupt is raised when `run`
returns, so an interrupted LP never hands its partial result to anyone. HiGHS' presolve polls no
callback, and on an event-time LP it does nearly all the work (a 100,000-row LP: 30 s of presolve,
no simplex iteration), so an LP of THREADED_ROWS rows or more runs in a worker thread (HiGHS
releases the GIL) while the main thread waits where a signal reaches it: on Ctrl-C the
KeyboardInterrupt is raised at once, and the worker, told to stop, is abandoned to finish its
presolve unread (`interrupt.abandoned`; the command then ends with os._exit). cvxpy's HIGHS
interface makes its `highspy.Highs()` itself: `interruptible_everywhere` points that name here.
"""
import functools
import os
import sys
import threading

import highspy

from mechopt.kit import interrupt

# functools.cache lets threads that arrive together all run the body: two swaps of descriptor 1
# interleaved would save the other's stderr as "stdout" and leave it there
_SWAPPING = threading.Lock()

# HiGHS' callbacks polled once per iteration of each algorithm; setting user_interrupt stops it
INTERRUPT_CALLBACKS = ("cbSimplexInterrupt", "cbIpmInterrupt", "cbMipInterrupt")
RealHighs = highspy.Highs           # the class before `interruptible_everywhere` points the name here
THREADED_ROWS = 5000                # an LP this large runs beside the main thread (a count: never a clock)
WAIT_S = 0.05                       # how often the waiting main thread looks whether Ctrl-C came


def _stop_if_interrupted(event) -> None:
    """HiGHS' interrupt callback: stop the solve when Ctrl-C is pending or its run was abandoned
    (the spine may have consumed the Ctrl-C since)."""
    if interrupt.pending() or event.user_data.is_set():
        event.interrupt()


class InterruptibleHighs(RealHighs):
    """A Highs whose `run` stops within an iteration of Ctrl-C and then raises KeyboardInterrupt."""

    def __init__(self):
        quiet_banner()
        super().__init__()
        self.abandoned = threading.Event()
        self.worker = None
        for name in INTERRUPT_CALLBACKS:
            getattr(self, name).subscribe(_stop_if_interrupted, self.abandoned)

    def run(self):
        if self.worker is not None:             # a run abandoned by Ctrl-C may still hold this model
            self._reclaim()
        if self.getNumRow() < THREADED_ROWS or threading.current_thread() is not threading.main_thread():
            with interrupt.polled():
                return super().run()
        return self._run_beside()

    def _run_beside(self):
        """`run` in a worker thread, the main thread waiting where Ctrl-C reaches it."""
        outcome = {}
        worker = threading.Thread(target=lambda: outcome.setdefault("status", RealHighs.run(self)),
                                  name="highs-run", daemon=True)
        with interrupt.polled():                # before the start: a Ctrl-C from now on finds the worker
            worker.start()
            while worker.is_alive() and not interrupt.pending():
                worker.join(WAIT_S)
            self.worker = worker
            if worker.is_alive():
                self.abandoned.set()            # its callbacks stop it at the next iteration
                interrupt.abandon(worker)
        self._reclaim()                         # here only when the handler outside let the Ctrl-C pass
        return outcome["status"]

    def _reclaim(self):
        """Wait for an abandoned run to end, and let the next run go uninterrupted."""
        self.worker.join()
        self.worker = None
        self.abandoned.clear()


@functools.cache
def interruptible_everywhere() -> None:
    """Make every Highs made from here on (cvxpy's too: it calls `highspy.Highs()` at each solve)
    an `InterruptibleHighs` (once)."""
    highspy.Highs = InterruptibleHighs


@functools.cache
def quiet_banner() -> None:
    """Make the process's first Highs object with file descriptor 1 on the null device (once): its
    banner goes nowhere, and HiGHS prints it for no later object."""
    with _SWAPPING:
        sys.stdout.flush()
        saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, 1)
            RealHighs()
        finally:
            os.dup2(saved, 1)
            os.close(saved)
            os.close(null)


# HiGHS' model statuses as a Status: the same words cvxpy's table (HIGHS.STATUS_MAP) and
# `from_cvxpy` give (a test holds the two equal), without importing cvxpy (0.9 s of CPU) where
# nothing else needs it. Only kOptimal is SOLVED; kUnknown, a solve error, kUnboundedOrInfeasible
# and anything else not named here are FAILED.
HIGHS_STATUS = {"kOptimal": "SOLVED", "kInfeasible": "INFEASIBLE", "kUnbounded": "UNBOUNDED",
                "kIterationLimit": "LIMIT", "kTimeLimit": "LIMIT", "kObjectiveBound": "LIMIT",
                "kObjectiveTarget": "LIMIT", "kSolutionLimit": "LIMIT"}


def status_of(highs):
    """A Highs object's model status after `run` as a Status (`HIGHS_STATUS`)."""
    from mechopt.kit.result import Status
    return Status(HIGHS_STATUS.get(highs.getModelStatus().name, "FAILED"))
