"""Old path of mechopt.solvers.cyclogram.motions, kept for one release: the same module."""
import sys

from mechopt.solvers.cyclogram import motions

sys.modules[__name__] = motions
