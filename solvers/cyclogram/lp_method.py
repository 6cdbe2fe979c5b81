"""The event-time LP in cvxpy (method "lp"): built once per structure (its limits are Parameters:
a what-if re-solve reuses the compiled problem), solved, and checked against the longest-path
certificate of solvers/cyclogram/graph.py (a positive cycle, the optimum, the floats)."""
from typing import TYPE_CHECKING

import numpy as np

from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import some_of
from mechopt.kit.result import Clock, Result, Status, from_cvxpy
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.loom_limits import amplitude_mm
from mechopt.solvers.cyclogram.conflicts import conflict_chain, infeasible_result
from mechopt.solvers.cyclogram.graph import Levels, PositiveCycle
from mechopt.solvers.cyclogram.net import Net, back_arcs, plan_arrays
from mechopt.solvers.cyclogram.schedule import (
    SENSITIVITY_CONVENTION,
    float_array,
    graph_floats,
    limit_diagnostics,
    schedule_values,
)

if TYPE_CHECKING:      # the LP's modules (cvxpy: seconds to import) load only when the LP is asked for
    from mechopt.solvers.cyclogram.event_time import EventTimeLP

LP_BUILDS = BuildCache("cyclogram.event_time_lp", maxsize=8)


def plan_lp(task, *, stress_form, tol_deg, backend, warm_start) -> Result:
    """The event-time LP in cvxpy, checked against the longest-path certificate."""
    from mechopt.solvers.cyclogram.event_time import build_event_time_lp
    clock = Clock()
    net = Net(task, stress_form)
    def build():
        lp = build_event_time_lp(len(net.names), net.tails, net.heads, first=net.first, last=net.last,
                                 stress_rows=net.stress_rows, stress_ref=net.stress_ref, stress_form=stress_form,
                                 amplitude_rows=net.amp_rows, window_arcs=net.window_idx, sync_arcs=net.sync_idx,
                                 limiting=net.limiting, with_cycle=task.cycle_deg is not None)
        set_parameters(lp, task, net)
        lp.problem.get_problem_data(backend)      # compile now, so build and solve time separate
        return lp
    # cvxpy caches one compiled chain per problem and solver
    key = (backend, *net.signature())
    # its parameters, the solve and the reading of values and duals are one state: one thread at a time
    with LP_BUILDS.held(key, build) as (lp, compiled_s):
        return _solve_held_lp(task, net, lp, clock, compiled_s > 0, stress_form=stress_form, tol_deg=tol_deg,
                              backend=backend, warm_start=warm_start)


def _solve_held_lp(task, net, lp, clock, fresh, *, stress_form, tol_deg, backend, warm_start) -> Result:
    """The cached event-time LP `lp` (held by this thread) solved for `task`: parameters set,
    solved, its answer checked and read."""
    import cvxpy as cp
    set_parameters(lp, task, net)
    clock.built()
    try:
        lp.problem.solve(solver=backend, warm_start=warm_start)
    except cp.error.SolverError as exc:
        return clock.result(Status.FAILED, {}, message=f"{backend} failed: {exc}")
    status = from_cvxpy(lp.problem.status)
    diagnostics = {"method": "lp", "backend": backend, "stress_form": stress_form, "compiled_now": fresh,
                   "events": len(net.names), "operations": len(net.tails), "isolated_events": task.isolated_events,
                   "solver_status": lp.problem.status, "solve_time_backend_s": lp.problem.solver_stats.solve_time}
    # the certificate: an optimum is only trusted when the difference constraints hold no positive cycle
    chain = conflict_chain(net) if status is Status.INFEASIBLE or _may_conflict(net) else []
    if chain:
        note = "" if status is Status.INFEASIBLE else \
            f"; {backend} reported {lp.problem.status}, the longest-path certificate overrules it"
        return infeasible_result(chain, clock, diagnostics, note)
    if status is not Status.SOLVED:
        message = f"{backend}: {lp.problem.status}"
        if status is Status.INFEASIBLE:
            message += " (no positive cycle among the difference constraints: a numerical failure?)"
        return clock.result(status, {}, message=message, diagnostics=diagnostics)
    values, more, overstressed, disagreement, (p, floats) = _report(task, net, lp, tol_deg)
    diagnostics |= more
    if disagreement:
        return clock.result(Status.INACCURATE, values, message=disagreement, violated=overstressed,
                            diagnostics=diagnostics, arrays=plan_arrays(net, values, diagnostics, p, floats))
    objective = "limiting_op_deg" if net.limiting else "span_deg"
    message = (f"{objective} = {values[objective]:.6g} ({backend}, {stress_form} stress, "
               f"{'compiled' if fresh else 'DPP re-solve'}); {SENSITIVITY_CONVENTION}")
    if overstressed:      # the tangent under-estimates sigma_max: the linearised optimum breaks the true limit
        message += f"; the linearised stress limit lets sigma_max exceed [sigma_H] on {some_of(overstressed, sep=', ')}"
    return clock.result(Status.SOLVED, values, message=message, violated=overstressed,
                        diagnostics=diagnostics, arrays=plan_arrays(net, values, diagnostics, p, floats))


