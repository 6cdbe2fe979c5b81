"""Old path of mechopt.solvers.cyclogram.graph, kept for one release: the same module."""
import sys

from mechopt.solvers.cyclogram import graph

sys.modules[__name__] = graph
