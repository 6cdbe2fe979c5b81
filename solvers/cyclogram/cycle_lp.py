"""The least cycle time's certificate: the LP in (p, T), minimise T (cvxpy and HiGHS or
Clarabel), and a graph result checked against it (check = true)."""
from mechopt.kit.result import Result, Status, from_cvxpy
from mechopt.solvers.cyclogram.certify import certified
from mechopt.solvers.cyclogram.cycle_uniform import Uniform

CHECK_RTOL = 1e-9            # the LP's least T against the graph's, relative (per unit above 1)


def cycle_time_lp(u: Uniform, backend: str = "HIGHS"):
    """(status, least T or None): minimise T over (p, T) s.t. D p >= d - k T, T >= 0, p(0) = 0."""
    import cvxpy as cp  # the certificate alone needs it: the graph does not wait for it

    from mechopt.solvers.cyclogram.event_time import incidence
    n = len(u.names)
    p, T = cp.Variable(n, name="p"), cp.Variable(nonneg=True, name="T")
    cons = [p[0] == 0]
    if len(u.tails):
        cons.append(incidence(n, u.tails, u.heads) @ p + T * u.k >= u.d)
    problem = cp.Problem(cp.Minimize(T), cons)
    try:
        problem.solve(solver=backend)
    except cp.error.SolverError as exc:
        return Status.FAILED, None, str(exc)
    status = from_cvxpy(problem.status)
    return status, (float(T.value) if status is Status.SOLVED else None), problem.status


def checked_by_lp(result: Result, u: Uniform, name: str, backend: str) -> Result:
    """`result` with the LP's answer beside it: the same status and T to CHECK_RTOL (per unit above 1)."""
    status, T, said = cycle_time_lp(u, backend)
    diagnostics = result.diagnostics | {"check": {"method": f"lp ({backend})", "status": status.value,
                                                  "solver_status": said}}
    values, problems = result.values, []
    if status is not result.status:
        problems.append(f"the LP says {status.value} ({said})")
    elif status is Status.SOLVED:
        rel = abs(result.values[name] - T) / max(1.0, abs(T))
        values = values | {"check_rel": rel}
        diagnostics["check"] |= {name: T, "rel": rel}
        if not rel <= CHECK_RTOL:
            problems.append(f"{name} {result.values[name]!r} against the LP's {T!r}")
    return certified(result, values, diagnostics, problems, by=f"the LP ({backend})")
