"""The one result every solver returns, the clock that times it and builds it (a solver's one exit),
and the only code that knows back ends' status words."""
import html
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from enum import Enum

import numpy as np

from mechopt.kit.errors import SolverError


class Status(str, Enum):
    SOLVED = "SOLVED"
    INACCURATE = "INACCURATE"      # the back end stopped short of its tolerance: not an answer to trust
    INFEASIBLE = "INFEASIBLE"      # no point meets the limits; `values` hold the best achievable
    UNBOUNDED = "UNBOUNDED"
    LIMIT = "LIMIT"                # iteration, round or size limit reached
    FAILED = "FAILED"

    def __bool__(self) -> bool:
        """True for SOLVED only: `if result.status:` reads as "was it solved?" (a str Enum is
        otherwise always true, INFEASIBLE included)."""
        return self is Status.SOLVED


SHOWN = 4          # values a Result's repr names before "... N more"
MAX_MESSAGE = 10_000      # characters of a Result's message: a safety net under each solver's own bound
MAX_VIOLATED = 100        # names of broken limits a Result keeps; the message says how many more there were


def _bounded(message: str, violated: tuple) -> tuple[str, tuple]:
    """(message, violated) within MAX_MESSAGE characters and MAX_VIOLATED names, each cut saying
    how much was left out (an unbounded list printed 87 MB and wrote a 110 MB --json)."""
    if len(message) > MAX_MESSAGE:
        message = f"{message[:MAX_MESSAGE]}... (and {len(message) - MAX_MESSAGE:,} more characters)"
    if len(violated) > MAX_VIOLATED:       # said after the cut, so that the cut never hides it
        message += f" (violated names the first {MAX_VIOLATED} of {len(violated):,} broken limits)"
        violated = violated[:MAX_VIOLATED]
    return message, violated


@dataclass(frozen=True)
class Timing:
    build_s: float       # problem construction (0 when a cached build was reused)
    solve_s: float


@dataclass(frozen=True)
class Result:
    """What a solver found. `values` are named with their unit (`H_mm`) and are always finite:
    a quantity the solver could not determine is left out, never NaN."""
    status: Status
    values: dict[str, float]
    timing: Timing
    message: str = ""
    violated: tuple[str, ...] = ()              # physical names of broken limits
    diagnostics: dict = field(default_factory=dict)
    arrays: Mapping[str, np.ndarray] = field(default_factory=dict)
    """What the solver computed along the way, named with units (a run's `t_s` and states, a
    response's samples): what figures and notebooks read. The arrays are read-only copies: floats,
    or text in a label column that names a table's rows (`parameter`)."""
    warnings: tuple[str, ...] = ()
    """Plain sentences, one per way this answer leaves what its model's source or derivation
    supports (an extrapolated force law, a lever slower than its cycle): the answer stands, with them."""

    def __post_init__(self):
        bad = {k: v for k, v in self.values.items() if not math.isfinite(v)}
        if bad:
            raise SolverError(f"solver produced non-finite values {bad} (status {self.status.value})")
        # plain Python numbers, whatever the back end handed over: one type to print, compare and store
        object.__setattr__(self, "values", {k: v.item() if isinstance(v, np.generic) else v
                                            for k, v in self.values.items()})
        arrays = {}
        for name, array in self.arrays.items():
            labels = np.asarray(array)
            # a copy (the caller's array stays writable); text is a label column naming rows (a table's parameters)
            array = labels.astype(str) if labels.dtype.kind == "U" else np.array(array, dtype=float)
            array.flags.writeable = False
            arrays[name] = array
        object.__setattr__(self, "arrays", arrays)
        if isinstance(self.warnings, str) or not all(isinstance(w, str) for w in self.warnings):
            raise SolverError(f"warnings must be a tuple of sentences, got {self.warnings!r}")
        object.__setattr__(self, "warnings", tuple(dict.fromkeys(self.warnings)))
        message, violated = _bounded(str(self.message), tuple(self.violated))
        object.__setattr__(self, "message", message)
        object.__setattr__(self, "violated", violated)

    def with_warnings(self, more) -> "Result":
        """This result with more warnings (each sentence once)."""
        return replace(self, warnings=(*self.warnings, *more)) if more else self

    @property
    def success(self) -> bool:
        """Whether the solver reached an answer to trust (SOLVED), as scipy's `OptimizeResult.success`."""
        return self.status is Status.SOLVED

    def __repr__(self) -> str:
        """One line: status, the first values, how many more (the full dict is `values`)."""
        shown = ", ".join(f"{k}={v:.6g}" for k, v in list(self.values.items())[:SHOWN])
        more = f", ... {len(self.values) - SHOWN} more" if len(self.values) > SHOWN else ""
        return (f"Result({self.status.value}, values={{{shown}{more}}}"
                + (f", {len(self.arrays)} arrays" if self.arrays else "")
                + (f", message={self.message[:80]!r}" if self.message else "") + ")")

    def _repr_html_(self) -> str:
        """A notebook's view: the status and a table of the values (printed as the command prints them)."""
        rows = "".join(f"<tr><td>{html.escape(k)}</td><td title='{v!r}'>{html.escape(shown(v))}</td></tr>"
                       for k, v in self.values.items())
        return (f"<p><b>{self.status.value}</b> {html.escape(self.message)}</p>"
                f"<table><tr><th>value</th><th></th></tr>{rows}</table>")


