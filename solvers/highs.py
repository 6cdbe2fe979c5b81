"""HiGHS writes its banner ("Running HiGHS ...") to the C-level stdout when the first Highs object of
a process is made, whatever its output_flag; cvxpy's HIGHS interface does the same. Stdout is for
results (`mechopt run ... | grep`, `--json -`): make that first object with stdout pointed at stderr."""
import functools
import os
import sys
import threading

import highspy

# functools.cache lets threads that arrive together all run the body: two swaps of descriptor 1
# interleaved would save the other's stderr as "stdout" and leave it there
_SWAPPING = threading.Lock()


@functools.cache
def banner_to_stderr() -> None:
    """Make the process's first Highs object with file descriptor 1 on stderr (once)."""
    with _SWAPPING:
        sys.stdout.flush()
        saved = os.dup(1)
        try:
            os.dup2(2, 1)
            highspy.Highs()
        finally:
            os.dup2(saved, 1)
            os.close(saved)
