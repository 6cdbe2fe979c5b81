"""Which figures a solved scene has: one function per solver, registered with `@figure(solver)`.

A figure function takes a `Run` and returns `{name: matplotlib Figure}`, empty when the result has
nothing to draw (an infeasible scan). It draws the Result as it is: the arrays and values the
solver returned (named with units), the scene's id and the limits the task states for labels; it
computes nothing (what a picture needs that the solver did not return goes into that solver's
`Result.arrays`). It writes no file and touches no pyplot state: `save_figure` saves, and a
notebook shows the figures as they are.

Which function draws a run is found by the run's solver (the function its scene names), never by
looking at which values the result happens to hold.
"""
import importlib
from collections.abc import Callable

from mechopt.kit.errors import MechoptError
from mechopt.kit.registrar import by_solver
from mechopt.mechanisms import mechanisms

FIGURES: dict[Callable, Callable] = {}


figure = by_solver(FIGURES, "figure", "draws")
figure.__doc__ = "Register a figure function for these solver functions (one figure function per solver)."


def register(*task_classes):
    """The old registration by task class: gone, so that a figure module written for it fails at
    import, never silently draws nothing."""
    names = ", ".join(getattr(c, "__name__", repr(c)) for c in task_classes)
    raise MechoptError(f"@register({names}): figures are registered by solver now; write "
                       f"@figure(solver_fn, ...) with the solver functions the scenes name "
                       f"(from mechopt.figures.registry import figure)")


def import_rows() -> None:
    """Import every row's figure (and output) modules of `mechopt.mechanisms`: each registers its
    functions. Read at each call, so a row added since the last is read too; a broken module is
    an import error, never a silently missing figure."""
    for name in (n for m in mechanisms() for n in m.figures):
        importlib.import_module(name)


def figures_of(run) -> dict:
    """The figures of a solved scene, by name; an error when its solver has none registered."""
    import_rows()
    solver = run.scene.solver
    if solver not in FIGURES:
        raise MechoptError(f"no figures registered for solver {_name(solver)} (scene {run.scene.id}); "
                           f"register a function in mechopt/figures/ with @figure({solver.__name__})")
    return FIGURES[solver](run)


def new_figure(**options):
    """A matplotlib Figure outside pyplot (nothing global to close, safe in sweeps and notebooks)."""
    from matplotlib.figure import Figure
    return Figure(**options)


def _name(solver) -> str:
    return f"{solver.__module__}.{getattr(solver, '__qualname__', solver)}"