def _may_conflict(net) -> bool:
    """Whether the constraints can hold a positive cycle: windows and syncs can; a DAG of
    operations only with its cycle, when its longest path (linear time) is longer than it."""
    task = net.task
    if task.windows or task.syncs:
        return True
    if task.cycle_deg is None:
        return False
    return _levels(net).longest_from(net.first, net.lb)[net.last] > task.cycle_deg


def _levels(net) -> Levels:
    """The operations' DAG for the longest-path passes (one per structure: kept in a BuildCache)."""
    return Levels.of(len(net.names), net.tails, net.heads)


def set_parameters(lp: "EventTimeLP", task: Cyclogram, net) -> None:
    """Write the task's limits into the LP's Parameters (no recompilation)."""
    prm = lp.params
    prm["min_deg"].value = task.min_angles_deg()
    if "sigma_H_MPa" in prm:
        prm["sigma_H_MPa"].value = task.sigma_H_limit_MPa
    if "inv_sigma_H_per_MPa" in prm:
        prm["inv_sigma_H_per_MPa"].value = 1.0 / task.sigma_H_limit_MPa
    if "slope_mm_per_deg" in prm:
        prm["slope_mm_per_deg"].value = task.amplitude_slope_mm_per_deg
        prm["intercept_mm"].value = task.amplitude_intercept_mm
        prm["amplitude_limit_mm"].value = task.amplitude_limit_mm
    if "window_deg" in prm:
        prm["window_deg"].value = np.array([w for _, _, w in task.window_arcs()])
    if "cycle_deg" in prm:
        prm["cycle_deg"].value = task.cycle_deg


def _report(task, net, lp, tol):
    """Values and diagnostics of a solved LP: times, angles, floats, duals, the cross-check."""
    p = lp.p.value
    p = p - p[net.first]                      # the anchor holds to solver precision; make it exact
    values, overstressed = schedule_values(task, net, p)
    t = p[net.heads] - p[net.tails]

    longest, disagreement = _cross_check(task, net, values, tol)
    if longest is not None:
        values["longest_path_deg"] = longest
    sens, binding, sens_min = _sensitivities(task, net, lp, t, tol)
    values |= sens
    floats, float_deg = _floats(net, values, tol)
    diagnostics = {"binding": binding, "sens_min_deg": sens_min} | limit_diagnostics(task, net) | floats
    return values, diagnostics, tuple(overstressed), disagreement, (p, float_deg)


def _cross_check(task, net, values, tol):
    """The LP's optimum against the exact longest-path certificate: (longest first -> last [deg],
    None or why the LP is not to be trusted). Tolerance: tol * max(1, |certificate|) [deg].

    The certificate is the graph's longest paths over every difference constraint
    (solvers/cyclogram/graph.py: DAG passes, Bellman-Ford rounds over windows and syncs): the
    span is the longest path first -> last; a machine's max t(x*, y*) is minus the longest path
    y* -> x* through the cycle's arc (the shortest-path dual of the LP)."""
    try:
        longest, expected = longest_certificate(net)
    except PositiveCycle:       # a cycle within round-off of zero that the passes take as positive
        return None, ("cross-check failed: the LP reports an optimum but the longest-path passes find a positive "
                      "cycle that the conflict search (1e-12 round-off margin) does not: not certified")
    got, what = (values["limiting_op_deg"], "limiting_op_deg") if net.limiting else (values["span_deg"], "span_deg")
    longest = float(longest) if np.isfinite(longest) else None
    if not abs(expected - got) <= tol * max(1.0, abs(expected)):
        return longest, (f"cross-check failed: LP {what} = {got!r} but the longest path on the graph gives "
                         f"{expected!r} (tolerance {tol:g} deg per degree above 1): not certified")
    return longest, None


