"""A scene's expectations against its result: each check's verdict (reproduced, calibrated, a
declared miss, ...) and their tally, as `validate`, `run` and the report show them."""
from dataclasses import dataclass
from typing import Any

from mechopt.kit.result import Result, Status

# Every check's verdict, the misses first: the order in which validate lists and counts them.
VERDICTS = ("failed", "unexpectedly_reproduced", "not_reproduced", "not_reproducible",
            "reproduced", "alternative", "calibrated", "derived", "follows")
MISSES = VERDICTS[:4]


@dataclass(frozen=True)
class Check:
    """One expectation against the result. `verdict` says what it shows:
    reproduced (a figure of the source, met by a model not fitted to it), alternative (a figure met under
    a reading that excludes the one the scene `alternative_to` names takes: reported, not counted as a
    reproduction), calibrated (agreement by construction), derived (an independent computation, a bound
    or a status), follows (a row that restates what the status certifies: it cannot fail while SOLVED),
    not_reproduced (a declared miss: computed, outside the tolerance), not_reproducible (the source lacks
    what is needed), failed, or unexpectedly_reproduced (a declared miss that now passes: the
    declaration is to be corrected).
    `ok` is whether validation passes it: a declared miss does, as pytest's xfail."""
    name: str
    expected: str            # as the scene states it: "1.5 ± 0.01", "<= 0.2", "INFEASIBLE"
    got: Any                 # float, status word, or None when the solver did not produce it
    tol: float | None
    ok: bool
    kind: str                # published | experimental | derived
    where: str
    calibrated: bool = False  # fitted to this value, or it follows from a fit: agreement by construction
    verdict: str = "derived"
    reason: str = ""          # why a declared miss is missed
    gap: float | None = None  # (got - expected) / |expected|, where both are numbers
    readings_after_figure: tuple[str, ...] = ()   # readings chosen with the published figure in view
    alternative_to: str = ""  # the scene whose reading excludes this row's (verdict alternative)

    def as_dict(self):
        return {"name": self.name, "expected": self.expected, "got": self.got, "tol": self.tol,
                "ok": self.ok, "verdict": self.verdict, "kind": self.kind, "where": self.where,
                "calibrated": self.calibrated, "reason": self.reason, "gap": self.gap,
                "readings_after_figure": list(self.readings_after_figure), "alternative_to": self.alternative_to}

    @property
    def label(self) -> str:
        """The verdict as a table shows it."""
        if self.verdict == "not_reproduced" and self.gap is not None:
            return f"not reproduced ({self.gap:+.1%})"
        if self.verdict == "reproduced" and self.readings_after_figure:
            return "reproduced (readings chosen after the figure)"
        if self.verdict == "alternative":
            return f"alternative (the reading taken: {self.alternative_to})"
        return self.verdict.replace("_", " ")


def verdict_of(exp, met: bool, calibrated: bool) -> str:
    """The verdict of an expectation `exp` whose comparison gave `met`."""
    if exp.verdict == "not_reproducible":
        return "not_reproducible"
    if exp.verdict == "not_reproduced":
        return "unexpectedly_reproduced" if met else "not_reproduced"
    if not met:
        return "failed"
    if exp.kind == "follows":
        return "follows"
    if calibrated:
        return "calibrated"
    if exp.alternative_to:
        return "alternative"
    return "reproduced" if exp.kind in ("published", "experimental") else "derived"


def tally(checks) -> dict[str, int]:
    """How many checks carry each verdict (see `Check`), in the order of `VERDICTS`."""
    verdicts = [c.verdict for c in checks]
    return {v: verdicts.count(v) for v in VERDICTS}


def summary_line(checks) -> str:
    """One line: the counts per verdict, the misses first."""
    checks = list(checks)
    counts = tally(checks)
    after = sum(c.verdict == "reproduced" and bool(c.readings_after_figure) for c in checks)
    parts = [f"{counts[v]} {v.replace('_', ' ')}" + (f" ({after} with readings chosen after the figure)"
                                                    if v == "reproduced" and after else "")
             for v in VERDICTS if counts[v] or v in ("failed", "not_reproduced", "reproduced")]
    return f"{len(checks)} checks: " + ", ".join(parts)


def calibrated_on(spec) -> set[str]:
    """Values some parameter of a scene file (`SceneFile`) was fitted to: their checks are
    calibrations, not reproductions."""
    return {p.on for p in spec.params.values() if p.mark == "calibrated"}


def check(spec, result: Result) -> list[Check]:
    """Each expectation of a scene file (`SceneFile`) against the result. A number counts only from a
    SOLVED result, or from the status the scene itself expects (an INFEASIBLE best-achievable value)."""
    expected_status = spec.expect.get("status")
    trusted = result.status is Status.SOLVED or (expected_status is not None
                                                 and result.status.value == expected_status.value)
    out = []
    fitted_to = calibrated_on(spec)
    for name, exp in spec.expect.items():
        got = None if exp.verdict == "not_reproducible" else (
            result.status.value if name == "status" else result.values.get(exp.of or name))
        got = None if got is None else (got if isinstance(got, str) else float(got))
        numeric = isinstance(exp.value, (int, float)) and not isinstance(exp.value, bool)
        tol = max(exp.abs or 0.0, (exp.rel or 0.0) * abs(exp.value)) if numeric and exp.verdict != "not_reproducible" else None
        met = exp.check(got) and (name == "status" or trusted)
        calibrated = name in fitted_to or bool(exp.follows)
        verdict = verdict_of(exp, met, calibrated)
        # a declared miss must still be computed: a missing value is a failure, not the declared miss
        if verdict == "not_reproduced" and (got is None or not (name == "status" or trusted)):
            verdict = "failed"
        gap = (got - exp.value) / abs(exp.value) if numeric and isinstance(got, float) and exp.value else None
        out.append(Check(name, exp.describe(), got, tol, verdict not in ("failed", "unexpectedly_reproduced"),
                         exp.kind, exp.where, calibrated, verdict, exp.reason, gap, tuple(exp.readings_after_figure),
                         exp.alternative_to))
    return out
