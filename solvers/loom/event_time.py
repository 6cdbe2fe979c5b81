"""Old path of mechopt.solvers.cyclogram.event_time, kept for one release: the same module."""
import sys

from mechopt.solvers.cyclogram import event_time

sys.modules[__name__] = event_time
