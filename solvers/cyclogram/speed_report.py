"""The schedule at the highest speed: event times, the exact laws' readings there, floats, the
critical chain and the limits on it (d n / d cycle), and whether a window rather than the
machine's cycle closes the limiting cycle."""
import math

import numpy as np

from mechopt.solvers.cyclogram.graph import Levels
from mechopt.solvers.cyclogram.net import back_arcs
from mechopt.solvers.cyclogram.schedule import graph_floats
from mechopt.solvers.loom.repair import exact_amplitude_mm


def speed_passes(net, sg=None):
    """The longest-path passes over the operations and the back arcs without the machine cycle
    (windows, syncs): `sg`'s (a SpeedGraph) when given, else built (Levels: once per structure)."""
    if sg is not None:
        return sg.levels, sg.back
    return Levels.of(len(net.names), net.tails, net.heads), back_arcs(net, with_cycle=False)[0]


def closed_without_the_cycle(net, lb_above, sg=None) -> bool:
    """Whether the bounds just above the highest speed hold a positive cycle of operations, windows
    and syncs alone: then a window, not the machine's cycle, limits the speed, and a longer cycle
    gives none (dn/dcycle = 0; the critical chain's slope is dn/dwindow)."""
    levels, back = speed_passes(net, sg)
    return bool(len(back)) and bool(np.all(np.isfinite(lb_above))) and levels.has_positive_cycle(lb_above, back)


def speed_report_of(task, net, lb, why, n_max, tol, sg=None):
    """Event times at max speed (earliest start), exact readings, and which constraints limit it
    (times and floats by the longest-path passes: `sg`'s, a SpeedGraph, when given)."""
    levels, back = speed_passes(net, sg)
    p = levels.longest_from(net.first, lb, back)
    t = p[net.heads] - p[net.tails]
    values = {"max_speed_rpm": n_max, "cycle_time_ms": 60_000.0 / n_max, "span_deg": float(p[net.last] - p[net.first])}
    if task.limiting_op is not None:
        x, y = (net.index[str(v)] for v in task.limiting_op)
        values["limiting_op_deg"] = float(p[y] - p[x])
    values |= {f"p_{v}_deg": float(p[i]) for i, v in enumerate(net.names)}
    values |= {f"t_{x}_{y}_deg": float(t[k]) for k, (x, y) in enumerate(net.arcs)}
    amp_rows = task.amplitude_arcs()
    amps = np.ravel(exact_amplitude_mm(task, t[amp_rows], n_max)) if amp_rows else []    # one vectorised call
    for k, a in zip(amp_rows, amps):
        x, y = net.arcs[k]
        values[f"amplitude_{x}_{y}_mm"] = float(a)
    for k in task.stress_arcs():
        x, y = net.arcs[k]
        values[f"sigma_{x}_{y}_MPa"] = float(task.stress_at_MPa(k, t[k], n_max))
    values |= task.motion_values(t, n_max)
    group = dict(task.graph.nodes(data="group"))
    schedule = graph_floats(net, levels, back, lb, task.cycle_deg, tol * max(1.0, task.cycle_deg))
    floats, critical, chain = (schedule.get(k, []) for k in ("float_deg", "critical_ops", "critical_chain"))
    limiting = []
    for k, (x, y) in enumerate(net.arcs):
        if why[k] and f"{x}->{y}" in critical:      # set by a law that grows with n (deg/rpm: its secant)
            # the operation's own group (a die stroke starting at the turret's stop is the die's), else its events'
            own = task.graph.edges[x, y].get("group")
            limiting.append({"constraint": f"{why[k]}[{x}->{y}]", "group": own or group[x] or group[y] or "-",
                             "deg_per_rpm": float(lb[k] / n_max), "deg": float(lb[k])})
    by_group: dict = {}
    for row in limiting:
        by_group[row["group"]] = by_group.get(row["group"], 0.0) + row["deg_per_rpm"]
    slope = sum(by_group.values())
    more = {"limiting": limiting, "float_deg": floats, "critical_ops": critical, "critical_chain": chain,
            "limiting_group": max(by_group, key=by_group.get) if by_group else "-",
            "limiting_constraint": max(limiting, key=lambda r: r["deg_per_rpm"])["constraint"] if limiting else "-",
            "sens_cycle_rpm_per_deg": 1.0 / slope if slope > 0 else math.inf}
    return values, more
