"""Where a model leaves what its source or its own derivation supports: the sentences of a
Result's `warnings`. The answer stands; the warning says how far to trust it.

Each model says its own: a task class with a method `warnings(self, values) -> list[str]` (its
inputs and the result's `values`) is asked after every solve; a class without one has none. The
ranges are data, given by the scene (eq. (1)'s fitted travel, the speeds a lever's law was studied
at) or following from the model's derivation; a range the scene does not state is not checked.
"""
from typing import Protocol, runtime_checkable


@runtime_checkable
class Warns(Protocol):
    """A model that says where its answer leaves what its source supports."""

    def warnings(self, values: dict) -> list[str]: ...


def out_of_range(task, values: dict) -> tuple[str, ...]:
    """Every warning for a task (the model's inputs) and its result's `values`; none for a model
    that states none."""
    return tuple(task.warnings(values)) if isinstance(task, Warns) else ()
