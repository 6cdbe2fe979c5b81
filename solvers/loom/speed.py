"""Old path of mechopt.solvers.cyclogram.speed, kept for one release: the same module."""
import sys

from mechopt.solvers.cyclogram import speed

sys.modules[__name__] = speed
