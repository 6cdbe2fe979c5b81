"""Registration by solver: a figure module or a DXF writer says which solver functions' results
it draws (`@figure(solver)`, `@shop_drawing(solver)`), and the spine looks it up by the scene's solver."""
from collections.abc import Callable

from mechopt.kit.errors import MechoptError


def by_solver(table: dict, decorator: str, what: str) -> Callable:
    """A registering decorator, `@<decorator>(solver, ...)`, putting a function into `table` for
    each of these solver functions (one per solver): figures here, DXF writers in mechopt.dxf."""
    def register_for(*solvers: Callable) -> Callable:
        if not solvers or not all(callable(s) for s in solvers):
            raise MechoptError(f"@{decorator} takes the solver functions whose results it {what}, got {solvers!r}")

        def wrap(fn):
            for solver in solvers:
                if solver in table:
                    raise MechoptError(f"{decorator} functions for solver {_name(solver)} registered twice: "
                                       f"{table[solver].__name__} and {fn.__name__}")
                table[solver] = fn
            return fn
        return wrap
    return register_for


def _name(solver) -> str:
    return f"{solver.__module__}.{solver.__qualname__}"
