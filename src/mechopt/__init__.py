"""mechopt: formal optimisation models for machine mechanisms, from published studies.

The Python API (the `mechopt` command does the same from a terminal)::

    import mechopt
    scene = mechopt.load("cam-cutter/minimax")         # a registry id, or a scene file's path
    run = mechopt.solve(scene, a_mm=40, h_mm=3)         # overrides are validated like the file
    run.status, run.values["H_mm"], run.with_units()    # values carry their unit in the name
    run.arrays                                          # what the solver computed along the way
    run.figures()                                       # matplotlib Figures, by name (no files)
    mechopt.describe(scene)                             # every key you can override, unit, range

`mechopt.scenes()` lists the registry (the package's scenes plus `add_cases(folder)` and the
MECHOPT_CASES folders); `mechopt.sweep.sweep` runs what-if studies; `mechopt.clear_caches()`
drops every solver build kept in this process. Where a mechanism has several methods, one door
takes `method=`: `mechopt.solvers.press.simulate`, `mechopt.solvers.cam_cutter.fit_linkage`,
`mechopt.solvers.stop_impact.rebound`.
"""
from importlib.metadata import PackageNotFoundError, version

from mechopt.models.cache import clear as clear_caches
from mechopt.models.errors import MechoptError, ModelError, SceneError, SolverError
from mechopt.registry import Run, add_cases
from mechopt.registry import all_scenes as scenes
from mechopt.registry import find as load
from mechopt.solvers.result import Result, Status

try:
    __version__ = version("mechopt")
except PackageNotFoundError:        # imported from a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["load", "solve", "describe", "scenes", "add_cases", "clear_caches", "Run", "Result", "Status",
           "MechoptError", "ModelError", "SceneError", "SolverError", "__version__"]


def solve(scene, overrides: dict | None = None, **more) -> Run:
    """Solve a scene (a Scene, a registry id or a scene file's path) with overrides of its
    parameters, solver settings or structure paths, given as a dict or as keywords; returns the
    Run (status, values, arrays, checks, figures). The source's checks are made only when no
    parameter was changed."""
    from mechopt import registry
    return registry.run(scene, {**(overrides or {}), **more})


def describe(scene) -> list[dict[str, str]]:
    """Every key an override reaches, with its kind, unit, mark, allowed range and current value."""
    return load(scene).describe()
