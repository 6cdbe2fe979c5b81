"""Figures of solved scenes, one module per mechanism, each registering its functions per task
class (see `registry`); `sweep` draws the maps of a sweep table. Every module is imported here,
by name: a broken one is an import error, never a silently missing figure."""
from mechopt.figures import cam_cutter, cam_shape, loom, press, stop_impact  # noqa: F401  (they register)
from mechopt.figures.registry import FIGURES, figures_of, register

__all__ = ["FIGURES", "figures_of", "register"]
