"""The event-time LP solved on its graph (method "graph", the default): its dual, longest paths
(solvers/cyclogram/graph.py). Event times, the objective's path, duals as the path's arcs,
floats and ranging."""
import dataclasses

import numpy as np

from mechopt.kit.errors import some_of
from mechopt.kit.result import Clock, Result, Status
from mechopt.models.loom_limits import amplitude_mm, stress_bound_deg
from mechopt.solvers.cyclogram.conflicts import MAX_CONFLICTS, conflict_chain, infeasible_result
from mechopt.solvers.cyclogram.graph import Levels, PositiveCycle, a_path, tight_arcs
from mechopt.solvers.cyclogram.net import Net, back_arcs, per_name, plan_arrays
from mechopt.solvers.cyclogram.schedule import (
    SENSITIVITY_CONVENTION,
    float_array,
    graph_floats,
    limit_diagnostics,
    schedule_values,
)

RANGING_MAX_OPS = 64       # ranging of the critical operations: one pass each, for chains up to this long
RANGING_MAX_TABLE = 10_000  # a ranging table per operation for networks up to this many operations


def plan_graph(task, *, stress_form, tol_deg) -> Result:
    """Event times, floats, duals and ranging by longest paths (solvers/cyclogram/graph.py)."""
    clock = Clock()
    net = Net(task, stress_form)
    levels = Levels.of(len(net.names), net.tails, net.heads)
    back, kinds = back_arcs(net)
    clock.built()
    diagnostics = {"method": "graph", "stress_form": stress_form, "events": len(net.names),
                   "operations": len(net.tails), "isolated_events": task.isolated_events}
    try:
        solved = longest_schedule(net, levels, back, tol_deg)
    except PositiveCycle:
        chains = conflict_chain(net, MAX_CONFLICTS)
        if len(chains) < 2:
            return infeasible_result(chains[0] if chains else [], clock, diagnostics)
        first = infeasible_result(chains[0], clock, diagnostics)
        more = [infeasible_result(chain, clock, {}) for chain in chains[1:]]
        message = first.message + "".join(f"; and, independent of it, {r.message.removeprefix('infeasible: ')}"
                                          for r in more)
        return dataclasses.replace(first, message=message, violated=sum((r.violated for r in [first, *more]), ()),
                                   diagnostics=first.diagnostics | {"conflicts": [r.diagnostics for r in more]})
    if solved is None:
        x, y = (net.names[i] for i in net.limiting)
        return clock.result(Status.UNBOUNDED, {}, diagnostics=diagnostics,
                            message=f"unbounded: no chain of limits leads from {y} back to {x} (give cycle_deg), so "
                                    f"t({x}->{y}) can grow without end")
    p, objective, uses, back_uses, lb_at = solved
    values, overstressed = schedule_values(task, net, p)
    sign = -1.0 if net.limiting else 1.0
    sens, binding, sens_min = _graph_sensitivities(task, net, p, sign * uses, sign * back_uses, kinds, tol_deg)
    values |= sens
    values["longest_path_deg"] = objective if not net.limiting else \
        float(levels.longest_from(net.first, net.lb, back_arcs(net, with_cycle=False)[0])[net.last])
    float_deg = float_array(net, levels, back, lb_at, values["span_deg"], early=p)    # p: the earliest times
    floats = graph_floats(net, levels, back, lb_at, values["span_deg"], tol_deg, float_deg)
    diagnostics |= {"binding": binding, "sens_min_deg": sens_min} | limit_diagnostics(task, net) | floats
    if not net.limiting and len(net.tails) <= RANGING_MAX_TABLE:
        diagnostics["ranging_deg"] = _ranging(net, levels, back, uses, floats, objective)
    name = "limiting_op_deg" if net.limiting else "span_deg"
    message = f"{name} = {values[name]:.6g} (graph, {stress_form} stress); {SENSITIVITY_CONVENTION}"
    if overstressed:
        message += f"; the linearised stress limit lets sigma_max exceed [sigma_H] on {some_of(overstressed, sep=', ')}"
    return clock.result(Status.SOLVED, values, message=message, violated=overstressed, diagnostics=diagnostics,
                        arrays=plan_arrays(net, values, diagnostics, p, float_deg))


def longest_schedule(net, levels, back, tol):
    """The optimum by longest paths: (earliest event times p, objective, per operation and per
    back arc the times it lies on the objective's path, the bounds p meets); None: unbounded.

    Span: the longest path first -> last. Machine: max t(x*, y*) = -(longest path y* -> x*)
    through the cycle's arc (the shortest-path dual of the LP); p then holds t(x*, y*) at it."""
    lb = net.lb
    source, target = (net.limiting[1], net.limiting[0]) if net.limiting else (net.first, net.last)
    dist = levels.longest_from(source, lb, back)
    if not np.isfinite(dist[target]):
        if levels.has_positive_cycle(lb, back):     # a conflict out of the source's reach: no schedule at all
            raise PositiveCycle
        return None          # a machine's limiting operation with nothing to hold it: unbounded
    objective = float(-dist[target] if net.limiting else dist[target])
    lb_at = lb
    if net.limiting:
        lb_at = lb.copy()
        lb_at[_limiting_arc(net)] = objective
        p = levels.longest_from(net.first, lb_at, back)
    else:
        p = dist
    m = len(net.tails)
    tails, heads, w = ((net.tails, net.heads, lb) if not len(back) else     # no copies of a large DAG's arcs
                       (np.r_[net.tails, back.tails], np.r_[net.heads, back.heads], np.r_[lb, back.weights]))
    eps = tol * 1e-3 * max(1.0, abs(objective))
    tight = tight_arcs(tails, heads, w, dist, eps)
    path = np.asarray(a_path(len(net.names), tails[tight], heads[tight], source, target), dtype=np.int64)
    counts = np.bincount(tight[path], minlength=m + len(back))
    return p, objective, counts[:m].astype(float), counts[m:].astype(float), lb_at


