"""The whole machine at its highest speed: an LP in (p, n) when every law is a
function of n / t (a probe checks), bisection on n with LP feasibility otherwise.

The driver and the check of one method by the other; the laws as t >= g n (speed_laws), the
graph method (speed_graph), the LP and bisection (speed_lp) and the report (speed_report) are
their own modules."""
import functools
import math
from typing import Annotated, Literal

import numpy as np

from mechopt.kit.errors import NAMED, ModelError, some_of
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Interval, check_settings
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram.net import Net, plan_arrays
from mechopt.solvers.cyclogram.speed_graph import (
    certify_on_graph,
    speed_on_graph,
)
from mechopt.solvers.cyclogram.speed_laws import (
    angle_floors_deg,
    exact_amplitude_bounds,
    exact_bounds_at,
    lp_bounds_at,
    n_over_t_probe,
    speed_coeffs_deg_per_rpm,
)
from mechopt.solvers.cyclogram.speed_lp import (
    certify_speed,
    conflict_at,
    speed_bisection,
    speed_by_lp,
)
from mechopt.solvers.cyclogram.speed_report import closed_without_the_cycle, speed_report_of
from mechopt.solvers.stop_impact.lever_box import LeverBox, takes_box


@takes_box
def max_machine_speed(task: Cyclogram, *, method: Literal["auto", "graph", "lp", "bisection"] = "auto",
                      backend: Literal["HIGHS", "CLARABEL"] = "HIGHS",
                      rtol: Annotated[float, Interval(ge=1e-9, le=1e-2)] = 1e-7,
                      scan_to_deg: Annotated[float, Interval(gt=0.0, le=360.0)] = 60.0,
                      scan_step_deg: Annotated[float, Interval(ge=1e-3, le=10.0)] = 0.25,
                      check: bool = False, box: LeverBox | None = None) -> Result:
    """The largest main-shaft speed n at which every group fits the machine's cycle, with
    the event times there.

    Every limit is a lower bound on a phase angle. [phi] does not depend on n; a time `min_ms`
    (the microshuttle's flight) asks for 0.006 n T deg; the contact stress, sigma_ref (t_ref / t)
    (n / n_ref) <= [sigma_H] (n_ref = stress_speed_rpm), and the lever's exact rebound
    a(t, n) = h(n / t) <= a_lim depend on n and t only through r = n / t. The first two grow with
    r; the chain's h is wavy, so its r* is where h first crosses the limit going up from the
    stated range's start (`speed_coeffs_deg_per_rpm`): a <= limit for every r in [n_ref /
    scan_to_deg, r*], n_ref = speed_rpm. Each law is then r <= r*, i.e.

        t(x, y) >= g(x, y) n,      g = 1 / r*  [deg/rpm]  (0.006 T; sigma_ref t_ref / ([sigma_H] n_ref); 1 / r*_a)

    homogeneous and linear in (p, n): maximise n s.t. D p >= [phi], D p >= g n, windows, syncs,
    p(first) = 0, p(last) - p(first) <= cycle is an LP (method "lp"), and on the graph a
    parametric longest-path problem (method "graph", `SpeedGraph`: Newton on the positive cycles,
    each step one numpy pass; the limiting cycle of operations named, diagnostics limiting_cycle,
    and per speed limit on it the speed without it, ranging_at_max_speed). (In times rather than
    angles, tau = t / (6 n), the same bounds read tau >= [phi] / 6 (1/n) and tau >= g / 6 and the
    cycle 60 (1/n): an LP in (tau, 1/n), minimising 1/n.) A law that is not a function of n / t
    alone (a dwell over which a vibration must decay, a time with an angle) breaks this; then
    method "bisection" is the general route: bisection on n, each step the exact bounds at that n
    (the rebound's by `exact_amplitude_bound` at that n on [phi, scan_to_deg], not through r*)
    and the event-time LP's feasibility, its status checked. It is also the independent check of
    the LP. Method "auto" takes the graph when `n_over_t_probe` finds the rebound a function of n / t
    (diagnostics: method, n_over_t_probe_rel), else bisection. check = true solves the other of
    graph and LP as well (diagnostics check): a speed that differs by more than 1e-9 relative makes
    the answer INACCURATE (bisection's own check is the certificate below). rtol (relative) on n:
    the answer is certified by the longest-path certificate at n (1 - tol) (fits) and n (1 + tol) (does not);
    below 1e-9 the LP's own feasibility tolerance (1e-7 deg on a 360 deg cycle) decides.

    Returns max_speed_rpm, cycle_time_ms, span_deg, p_*, t_*, amplitude_*_mm and sigma_*_MPa
    (exact, at max speed), limiting_op_deg (machines with one); diagnostics: limiting_group,
    limiting_constraint, limiting (the speed-bound constraints on the critical chain, each with
    its group and deg/rpm), critical_chain, sens_cycle_rpm_per_deg (0 where a window, not the cycle,
    closes the limiting cycle). INFEASIBLE when the cycle cannot hold the groups at any speed (the
    conflicting chain named, as in plan_cyclogram),
    UNBOUNDED when no limit grows with n on a chain the cycle closes, LIMIT when bisection finds
    every speed up to its search bound feasible or the rebound exceeds its limit on the whole
    stated range. With a rebound: amplitude_holds_from_*_deg and amplitude_holds_to_*_deg, the
    range of t at the answer on which a <= limit is shown.

    box (a scene's box_frequency_low ... box_grid; lever_box.LeverBox): the rebound's bound is the
    largest over the box's levers (its nominal, corners and grid) at the speed raised by its margin
    (`box_amplitude_bound`): the machine holds the limit on every lever of the box, run up to
    n (1 + margin). Each lever's bound is t >= c_k (1 + margin) n, so the answer is the least over
    the levers of each lever's highest speed (their feasible sets are nested); diagnostics
    amplitude_box names the lever that binds. amplitude_*_mm stays the nominal lever's at n.
    """
    check_settings(max_machine_speed, method=method, backend=backend)
    if task.cycle_deg is None:
        raise ModelError("cycle_deg: the machine's speed is limited by its cycle; give cycle_deg", key="cycle_deg")
    if task.time_windows():         # its angle 0.006 n max_ms would move with the speed sought: not modelled
        k = task.time_windows()[0]
        raise ModelError(f"windows[{k}].max_ms: the highest speed takes windows as angles (max_deg); a window in "
                         f"time holds at a given speed (cyclogram.plan_cyclogram with speed_rpm, or the least cycle "
                         f"time of a time-based network)", key=f"windows[{k}].max_ms")
    clock = Clock()
    net = Net.structure(task)        # the speed LP has its own bounds
    phi = angle_floors_deg(task)
    g, why, amp_bounds = speed_coeffs_deg_per_rpm(task, scan_to_deg, scan_step_deg, box)
    scales, probe = n_over_t_probe(task, scan_to_deg)
    chosen = ("graph" if scales else "bisection") if method == "auto" else method
    diagnostics = {"method": chosen, "method_asked": method, "n_over_t_probe_rel": probe, "backend": backend,
                   "amplitude_bounds_at_reference": {f"{task.arcs[k][0]}->{task.arcs[k][1]}": b.statement()
                                                     for k, b in amp_bounds.items()}}
    margin = 1.0 if box is None else 1.0 + box.speed_margin        # the rebound's bounds hold at n (1 + margin)
    if box is not None and not box.trivial:
        diagnostics["amplitude_box"] = {f"{task.arcs[k][0]}->{task.arcs[k][1]}": {
            "frequency_factor": b.lever[0], "zeta": b.lever[1], "speed_factor": margin} for k, b in amp_bounds.items()}
    unreached = [b for b in amp_bounds.values() if b.from_deg is None]
    if unreached:
        return clock.result(Status.LIMIT, {}, message=f"the rebound's bound is not on the stated range: "
                            f"{unreached[0].statement()} (raise scan_to_deg)", diagnostics=diagnostics)
    if chosen == "graph":
        n_max, status, message, clock.build_s, extra = speed_on_graph(task, net, phi, g, why)
        bounds_at = functools.partial(lp_bounds_at, phi, g, why)
    elif chosen == "lp":
        n_max, status, message, clock.build_s, extra = speed_by_lp(task, net, phi, g, backend)
        bounds_at = functools.partial(lp_bounds_at, phi, g, why)
    else:
        bounds_at = functools.partial(exact_bounds_at, task, box, phi, scan_to_deg, scan_step_deg)
        n_max, status, message, clock.build_s, extra = speed_bisection(task, net, bounds_at, rtol)
    sg = extra.pop("graph", None)
    cycle = extra.pop("limiting_cycle_arcs", None)
    diagnostics |= {"speed_coeffs_deg_per_rpm":
                    {f"{x}->{y}": float(g[k]) for k, (x, y) in enumerate(task.arcs) if g[k] > 0}} | extra
    if status is Status.SOLVED and n_max * g.max(initial=0.0) <= 1e-6:   # below a micro-degree: at rest
        status = Status.INFEASIBLE
    if status is Status.INFEASIBLE:
        chain = conflict_at(task, net, phi) or conflict_at(task, net, np.maximum(phi, g * rtol))
        groups = list(dict.fromkeys(task.graph.nodes[v]["group"] or "-" for v, _, _ in chain))
        diagnostics |= {"conflict_groups": groups[:NAMED], "conflict_length": len(chain)}
        message = ("no speed fits: conflicting chain " + some_of(label for _, label, _ in chain)
                   + f" (needs {math.fsum(w for _, _, w in chain):.6g} deg more than its limits allow as n -> 0;"
                   + f" groups {some_of(groups, sep=', ')})") if chain else (
            f"no speed above rest fits: the {chosen} method's highest speed is {n_max or 0.0:.6g} rpm, and no "
            f"chain conflicts at rest")
        return clock.result(Status.INFEASIBLE, {}, message=message,
                            violated=tuple(label for _, label, _ in chain[:NAMED]), diagnostics=diagnostics)
    if status is Status.UNBOUNDED:
        message += ": no limit grows with the speed on a chain the cycle closes (no stress, rebound or min_ms there)"
    if status is not Status.SOLVED:
        return clock.result(status, {}, message=message, diagnostics=diagnostics)
    lb, why_at = bounds_at(n_max)
    certified = certify_on_graph(sg, n_max, rtol) if sg else certify_speed(task, net, bounds_at, n_max, rtol)
    values, more = speed_report_of(task, net, lb, why_at, n_max, rtol, sg)
    if closed_without_the_cycle(net, bounds_at(n_max * (1 + rtol))[0], sg):
        more["sens_cycle_rpm_per_deg"] = 0.0
    if sg:
        more["ranging_at_max_speed"] = sg.ranging(cycle, n_max, why)
    if check and not certified and chosen in ("graph", "lp"):
        certified = _check_by_other(chosen, task, net, phi, g, why, backend, n_max, more)
        if "rel" in more["check"]:
            values["check_rel"] = more["check"]["rel"]        # validate's certificate (the scenes: < 1e-9)
    held = amp_bounds if chosen in ("lp", "graph") else exact_amplitude_bounds(task, box, phi, scan_to_deg,
                                                                                  scan_step_deg, n_max)
    for k, b in amp_bounds.items():      # the range of t on which the rebound was shown to hold, at n_max
        x, y = task.arcs[k]
        at = held[k]
        scale = n_max * margin / b.speed_rpm if chosen in ("lp", "graph") else 1.0
        values[f"amplitude_holds_from_{x}_{y}_deg"] = at.from_deg * scale
        values[f"amplitude_holds_to_{x}_{y}_deg"] = at.to_deg * scale
    diagnostics |= more
    arrays = plan_arrays(net, values, diagnostics)          # the schedule at the highest speed, per operation
    if certified:
        return clock.result(Status.INACCURATE, values, message=certified, diagnostics=diagnostics, arrays=arrays)
    reason = ("every law a function of n / t" if scales else "the rebound is not a function of n / t") \
        + f" (probe {probe:.2g})"
    message = (f"max_speed_rpm = {n_max:.6g} ({chosen}{': ' + reason if method == 'auto' else ''}); limiting "
               f"group {more['limiting_group']}, constraint {more['limiting_constraint']}")
    if "check" in more:
        message += f"; checked by the {more['check']['method']} ({more['check']['rel']:.1g} relative)"
    return clock.result(Status.SOLVED, values, message=message, diagnostics=diagnostics, arrays=arrays)


CHECK_RTOL = 1e-9                # the graph's speed against the LP's (check = true)


def _check_by_other(chosen, task, net, phi, g, why, backend, n_max, more):
    """'' when the other method (the LP in (p, n) for the graph, the graph for the LP) gives the
    same speed to CHECK_RTOL, else why not (its figures in `more`)."""
    other = "LP in (p, n)" if chosen == "graph" else "graph"
    solve = speed_by_lp(task, net, phi, g, backend) if chosen == "graph" else speed_on_graph(task, net, phi, g, why)
    n_other, status, message = solve[:3]
    more["check"] = {"method": other, "status": status.value, "max_speed_rpm": n_other}
    if status is not Status.SOLVED:
        return f"check failed: the {other} says {status.value} ({message})"
    more["check"]["rel"] = abs(n_other - n_max) / n_max
    if more["check"]["rel"] > CHECK_RTOL:
        return f"check failed: the {other} gives {n_other!r} rpm against the {chosen}'s {n_max!r}"
    return ""
