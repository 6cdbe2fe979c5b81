"""Old path of mechopt.solvers.cyclogram.kernel, kept for one release: the same module."""
import sys

from mechopt.solvers.cyclogram import kernel

sys.modules[__name__] = kernel
