"""A package's door that imports each of its names when first used (PEP 562), so that using one
solver never waits for another's back end (CasADi, cvxpy) to import.

    from typing import TYPE_CHECKING
    from mechopt.kit.lazy import lazy_names

    if TYPE_CHECKING:                       # for readers, type checkers and the docs
        from mechopt.solvers.loom.plan import plan_cyclogram
    __getattr__, __dir__ = lazy_names(__name__, {"plan": ["plan_cyclogram"]})
"""
import importlib
import sys


def lazy_names(package: str, modules: dict[str, list[str]]):
    """The module-level `__getattr__` and `__dir__` of `package`: each name of `modules`
    (submodule -> the names it defines) is imported from `package.submodule` on first use, then
    kept in the package as if imported at its top."""
    where = {name: module for module, names in modules.items() for name in names}

    def __getattr__(name: str):
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{where[name]}"), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(where))
    return __getattr__, __dir__