def longest_certificate(net) -> tuple[float, float]:
    """(the longest path first -> last, the objective it certifies: that path, or for a machine
    minus the longest path y* -> x* through the cycle (inf: none)) [deg]; PositiveCycle."""
    levels = _levels(net)
    longest = levels.longest_from(net.first, net.lb, back_arcs(net, with_cycle=False)[0])[net.last]
    if not net.limiting:
        return longest, longest
    back = levels.longest_from(net.limiting[1], net.lb, back_arcs(net)[0])[net.limiting[0]]
    return longest, (-back if np.isfinite(back) else np.inf)


def _sensitivities(task, net, lp, t, tol):
    """d(objective)/d(limit) from the duals, and the binding constraints by name."""
    s, blocks = lp.sign, lp.blocks
    sens, binding = {}, []
    dual_phi = np.asarray(blocks["min_angle"].dual_value, dtype=float).ravel()
    sens_min, phi = {}, task.min_angles_deg()
    for k, (x, y) in enumerate(net.arcs):
        if t[k] - phi[k] <= tol:
            binding.append({"constraint": f"min_angle[{x}->{y}]", "dual_deg_per_deg": float(s * dual_phi[k]) + 0.0})
        if abs(dual_phi[k]) > tol:
            sens_min[f"{x}->{y}"] = float(s * dual_phi[k])
    if "contact_stress" in blocks:
        dual = np.asarray(blocks["contact_stress"].dual_value, dtype=float).ravel()
        sigma = task.sigma_H_limit_MPa
        if "sigma_H_MPa" in lp.params:
            drhs = lp.stress_coeffs[1]                       # d(rhs)/d(sigma_H), tangent form
        else:
            drhs = -lp.stress_coeffs[0] / sigma**2           # d(K / sigma_H)/d(sigma_H)
        sens["sens_sigma_H_deg_per_MPa"] = float(s * np.dot(dual, drhs))
        rhs = (lp.stress_coeffs[0] + lp.stress_coeffs[1] * sigma if len(lp.stress_coeffs) == 2
               else lp.stress_coeffs[0] / sigma)
        for j, k in enumerate(net.stress_rows):
            if t[k] - rhs[j] <= tol:
                x, y = net.arcs[k]
                binding.append({"constraint": f"contact_stress[{x}->{y}]",
                                "dual_deg_per_MPa": float(s * dual[j] * drhs[j])})
    if "amplitude" in blocks:
        dual = np.asarray(blocks["amplitude"].dual_value, dtype=float).ravel()
        sens["sens_amplitude_limit_deg_per_mm"] = float(-s * dual.sum())     # <= form: d/d(limit) = -dual
        for j, k in enumerate(net.amp_rows):
            a = amplitude_mm(task.amplitude_slope_mm_per_deg, task.amplitude_intercept_mm, t[k])
            if task.amplitude_limit_mm - a <= tol * abs(task.amplitude_slope_mm_per_deg):
                x, y = net.arcs[k]
                binding.append({"constraint": f"amplitude[{x}->{y}]", "dual_deg_per_mm": float(-s * dual[j])})
    if "window" in blocks:
        dual = np.asarray(blocks["window"].dual_value, dtype=float).ravel()
        for j, (a, b, w) in enumerate(task.window_arcs()):
            sens[f"sens_window_{a}_{b}_deg_per_deg"] = float(-s * dual[j])
            if w - (lp.p.value[net.index[b]] - lp.p.value[net.index[a]]) <= tol:
                binding.append({"constraint": f"window[{a}->{b}]", "dual_deg_per_deg": float(-s * dual[j])})
    if "cycle" in blocks:
        dual = float(np.asarray(blocks["cycle"].dual_value))
        sens["sens_cycle_deg_per_deg"] = -s * dual
        binding.append({"constraint": "cycle", "dual_deg_per_deg": -s * dual}) if abs(dual) > tol else None
    return sens, binding, sens_min


def _floats(net, values, tol) -> tuple[dict, np.ndarray | None]:
    """Total float of every operation for the found span (a machine: with the limiting operation
    held at its optimum, a hair under: no 0+ cycle), by the graph's passes (`graph_floats`): its
    diagnostics and the floats as an array (None: round-off made a zero cycle positive)."""
    lb = net.lb.copy()
    if net.limiting:
        k = next(k for k, (x, y) in enumerate(net.arcs) if (net.index[x], net.index[y]) == net.limiting)
        lb[k] = values["limiting_op_deg"] - tol / 10
    levels, back = _levels(net), back_arcs(net, with_cycle=False)[0]
    floats = float_array(net, levels, back, lb, values["span_deg"])
    return graph_floats(net, levels, back, lb, values["span_deg"], tol, floats), floats
