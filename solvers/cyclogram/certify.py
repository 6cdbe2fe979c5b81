"""One method's result certified by the other's: the same status, the same objective to tol_deg,
the same sensitivities where the dual is unique (else both between the one-sided derivatives)."""
import dataclasses

from mechopt.kit.result import Result, Status

# a limit a sens_* is taken with respect to: its task field (window and cycle duals are compared as they are)
SENS_LIMITS = {"sens_sigma_H_deg_per_MPa": "sigma_H_limit_MPa", "sens_amplitude_limit_deg_per_mm": "amplitude_limit_mm"}
ONE_SIDED_STEP = 1e-6          # relative step of the limit for the one-sided derivatives


def one_sided_sensitivity(task, key, solve, at: Result) -> tuple[float, float] | None:
    """d(objective)/d(limit) from below and from above, by `solve` (the graph) at the limit -+ h:
    where two bounds tie at the optimum they differ, and every value between them is a dual (the
    LP and the graph may each return a different one); `at` is the solved result at the limit.
    None for a sens_* of no scalar limit."""
    field = SENS_LIMITS.get(key)
    limit = getattr(task, field, None) if field else None
    if limit is None:
        return None
    h = ONE_SIDED_STEP * max(1.0, abs(limit))
    spans = []
    for value in (limit - h, None, limit + h):
        r = at if value is None else solve(dataclasses.replace(task, **{field: value}))
        if r.status is not Status.SOLVED:
            return None
        spans.append(r.values.get("limiting_op_deg", r.values["span_deg"]))
    return (spans[1] - spans[0]) / h, (spans[2] - spans[1]) / h


def _between(x, sides, rtol=1e-4):
    lo, hi = min(sides), max(sides)
    return lo - rtol * max(1.0, abs(lo)) <= x <= hi + rtol * max(1.0, abs(hi))


def certify(result: Result, other: Result, tol_deg: float, one_sided=None) -> Result:
    """`result` checked against the other method's `other`: the same status, objective to
    tol_deg (per degree above 1) and, where the critical chain is unique, the same sens_*; where
    `one_sided(key)` gives a limit's derivatives from below and above that differ (two bounds tie:
    the dual is not unique), both sens_* must lie between them instead (named in
    diagnostics["sens_not_unique"]). A mismatch makes it INACCURATE, named in the message."""
    name = "limiting_op_deg" if "limiting_op_deg" in result.values else "span_deg"
    diagnostics = result.diagnostics | {"check": other.diagnostics.get("method", "?"), "check_status":
                                        other.status.value}
    problems, values = [], result.values
    if other.status is not result.status:
        problems.append(f"{other.diagnostics.get('method')} says {other.status.value}")
    elif result.status is Status.SOLVED:
        mine, theirs = result.values[name], other.values[name]
        values = values | {"check_rel": abs(mine - theirs) / max(1.0, abs(theirs))}    # validate's certificate
        if not abs(mine - theirs) <= tol_deg * max(1.0, abs(theirs)):
            problems.append(f"{name} {mine!r} against {theirs!r}")
        chain = result.diagnostics.get("critical_chain", [])
        if len(result.diagnostics.get("critical_ops", ())) == max(len(chain) - 1, 0) > 0:
            for key in (k for k in result.values if k.startswith("sens_")):
                mine_s, theirs_s = result.values[key], other.values.get(key)
                if theirs_s is None or abs(mine_s - theirs_s) <= 1e-6 * max(1.0, abs(theirs_s)):
                    continue
                sides = one_sided(key) if one_sided else None
                if sides and _between(mine_s, sides) and _between(theirs_s, sides):
                    diagnostics.setdefault("sens_not_unique", {})[key] = list(sides)
                    continue
                problems.append(f"{key} {mine_s!r} against {theirs_s!r}")
        diagnostics["check_abs_deg"] = abs(mine - theirs)
    return certified(result, values, diagnostics, problems, by=diagnostics["check"])


def certified(result, values, diagnostics, problems, *, by) -> Result:
    """`result` with its certificate's outcome: checked `by` the other method when `problems` is
    empty; else INACCURATE, whichever said what (the methods disagree: an INFEASIBLE the LP solves
    too is not certified either), the disagreements named."""
    if not problems:
        return dataclasses.replace(result, values=values, diagnostics=diagnostics,
                                   message=result.message + f"; checked by {by}")
    status = Status.INACCURATE if result.status in (Status.SOLVED, Status.INFEASIBLE) else result.status
    return dataclasses.replace(result, status=status, values=values, diagnostics=diagnostics,
                               message=result.message + "; check failed: " + ", ".join(problems))
