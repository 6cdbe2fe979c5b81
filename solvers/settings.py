"""Allowed ranges of solver settings, declared in the solver's own signature and checked when a
scene is loaded or a `--set` is given, before anything runs:

    def events(task, *, tol: Tolerance = 1e-10, samples: Annotated[int, Interval(ge=1, le=10_000)] = 8)

The scene loader reads the `annotated_types` constraints (Gt, Ge, Lt, Le, Interval) and names
the range in its error; `mechopt describe` lists it.
"""
from typing import Annotated

from annotated_types import Ge, Gt, Interval, Le

Positive = Annotated[float, Gt(0)]
NonNegative = Annotated[float, Ge(0)]
Tolerance = Annotated[float, Interval(gt=0, le=0.1)]        # relative or absolute, of an iterative method
Count = Annotated[int, Interval(ge=1, le=10_000_000)]

__all__ = ["Positive", "NonNegative", "Tolerance", "Count", "Ge", "Gt", "Interval", "Le", "Annotated"]