def _limiting_arc(net):
    return next(k for k in range(len(net.tails)) if (net.tails[k], net.heads[k]) == net.limiting)


def _graph_sensitivities(task, net, p, d_lb, d_back, kinds, tol):
    """d(objective)/d(limit) from the path's arcs (d_lb: per operation d objective / d bound;
    d_back: per back arc d objective / d weight), and the binding constraints, as the LP's."""
    t = p[net.heads] - p[net.tails]
    phi, why = task.min_angles_deg(), net.lb_why
    sens, binding, sens_min = {}, [], {}
    phi_set = np.ones(len(why), dtype=bool)          # [phi] sets the bound, except where a law does
    laws = np.array([k for k in (*net.stress_rows, *net.amp_rows) if why[k] not in ("min_angle", "min_time", "max_accel", "max_velocity")],
                    dtype=np.int64)
    phi_set[laws] = False
    d_phi = np.where(phi_set, d_lb, 0.0) + 0.0
    # past PER_NAME_MAX_OPS the binding [phi] are those with a dual (on the path), not every tight one
    listed = (t - phi <= tol) | (d_phi != 0) if per_name(net) else d_phi != 0
    for k in np.flatnonzero(listed).tolist():
        x, y = net.arcs[k]
        if t[k] - phi[k] <= tol:
            binding.append({"constraint": f"min_angle[{x}->{y}]", "dual_deg_per_deg": float(d_phi[k])})
        if d_phi[k]:
            sens_min[f"{x}->{y}"] = float(d_phi[k])
    if net.stress_rows:
        sigma, total = task.sigma_H_limit_MPa, 0.0
        for k in net.stress_rows:
            sigma_ref, t_ref = task.stress_reference(k)
            slope = -sigma_ref * t_ref / sigma**2 if net.stress_form == "exact" else -t_ref / sigma_ref
            dual = float(d_lb[k] * slope) if why[k] == "contact_stress" else 0.0
            total += dual
            if t[k] - stress_bound_deg(sigma_ref, t_ref, sigma, net.stress_form) <= tol:
                x, y = net.arcs[k]
                binding.append({"constraint": f"contact_stress[{x}->{y}]", "dual_deg_per_MPa": dual + 0.0})
        sens["sens_sigma_H_deg_per_MPa"] = float(total) + 0.0
    if net.amp_rows:
        total = 0.0
        for k in net.amp_rows:
            dual = float(d_lb[k] / task.amplitude_slope_mm_per_deg) if why[k] == "amplitude" else 0.0
            total += dual
            a = amplitude_mm(task.amplitude_slope_mm_per_deg, task.amplitude_intercept_mm, t[k])
            if task.amplitude_limit_mm - a <= tol * abs(task.amplitude_slope_mm_per_deg):
                x, y = net.arcs[k]
                binding.append({"constraint": f"amplitude[{x}->{y}]", "dual_deg_per_mm": dual + 0.0})
        sens["sens_amplitude_limit_deg_per_mm"] = float(total) + 0.0
    windows = [j for j, kind in enumerate(kinds) if kind == "window"]
    for j, (a, b, w) in zip(windows, task.window_arcs()):
        dual = float(-d_back[j]) + 0.0           # the back arc's weight is -w
        sens[f"sens_window_{a}_{b}_deg_per_deg"] = dual
        if w - (p[net.index[b]] - p[net.index[a]]) <= tol:
            binding.append({"constraint": f"window[{a}->{b}]", "dual_deg_per_deg": dual})
    if "cycle" in kinds:
        dual = float(-d_back[kinds.index("cycle")]) + 0.0
        sens["sens_cycle_deg_per_deg"] = dual
        if abs(dual) > tol:
            binding.append({"constraint": "cycle", "dual_deg_per_deg": dual})
    return sens, binding, sens_min


def _ranging(net, levels, back, uses, floats, span):
    """Per operation [how far its bound may fall, how far rise] [deg] with its dual (d span /
    d bound) unchanged; None: without end. Off the path: rise by its float, fall without end.
    On it: fall until the longest path without it is as long (one pass each, for paths up to
    RANGING_MAX_OPS); rise without end in a DAG, else until the constraints close a positive
    cycle (one pass from its head each)."""
    if "float_deg" not in floats:
        return {}
    keys = list(floats["float_deg"])
    out = {key: [None, max(0.0, fl)] for key, fl in floats["float_deg"].items()}
    on_path = np.flatnonzero(uses)
    if len(on_path) > RANGING_MAX_OPS:          # the path's own ranging left out: too many passes
        return {key: r for (key, r), used in zip(out.items(), uses.tolist()) if not used}
    for k in on_path:
        lb = net.lb.copy()
        lb[k] = -np.inf
        try:
            without = levels.longest_from(net.first, lb, back)[net.last]
        except PositiveCycle:
            without = np.inf
        down = float(span - without) if np.isfinite(without) else None
        up = None
        if len(back):
            back_dist = levels.longest_from(net.heads[k], net.lb, back)[net.tails[k]]
            up = float(-back_dist - net.lb[k]) if np.isfinite(back_dist) else None
        out[keys[k]] = [down, up]
    return out
