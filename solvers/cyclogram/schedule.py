"""What a schedule (event times p) reports, whichever method found it: the values (span, times,
angles, the laws' amplitudes and stresses, group spans), which limit sets each bound, and every
operation's total float with the critical operations and one critical chain, by the longest-path
passes of solvers/cyclogram/graph.py."""
import numpy as np

from mechopt.models.loom_limits import amplitude_mm, stress_bound_deg, stress_MPa
from mechopt.solvers.cyclogram.graph import BackArcs, PositiveCycle, a_path
from mechopt.solvers.cyclogram.net import per_name

SENSITIVITY_CONVENTION = ("sens_* = d(objective)/d(limit): change of the objective [deg] per unit increase "
                          "of the limit; negative means a looser limit shortens the span")


def limit_diagnostics(task, net) -> dict:
    """Which limit sets each operation's bound, and the linearised stress bound's gap."""
    why = net.lb_why
    keep = range(len(why)) if per_name(net) else [k for k in (*net.stress_rows, *net.amp_rows, *task.time_arcs())
                                                  if why[k] != "min_angle"]   # large: the laws' arcs only
    return {"sensitivity_convention": SENSITIVITY_CONVENTION,
            "bound_source": {"{}->{}".format(*net.arcs[k]): why[k] for k in sorted(set(keep))},
            "stress_gap_deg": {f"{x}->{y}": _stress_gap(task, k) for k, (x, y) in
                               ((k, net.arcs[k]) for k in net.stress_rows)}}


def schedule_values(task, net, p):
    """Values of event times p [deg]: span, limiting operation, times, angles, amplitudes,
    stresses, group spans; and the operations whose stress exceeds [sigma_H]."""
    t = p[net.heads] - p[net.tails]
    span = float(p[net.last] - p[net.first])
    values = {"span_deg": span}
    if net.limiting:
        values["limiting_op_deg"] = float(p[net.limiting[1]] - p[net.limiting[0]])
    if per_name(net):
        values |= {f"p_{v}_deg": float(p[i]) for i, v in enumerate(net.names)}
        values |= {f"t_{x}_{y}_deg": float(t[k]) for k, (x, y) in enumerate(net.arcs)}
    for k in net.amp_rows:
        x, y = net.arcs[k]
        values[f"amplitude_{x}_{y}_mm"] = float(amplitude_mm(task.amplitude_slope_mm_per_deg,
                                                              task.amplitude_intercept_mm, t[k]))
    for k in net.stress_rows:
        x, y = net.arcs[k]
        values[f"sigma_{x}_{y}_MPa"] = float(stress_MPa(*task.stress_reference(k), t[k]))
    values |= task.motion_values(t, task.speed_rpm)
    for group, members in task.group_indices.items():
        if members.size:
            values[f"span_{group}_deg"] = float(p[members].max() - p[members].min())
    overstressed = [f"contact_stress[{x}->{y}]" for k, (x, y) in ((k, net.arcs[k]) for k in net.stress_rows)
                    if values[f"sigma_{x}_{y}_MPa"] > task.sigma_H_limit_MPa * (1 + 1e-9)]
    return values, tuple(overstressed)


def _stress_gap(task, k):
    """Exact minus linearised stress bound of arc k [deg]: >= 0, the tangent lies under sigma_max."""
    ref = task.stress_reference(k)
    return float(stress_bound_deg(*ref, task.sigma_H_limit_MPa, "exact")
                 - stress_bound_deg(*ref, task.sigma_H_limit_MPa, "linear"))


def float_array(net, levels, back, lb, span, early=None):
    """Total float LS(y) - ES(x) - lb of every operation for bounds lb in a span [deg] (None:
    round-off made a zero cycle positive): earliest times from first (`early`, when the caller
    holds them), latest from the longest paths to first with p(last) - p(first) <= span as one
    more back arc."""
    early = levels.longest_from(net.first, lb, back) if early is None else early
    closed = BackArcs(np.r_[back.tails, net.last], np.r_[back.heads, net.first], np.r_[back.weights, -span])
    try:
        late = -levels.longest_to(net.first, lb, closed)
    except PositiveCycle:
        return None
    return late[net.heads] - early[net.tails] - lb + 0.0        # + 0.0: a zero float is 0, never -0 (late is negated)


def critical_path(net, floats, tol) -> tuple[np.ndarray, list[int] | None]:
    """The critical operations (float <= tol [deg]: their indices) and one chain of them from the
    first event to the last (positions in those indices; None: none)."""
    critical = np.flatnonzero(floats <= tol)
    return critical, a_path(len(net.names), net.tails[critical], net.heads[critical], net.first, net.last)


def graph_floats(net, levels, back, lb, span, tol, floats=None):
    """The floats of `float_array` (or `floats`, computed before) for the result: {float_deg (by
    operation; a note for networks past PER_NAME_MAX_OPS, whose floats are the result's float_deg
    array), critical_ops (float <= tol), critical_chain (events first -> last)}."""
    floats = float_array(net, levels, back, lb, span) if floats is None else floats
    if floats is None:
        return {"floats": "not available: round-off made a zero cycle positive"}
    critical, path = critical_path(net, floats, tol)
    chain = [] if path is None else [net.names[net.first]] + [net.names[net.heads[critical[k]]] for k in path]
    labels = net.task.operation_labels
    float_deg = (dict(zip(labels.tolist(), floats.tolist())) if per_name(net)
                 else f"{len(floats)} operations: in the result's arrays (float_deg)")
    return {"float_deg": float_deg, "critical_ops": labels[critical].tolist(), "critical_chain": chain}