class Clock:
    """The seconds of one solve as a Result reports them, and the Result built with them: the one
    exit of every solver. Started where the solve starts; what it counts as construction is
    `build_s` (marked by `built()`, or added to: a cache's own count, a sub-solve's), the rest solve_s.

        clock = Clock()
        problem = build(task)
        clock.built()
        ...
        return clock.result(status, values, message=message)
    """

    def __init__(self):
        self.start = time.perf_counter()
        self.build_s = 0.0

    def elapsed(self) -> float:
        """Seconds since the start (a phase timed on its own: `Clock()` at its start)."""
        return time.perf_counter() - self.start

    def built(self) -> None:
        """Construction ends now: the seconds since the start are build_s."""
        self.build_s = self.elapsed()

    def timing(self) -> Timing:
        return Timing(self.build_s, self.elapsed() - self.build_s)

    def result(self, status: Status, values: dict[str, float], *args, **kwargs) -> Result:
        """The Result of this solve, timed now; the other arguments are Result's own."""
        return Result(status, values, self.timing(), *args, **kwargs)


SIGNIFICANT = 6          # digits shown; the full value is the report cell's tooltip


def shown(value) -> str:
    """A value as the command line, the report and a notebook print it: a float to SIGNIFICANT
    digits, None as "-", anything else as its text."""
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{SIGNIFICANT}g}"
    return str(value)


_IPOPT = {
    "Solve_Succeeded": Status.SOLVED,
    "Solved_To_Acceptable_Level": Status.INACCURATE,   # CasADi counts this as success; we do not
    "Infeasible_Problem_Detected": Status.INFEASIBLE,
    "Diverging_Iterates": Status.UNBOUNDED,
    "Maximum_Iterations_Exceeded": Status.LIMIT,
    "Maximum_CpuTime_Exceeded": Status.LIMIT,
    "Maximum_WallTime_Exceeded": Status.LIMIT,
}


def from_ipopt(return_status: str) -> Status:
    """IPOPT's return_status (via CasADi's stats()) as a Status; anything unknown is FAILED."""
    return _IPOPT.get(return_status, Status.FAILED)


_CVXPY = {
    "optimal": Status.SOLVED,
    "optimal_inaccurate": Status.INACCURATE,       # never passed on as optimal
    "infeasible": Status.INFEASIBLE,
    "infeasible_inaccurate": Status.INACCURATE,
    "unbounded": Status.UNBOUNDED,
    "unbounded_inaccurate": Status.INACCURATE,
    "user_limit": Status.LIMIT,
}


def from_cvxpy(status: str) -> Status:
    """cvxpy's problem.status as a Status; a solver error or anything unknown is FAILED."""
    return _CVXPY.get(status, Status.FAILED)


def from_ivp(status: int) -> Status:
    """scipy's solve_ivp `status` as a Status: 0 reached the end, 1 stopped at a terminal event
    (both answers); -1 the step size fell below what the method can take: FAILED."""
    return {0: Status.SOLVED, 1: Status.SOLVED}.get(status, Status.FAILED)


_ROOTFINDER = {
    "success": Status.SOLVED,
    "max_iteration_reached": Status.LIMIT,
}


def from_rootfinder(return_status: str) -> Status:
    """CasADi rootfinder's stats()["return_status"] ("newton" plugin) as a Status; anything else FAILED."""
    return _ROOTFINDER.get(return_status, Status.FAILED)


_QUADPACK = (                                       # scipy.integrate.quad's messages (full_output=1)
    ("maximum number of subdivisions", Status.LIMIT),
    ("roundoff error", Status.INACCURATE),           # ier 2 and 4: the tolerance was not reached
    ("bad integrand behavior", Status.INACCURATE),
    ("does not converge", Status.INACCURATE),
    ("divergent", Status.FAILED),
    ("input is invalid", Status.FAILED),
)


def from_quadpack(message: str | None) -> Status:
    """scipy's quad message (returned instead of warned with full_output=1) as a Status;
    None means no message: converged. Anything unknown is FAILED."""
    if message is None:
        return Status.SOLVED
    return next((status for words, status in _QUADPACK if words in message), Status.FAILED)


_CVODES_LIMIT = ("CV_TOO_MUCH_WORK", "max_num_steps")


def from_casadi_integrator(error: str | None) -> Status:
    """A CasADi integrator call's outcome as a Status: it raises instead of returning a status,
    so this takes the error text (None: the call returned). Too many steps is LIMIT, any other
    failure (CV_CONV_FAILURE, CV_ERR_FAILURE, ...) FAILED."""
    if error is None:
        return Status.SOLVED
    return Status.LIMIT if any(word in error for word in _CVODES_LIMIT) else Status.FAILED


_SQPMETHOD = {
    "Solve_Succeeded": Status.SOLVED,
    "Maximum_Iterations_Exceeded": Status.LIMIT,
    "Search_Direction_Becomes_Too_Small": Status.INACCURATE,   # stopped short of its tolerances
}


def from_sqpmethod(return_status: str, success: bool) -> Status:
    """CasADi sqpmethod's stats() ("return_status", "success") as a Status: SOLVED only when
    CasADi calls it a success too; anything unknown is FAILED."""
    status = _SQPMETHOD.get(return_status, Status.FAILED)
    return status if success or status is not Status.SOLVED else Status.FAILED
