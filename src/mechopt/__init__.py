"""mechopt: formal optimisation models for machine mechanisms, from published studies.

The Python API (the `mechopt` command does the same from a terminal)::

    import mechopt
    scene = mechopt.load("cam-cutter/minimax")         # a registry id, or a scene file's path
    run = mechopt.solve(scene, a_mm=40, h_mm=3)         # overrides are validated like the file
    run.status, run.values["H_mm"], run.with_units()    # values carry their unit in the name
    run.arrays                                          # what the solver computed along the way
    run.figures()                                       # matplotlib Figures, by name (no files)
    mechopt.describe(scene)                             # every key you can override, unit, range
    run.success, run.ok                                 # SOLVED?; the answer asked for, checks passed?
    table = mechopt.sweep("loom/group1", grid={"amplitude_limit_mm": (0.05, 0.2, 31)})   # pyarrow Table

`mechopt.scenes()` lists the registry (the package's scenes plus `add_cases(folder)` and the
MECHOPT_CASES folders); `mechopt.sweep` runs what-if studies (the module `mechopt.sweep`, callable,
holds the machinery: chunks, Dask, resuming a stopped sweep); `mechopt.clear_caches()`
drops every solver build kept in this process. Where a mechanism has several methods, one door
takes `method=`: `mechopt.solvers.press.simulate`, `mechopt.solvers.cam_cutter.fit_linkage`,
`mechopt.solvers.stop_impact.rebound`.
"""
import importlib
from typing import TYPE_CHECKING

from mechopt.kit import forking  # noqa: F401  (before any fork, HiGHS' workers stop: kit/forking.py)
from mechopt.kit.errors import MechoptError, ModelError, SceneError, SettingError, SolverError

if TYPE_CHECKING:       # for readers, type checkers and the docs; at run time __getattr__ imports each when used
    from mechopt import sweep
    from mechopt.api import describe, solve
    from mechopt.kit.cache import clear as clear_caches
    from mechopt.kit.result import Result, Status
    from mechopt.registry import Run, add_cases
    from mechopt.registry import all_scenes as scenes
    from mechopt.registry import find as load

__all__ = ["load", "solve", "sweep", "describe", "scenes", "add_cases", "clear_caches", "Run", "Result", "Status",
           "MechoptError", "ModelError", "SceneError", "SettingError", "SolverError", "__version__"]

# `import mechopt` is light (PEP 562): each name below imports its module when first used, so a
# script that needs the loom's graph never waits for CasADi, and `mechopt --version` for nothing
_LAZY = {"load": ("mechopt.registry", "find"), "scenes": ("mechopt.registry", "all_scenes"),
         "add_cases": ("mechopt.registry", "add_cases"), "Run": ("mechopt.registry", "Run"),
         "solve": ("mechopt.api", "solve"), "describe": ("mechopt.api", "describe"),
         "clear_caches": ("mechopt.kit.cache", "clear"), "Result": ("mechopt.kit.result", "Result"),
         "Status": ("mechopt.kit.result", "Status"), "sweep": ("mechopt.sweep", None)}


def __getattr__(name: str):
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version
        try:
            value = version("mechopt")
        except PackageNotFoundError:        # imported from a source tree that was never installed
            value = "0+unknown"
    elif name in _LAZY:
        module, attr = _LAZY[name]
        module = importlib.import_module(module)
        value = module if attr is None else getattr(module, attr)
    else:
        raise AttributeError(f"module 'mechopt' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
