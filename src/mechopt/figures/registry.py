"""Which figures a solved scene has: one function per task class, registered by name.

A figure function takes a `Run` (its scene, result, task and settings) and returns
`{name: matplotlib Figure}`, empty when the result has nothing to draw (an infeasible scan). It
writes no file and touches no pyplot state: `mechopt.plots.plot_run` saves the figures, and a
notebook shows them as they are.
"""
from collections.abc import Callable

from mechopt.errors import MechoptError

FIGURES: dict[type, Callable] = {}


def register(*task_classes: type) -> Callable:
    """Register a figure function for these task classes (one function per class)."""
    def wrap(draw):
        for cls in task_classes:
            if cls in FIGURES:
                raise MechoptError(f"figures for {cls.__name__} registered twice: {FIGURES[cls].__name__} "
                                   f"and {draw.__name__}")
            FIGURES[cls] = draw
        return draw
    return wrap


def figures_of(run) -> dict:
    """The figures of a solved scene, by name; an error when its task class has none registered."""
    cls = run.scene.task_class
    if cls not in FIGURES:
        raise MechoptError(f"no figures registered for task {cls.__module__}.{cls.__name__} "
                           f"(scene {run.scene.id}); register a function in mechopt/figures/ with "
                           f"@register({cls.__name__})")
    return FIGURES[cls](run)


def new_figure(**options):
    """A matplotlib Figure outside pyplot (nothing global to close, safe in sweeps and notebooks)."""
    from matplotlib.figure import Figure
    return Figure(**options)
