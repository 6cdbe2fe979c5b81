"""Figures of solved scenes: each mechanism's figure modules (named by its row in
`mechopt.mechanisms`) and `sweep`, the maps of a sweep table; `files` saves them.

A figure function is registered for the solver functions whose Result it draws:

    from mechopt.figures.registry import figure, new_figure
    from mechopt.solvers.press import design, catalogue

    @figure(design, catalogue)          # one function per solver; a solver registered twice is an error
    def designed(run):
        a = run.result.arrays           # what the solver returned, named with units
        ...
        return {"design": fig}          # {name: matplotlib Figure}; {} when there is nothing to draw

It draws the Result only: what a picture needs and the solver does not return goes into that
solver's `Result.arrays`, never recomputed here. A scene whose solver has no figure function is an
error naming the `@figure(...)` to write. The old `@register(TaskClass)` raises at import.

Every module is imported here: a broken one is an import error, never a silently missing figure.
"""
from mechopt.figures.files import figures, plot_run, save_figure
from mechopt.figures.registry import FIGURES, figure, figures_of, import_rows

import_rows()           # each row's modules register their functions

__all__ = ["FIGURES", "figure", "figures", "figures_of", "plot_run", "save_figure"]
