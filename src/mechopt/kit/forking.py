"""A child process forked after HiGHS has run must not inherit its scheduler mid-work.

HiGHS keeps a global pool of worker threads whose executor is guarded by a mutex. `fork()` copies
only the calling thread: a child forked while a worker held that mutex inherits it locked with no
thread to release it, and hangs at exit in the executor's thread-local destructor (seen as a
`mechopt run` fork that never ended: `HighsTaskExecutor::ExecutorHandle::dispose` waiting on a
futex). A process pool started after a solve (a sweep's workers, Dask's forked workers) is such a
child. So before every fork the parent stops HiGHS' workers (blocking until they have); the next
solve in the parent starts them again. Nothing is done where highspy was never imported."""
import os
import sys


def stop_highs_workers() -> None:
    highspy = sys.modules.get("highspy")
    if highspy is not None:
        highspy.Highs.resetGlobalScheduler(True)


if hasattr(os, "register_at_fork"):          # POSIX; Windows spawns and never forks
    os.register_at_fork(before=stop_highs_workers)
