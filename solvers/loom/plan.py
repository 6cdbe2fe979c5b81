"""Old path of mechopt.solvers.cyclogram.plan, kept for one release: the same module."""
import sys

from mechopt.solvers.cyclogram import plan

sys.modules[__name__] = plan
