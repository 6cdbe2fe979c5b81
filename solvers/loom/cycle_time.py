"""Old path of mechopt.solvers.cyclogram.cycle_time, kept for one release: the same module."""
import sys

from mechopt.solvers.cyclogram import cycle_time

sys.modules[__name__] = cycle_time
