"""The highest speed by an LP: maximise n over (p, n) in cvxpy (method "lp", built once per
structure, DPP), and bisection on n with the event-time LP's feasibility held in HiGHS (method
"bisection"), certified by the longest-path certificate at n (1 - tol) and n (1 + tol)."""
import numpy as np

from mechopt.kit.result import Clock, Status, from_cvxpy
from mechopt.models.cyclogram_tables import MAX_RPM
from mechopt.solvers.cyclogram.conflicts import constraint_arcs, positive_cycle
from mechopt.solvers.cyclogram.event_time import HeldLP, incidence
from mechopt.solvers.cyclogram.lp_method import LP_BUILDS
from mechopt.solvers.cyclogram.speed_graph import Undecided

MIN_RPM = 1e-6                   # bisection: below it the machine is at rest


def speed_by_lp(task, net, phi, g, backend):
    """maximise n over (p, n): the LP of the docstring, built once per structure (DPP)."""
    import cvxpy as cp  # here: the graph and bisection methods never need it
    rows = np.flatnonzero(g > 0)
    key = ("speed", backend, len(net.names), net.tails.tobytes(), net.heads.tobytes(), net.first, net.last,
           rows.tobytes(), tuple(net.window_idx), tuple(net.sync_idx))

    def build():
        D = incidence(len(net.names), net.tails, net.heads)
        p, n = cp.Variable(len(net.names), name="p_deg"), cp.Variable(nonneg=True, name="n_rpm")
        prm = {"min_deg": cp.Parameter(len(net.tails), name="min_deg"),
               "g": cp.Parameter(len(rows), nonneg=True, name="g_deg_per_rpm"),
               "cycle_deg": cp.Parameter(nonneg=True, name="cycle_deg")}
        cons = [D @ p >= prm["min_deg"], p[net.first] == 0, p[net.last] - p[net.first] <= prm["cycle_deg"]]
        if len(rows):
            cons.append(D[rows] @ p >= cp.multiply(prm["g"], n))
        if net.window_idx:
            w = np.asarray(net.window_idx)
            prm["window_deg"] = cp.Parameter(len(w), name="window_deg")
            cons.append(incidence(len(net.names), w[:, 0], w[:, 1]) @ p <= prm["window_deg"])
        if net.sync_idx:
            s = np.asarray(net.sync_idx)
            cons.append(incidence(len(net.names), s[:, 0], s[:, 1]) @ p == 0)
        problem = cp.Problem(cp.Maximize(n), cons)
        set_values(prm)
        problem.get_problem_data(backend)          # compile now, so build and solve time separate
        return problem, n, prm

    def set_values(prm):
        prm["min_deg"].value, prm["g"].value, prm["cycle_deg"].value = phi, g[rows], task.cycle_deg
        if "window_deg" in prm:
            prm["window_deg"].value = np.array([w for _, _, w in task.window_arcs()])
    clock = Clock()
    # its parameters, the solve and the reading of n are one state: one thread at a time
    with LP_BUILDS.held(key, build) as ((problem, n, prm), _):
        set_values(prm)
        build_s = clock.elapsed()
        try:
            problem.solve(solver=backend, warm_start=False)
        except cp.error.SolverError as exc:
            return None, Status.FAILED, f"{backend} failed: {exc}", build_s, {}
        status = from_cvxpy(problem.status)
        extra = {"solver_status": problem.status}
        if status is Status.SOLVED:
            return float(n.value), status, "", build_s, extra
        return None, status, f"{backend}: {problem.status}", build_s, extra


def speed_bisection(task, net, bounds_at, rtol):
    """Bisection on n: feasible when the event-time LP with the exact bounds at n fits the cycle
    (one HiGHS model held through the steps, `HeldLP`; `backend` is the LP method's)."""
    clock = Clock()
    lp = HeldLP(len(net.names), net.tails, net.heads, first=net.first, last=net.last,
                window_arcs=net.window_idx, sync_arcs=net.sync_idx, with_cycle=True)
    windows = [w for _, _, w in task.window_arcs()]
    build_s = clock.elapsed()
    steps = []

    def feasible(n_rpm):
        lb, _ = bounds_at(n_rpm)
        if not np.all(np.isfinite(lb)):          # a rebound over its limit on the whole stated range
            steps.append((n_rpm, "no bound on the range"))
            return False
        status, _ = lp.solve(lb, windows, task.cycle_deg)
        steps.append((n_rpm, status.value))
        if status not in (Status.SOLVED, Status.INFEASIBLE):
            raise Undecided(f"HiGHS: {status.value} at n = {n_rpm:.9g} rpm")
        return status is Status.SOLVED
    try:
        if not feasible(0.0):
            return None, Status.INFEASIBLE, "", build_s, {"bisection_steps": len(steps)}
        lo, hi = 0.0, 1.0
        while feasible(hi):
            lo, hi = hi, 2.0 * hi
            if hi > MAX_RPM:
                return None, Status.LIMIT, (f"every speed up to the search bound {MAX_RPM:g} rpm fits: no limit "
                                            f"grows with the speed"), build_s, {"bisection_steps": len(steps)}
        while hi - lo > 0.25 * rtol * hi and hi > MIN_RPM:   # a quarter: the certificate's margin is rtol
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if feasible(mid) else (lo, mid)
    except Undecided as exc:
        return None, Status.FAILED, str(exc), build_s, {"bisection_steps": len(steps)}
    return (lo if hi > MIN_RPM else 0.0), Status.SOLVED, "", build_s, {"bisection_steps": len(steps),
                                                                     "bisection_bracket_rpm": [lo, hi]}


def arcs_at(task, net, lb):
    """The difference constraints with the arcs' bounds `lb` and the cycle, for `positive_cycle`."""
    first, last = net.names[net.first], net.names[net.last]
    names = task.operation_names
    arcs = [(u, v, w, f"t({u}->{v}) >= {w:.6g} deg{names.get((u, v), '')}") for u, v, w in constraint_arcs(net, lb)]
    return arcs + [(last, first, -task.cycle_deg, f"cycle p({last}) - p({first}) <= {task.cycle_deg:.6g} deg")]


def conflict_at(task, net, lb):
    return [(u, label, w) for u, _, w, label in positive_cycle(arcs_at(task, net, lb))]


def certify_speed(task, net, bounds_at, n_max, tol):
    """'' when the bounds at n_max (1 - tol) leave no positive cycle and those at n_max (1 + tol)
    do (so n_max is the largest speed to tol); else why not."""
    below, above = n_max * (1 - tol), n_max * (1 + tol)
    lb_below, lb_above = bounds_at(below)[0], bounds_at(above)[0]
    if not np.all(np.isfinite(lb_below)) or conflict_at(task, net, lb_below):
        return f"certificate failed: n = {below:.9g} rpm (just under the answer) does not fit the cycle"
    if np.all(np.isfinite(lb_above)) and not conflict_at(task, net, lb_above):
        return f"certificate failed: n = {above:.9g} rpm (just over the answer) still fits the cycle"
    return ""
