"""The whole machine at its highest speed: an LP in (p, n) when every law is a
function of n / t (a probe checks), bisection on n with LP feasibility otherwise."""
import functools
import math
from typing import Annotated, Literal

import cvxpy as cp
import numpy as np

from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import NAMED, ModelError, some_of
from mechopt.kit.result import Clock, Result, Status, from_cvxpy
from mechopt.kit.settings import Interval, check_settings
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.cyclogram_tables import MAX_RPM
from mechopt.solvers.cyclogram.conflicts import constraint_arcs, positive_cycle
from mechopt.solvers.cyclogram.event_time import HeldLP, incidence
from mechopt.solvers.cyclogram.graph import Levels, a_path, tight_arcs
from mechopt.solvers.cyclogram.lp_method import LP_BUILDS
from mechopt.solvers.cyclogram.net import Net, back_arcs, plan_arrays
from mechopt.solvers.cyclogram.schedule import graph_floats
from mechopt.solvers.loom import repair
from mechopt.solvers.loom.repair import box_amplitude_bound, exact_amplitude_mm
from mechopt.solvers.stop_impact import walk_store
from mechopt.solvers.stop_impact.law import chain_rebounds_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox, takes_box


def _angle_floors_deg(task: Cyclogram) -> np.ndarray:
    """Each arc's [phi] as given, without the time floor of `min_ms` (that one grows with n) [deg]."""
    return np.fromiter((phi for _, _, phi in task.graph.edges(data="min_deg")), dtype=float, count=len(task.arcs))


MIN_RPM = 1e-6                   # bisection: below it the machine is at rest
N_OVER_T_RTOL = 1e-9             # the probe: a(c t, c n) = a(t, n) to this (the chain meets it to 1e-16)
N_OVER_T_FACTORS = (0.5, 2.0)
def n_over_t_probe(task: Cyclogram, scan_to_deg: float) -> tuple[bool, float]:
    """Whether every speed-dependent law is a function of n / t alone, and the largest relative
    change seen. The time floor (0.006 n T) and the stress (sigma_ref t_ref n / (t n_ref)) are by
    their form; the rebound is probed: a(c t, c n) against a(t, n) for c = 0.5, 2 at t =
    scan_to_deg and 3/4 of it, n the task's speed. (The chain passes: its rise in its own time
    depends on lambda = omega t / Omega only, and the impact on v0 only; see models/loom_limits.py, the STB loom's laws.)"""
    if not task.amplitude_arcs():
        return True, 0.0
    key = (task.lever_model, float(_reference_rpm(task)), float(scan_to_deg))    # a property of the law alone
    return _PROBES.get(key, lambda: walk_store.stored(                           # on disk too, when on
        "n_over_t_probe", key, lambda: _probe(task, scan_to_deg), list, lambda d: (bool(d[0]), float(d[1])),
        enabled=repair.rebound_amplitude_mm is chain_rebounds_mm))[0]


_PROBES = BuildCache("cyclogram.n_over_t_probe", maxsize=16)


def _probe(task, scan_to_deg):
    """Every point of the probe in one call of the law (the chain's batch path: each point's value
    is the one it has alone, a call's overhead paid once instead of six times)."""
    n, worst = _reference_rpm(task), 0.0
    tops = (scan_to_deg, 0.75 * scan_to_deg)
    t = np.array([[top, *(c * top for c in N_OVER_T_FACTORS)] for top in tops])
    speed = np.array([[n, *(c * n for c in N_OVER_T_FACTORS)] for _ in tops])
    for base, *others in np.asarray(exact_amplitude_mm(task, t, speed, lost=np.nan), dtype=float).tolist():
        for other in others:
            if np.isnan(base) and np.isnan(other):
                continue
            worst = max(worst, abs(other - base) / max(abs(base), 1e-300) if np.isfinite(other - base) else math.inf)
    return worst <= N_OVER_T_RTOL, worst


def _reference_rpm(task):
    if task.speed_rpm is None:
        raise ModelError("speed_rpm: the rebound's exact bound is found at a reference speed; give speed_rpm",
                         key="speed_rpm")
    return task.speed_rpm


def _time_law(task, k) -> str:
    """What sets arc k's time floor: a motion's limit ("max_accel", "max_velocity") or its min_ms."""
    return task.arc_data(k)["motion_limit"] or "min_time"


def speed_coeffs_deg_per_rpm(task: Cyclogram, scan_to_deg: float = 60.0, scan_step_deg: float = 0.25,
                             box: LeverBox | None = None) -> tuple[np.ndarray, list[str], dict]:
    """Per arc, the angle every rpm of speed asks for [deg/rpm], which law sets it ("min_time",
    "contact_stress", "amplitude" or "" for none), and per amplitude arc its exact bound at the
    task's speed. Each law is f(n / t) <= limit, so it is t >= n / r*: a bound proportional to n.
    For the wavy rebound r* = n_ref / T, T the exact bound at n_ref on [phi, scan_to_deg]
    (`exact_amplitude_bound`): a <= limit for every n / t in [n_ref / scan_to_deg, r*]. With a
    box, T is the largest over its levers at n_ref (1 + margin) (`box_amplitude_bound`)."""
    g = task.time_coeffs_deg_per_rpm()
    why = [_time_law(task, k) if c > 0 else "" for k, c in enumerate(g)]
    for k in task.stress_arcs():
        c = task.stress_coeff_deg_per_rpm(k)
        if c > g[k]:
            g[k], why[k] = c, "contact_stress"
    bounds, phi = {}, _angle_floors_deg(task)
    for k in task.amplitude_arcs():
        n_ref = _reference_rpm(task)
        bounds[k] = box_amplitude_bound(task, box, n_ref, float(phi[k]), scan_to_deg, scan_step_deg)
        c = math.inf if bounds[k].from_deg is None else bounds[k].from_deg / n_ref
        if c > g[k]:
            g[k], why[k] = c, "amplitude"
    return g, why, bounds


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
    phi = _angle_floors_deg(task)
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
        n_max, status, message, clock.build_s, extra = _speed_graph(task, net, phi, g, why)
        bounds_at = functools.partial(_lp_bounds_at, phi, g, why)
    elif chosen == "lp":
        n_max, status, message, clock.build_s, extra = _speed_lp(task, net, phi, g, backend)
        bounds_at = functools.partial(_lp_bounds_at, phi, g, why)
    else:
        bounds_at = functools.partial(_exact_bounds_at, task, box, phi, scan_to_deg, scan_step_deg)
        n_max, status, message, clock.build_s, extra = _speed_bisection(task, net, bounds_at, rtol)
    sg = extra.pop("graph", None)
    cycle = extra.pop("limiting_cycle_arcs", None)
    diagnostics |= {"speed_coeffs_deg_per_rpm":
                    {f"{x}->{y}": float(g[k]) for k, (x, y) in enumerate(task.arcs) if g[k] > 0}} | extra
    if status is Status.SOLVED and n_max * g.max(initial=0.0) <= 1e-6:   # below a micro-degree: at rest
        status = Status.INFEASIBLE
    if status is Status.INFEASIBLE:
        chain = _conflict_at(task, net, phi) or _conflict_at(task, net, np.maximum(phi, g * rtol))
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
    certified = _certify_on_graph(sg, n_max, rtol) if sg else _certify_speed(task, net, bounds_at, n_max, rtol)
    values, more = _speed_report(task, net, lb, why_at, n_max, rtol, sg)
    if _closed_without_the_cycle(net, bounds_at(n_max * (1 + rtol))[0], sg):
        more["sens_cycle_rpm_per_deg"] = 0.0
    if sg:
        more["ranging_at_max_speed"] = sg.ranging(cycle, n_max, why)
    if check and not certified and chosen in ("graph", "lp"):
        certified = _check_by_other(chosen, task, net, phi, g, why, backend, n_max, more)
        if "rel" in more["check"]:
            values["check_rel"] = more["check"]["rel"]        # validate's certificate (the scenes: < 1e-9)
    held = amp_bounds if chosen in ("lp", "graph") else _exact_amplitude_bounds(task, box, phi, scan_to_deg,
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


def _speed_lp(task, net, phi, g, backend):
    """maximise n over (p, n): the LP of the docstring, built once per structure (DPP)."""
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


CHECK_RTOL = 1e-9                # the graph's speed against the LP's (check = true)


def _check_by_other(chosen, task, net, phi, g, why, backend, n_max, more):
    """'' when the other method (the LP in (p, n) for the graph, the graph for the LP) gives the
    same speed to CHECK_RTOL, else why not (its figures in `more`)."""
    other = "LP in (p, n)" if chosen == "graph" else "graph"
    solve = _speed_lp(task, net, phi, g, backend) if chosen == "graph" else _speed_graph(task, net, phi, g, why)
    n_other, status, message = solve[:3]
    more["check"] = {"method": other, "status": status.value, "max_speed_rpm": n_other}
    if status is not Status.SOLVED:
        return f"check failed: the {other} says {status.value} ({message})"
    more["check"]["rel"] = abs(n_other - n_max) / n_max
    if more["check"]["rel"] > CHECK_RTOL:
        return f"check failed: the {other} gives {n_other!r} rpm against the {chosen}'s {n_max!r}"
    return ""


def _lp_bounds_at(phi, g, why, n_rpm):
    """The LP's bounds at speed n: max([phi], g n) [deg], and which law sets each ("" for [phi])."""
    lb = np.maximum(phi, g * n_rpm)
    return lb, [w if g[k] * n_rpm >= phi[k] else "" for k, w in enumerate(why)]


def _exact_amplitude_bounds(task, box, phi, scan_to_deg, scan_step_deg, n_rpm):
    """Per amplitude arc, the rebound's exact bound at speed n on [phi, scan_to_deg] (over the box)."""
    return {k: box_amplitude_bound(task, box, n_rpm, float(phi[k]), scan_to_deg, scan_step_deg)
            for k in task.amplitude_arcs()}


def _exact_bounds_at(task, box, phi, scan_to_deg, scan_step_deg, n_rpm):
    """Each arc's smallest angle at speed n from the exact laws directly [deg], and which law sets
    it: the time floor, the stress bound sigma_ref t_ref n / ([sigma_H] n_ref), the rebound's
    exact bound on [phi, scan_to_deg] (inf where none holds there). At n = 0: [phi]."""
    lb = np.maximum(phi, task.time_coeffs_deg_per_rpm() * n_rpm)
    why = [_time_law(task, k) if b > p else "" for k, (b, p) in enumerate(zip(lb, phi))]
    for k in task.stress_arcs():
        bound = task.stress_coeff_deg_per_rpm(k) * n_rpm
        if bound > lb[k]:
            lb[k], why[k] = bound, "contact_stress"
    if n_rpm > 0:
        for k, b in _exact_amplitude_bounds(task, box, phi, scan_to_deg, scan_step_deg, n_rpm).items():
            bound = math.inf if b.from_deg is None else b.from_deg
            if bound > lb[k]:
                lb[k], why[k] = bound, "amplitude"
    return lb, why


def _speed_bisection(task, net, bounds_at, rtol):
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
            raise _Undecided(f"HiGHS: {status.value} at n = {n_rpm:.9g} rpm")
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
    except _Undecided as exc:
        return None, Status.FAILED, str(exc), build_s, {"bisection_steps": len(steps)}
    return (lo if hi > MIN_RPM else 0.0), Status.SOLVED, "", build_s, {"bisection_steps": len(steps),
                                                                     "bisection_bracket_rpm": [lo, hi]}


class _Undecided(Exception):
    """A feasibility LP that was neither optimal nor infeasible: bisection cannot go on."""


def _arcs_at(task, net, lb):
    """The difference constraints with the arcs' bounds `lb` and the cycle, for `positive_cycle`."""
    first, last = net.names[net.first], net.names[net.last]
    names = task.operation_names
    arcs = [(u, v, w, f"t({u}->{v}) >= {w:.6g} deg{names.get((u, v), '')}") for u, v, w in constraint_arcs(net, lb)]
    return arcs + [(last, first, -task.cycle_deg, f"cycle p({last}) - p({first}) <= {task.cycle_deg:.6g} deg")]


def _conflict_at(task, net, lb):
    return [(u, label, w) for u, _, w, label in positive_cycle(_arcs_at(task, net, lb))]


def _certify_speed(task, net, bounds_at, n_max, tol):
    """'' when the bounds at n_max (1 - tol) leave no positive cycle and those at n_max (1 + tol)
    do (so n_max is the largest speed to tol); else why not."""
    below, above = n_max * (1 - tol), n_max * (1 + tol)
    lb_below, lb_above = bounds_at(below)[0], bounds_at(above)[0]
    if not np.all(np.isfinite(lb_below)) or _conflict_at(task, net, lb_below):
        return f"certificate failed: n = {below:.9g} rpm (just under the answer) does not fit the cycle"
    if np.all(np.isfinite(lb_above)) and not _conflict_at(task, net, lb_above):
        return f"certificate failed: n = {above:.9g} rpm (just over the answer) still fits the cycle"
    return ""


def _passes(net, sg=None):
    """The longest-path passes over the operations and the back arcs without the machine cycle
    (windows, syncs): `sg`'s (a SpeedGraph) when given, else built (Levels: once per structure)."""
    if sg is not None:
        return sg.levels, sg.back
    return Levels.of(len(net.names), net.tails, net.heads), back_arcs(net, with_cycle=False)[0]


def _closed_without_the_cycle(net, lb_above, sg=None) -> bool:
    """Whether the bounds just above the highest speed hold a positive cycle of operations, windows
    and syncs alone: then a window, not the machine's cycle, limits the speed, and a longer cycle
    gives none (dn/dcycle = 0; the critical chain's slope is dn/dwindow)."""
    levels, back = _passes(net, sg)
    return bool(len(back)) and bool(np.all(np.isfinite(lb_above))) and levels.has_positive_cycle(lb_above, back)


def _speed_report(task, net, lb, why, n_max, tol, sg=None):
    """Event times at max speed (earliest start), exact readings, and which constraints limit it
    (times and floats by the longest-path passes: `sg`'s, a SpeedGraph, when given)."""
    levels, back = _passes(net, sg)
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


# ---------------------------------------------------------------- the graph method

GRAPH_TOL = 1e-10            # relative to the cycle [deg/deg]: a chain closing the cycle within it fits
UNBOUNDED_RPM = 1e12         # the parametric search starts here; a machine that still fits has no speed limit
NEWTON_MAX_STEPS = 200
RANGING_MAX_LIMITS = 8       # limits on the limiting cycle re-solved without them (one solve each)


class SpeedGraph:
    """The speed problem on the graph: arc k needs t >= max(phi_k, g_k n) (a + b n, piecewise),
    windows and syncs are back arcs, the cycle closes first -> last. Speed n fits when no cycle of
    these constraints has a positive sum.

    Why Newton on cycles (Dinkelbach's iteration for the parametric problem) and not Howard's
    policy iteration or bisection: each cycle's sum W_C(n) is convex, piecewise linear and
    non-decreasing in n, and the highest speed is the least root over the cycles. From a speed
    that does not fit, the positive cycle the longest-path pass finds has a root below it; at
    that root the cycle closes exactly. The next pass either finds the speed fits (the root is
    the answer, exact: no tolerance in n, unlike bisection's ~40 passes) or a cycle with a lower
    root. Each step is one numpy longest-path pass (graph.Levels) on the structure's levels;
    in practice 2-4 steps. Howard's algorithm needs a strongly connected policy graph and a
    ratio form (the max(phi, g n) arcs are not a ratio); it was not worth writing for 2-4 passes."""

    def __init__(self, task, net, phi, g):
        self.task, self.net, self.phi, self.g, self.cycle = task, net, phi, g, float(task.cycle_deg)
        self.levels = Levels.of(len(net.names), net.tails, net.heads)
        self.back, self.kinds = back_arcs(net, with_cycle=False)
        self.tol = GRAPH_TOL * max(1.0, self.cycle)
        self.passes = 0

    def bounds(self, n_rpm: float, g=None) -> np.ndarray:
        return np.maximum(self.phi, (self.g if g is None else g) * n_rpm)

    def positive_cycle_at(self, n_rpm: float, g=None):
        """None when speed n fits; else a positive cycle as [(kind, index)] in order around it,
        kind "op" (operation k), "back" (window or sync arc j) or "cycle"."""
        lb, net, back = self.bounds(n_rpm, g), self.net, self.back
        self.passes += 1
        if len(back) and self.levels.has_positive_cycle(lb, back):
            return self._windows_cycle(lb)
        dist = self.levels.longest_from(net.first, lb, back)
        if not np.isfinite(dist[net.last]) or dist[net.last] - self.cycle <= self.tol:
            return None
        m = len(lb)
        tails, heads = np.r_[net.tails, back.tails], np.r_[net.heads, back.heads]
        tight = tight_arcs(tails, heads, np.r_[lb, back.weights], dist, 1e-2 * self.tol)
        path = a_path(len(net.names), tails[tight], heads[tight], net.first, net.last)
        arcs = tight[np.asarray(path, dtype=np.int64)]
        return [("op", int(k)) if k < m else ("back", int(k - m)) for k in arcs] + [("cycle", 0)]

    def _windows_cycle(self, lb):
        """A positive cycle without the machine cycle (windows, syncs): conflicts.positive_cycle's own
        Bellman-Ford, which returns the cycle (the numpy pass only proves one exists)."""
        names, net, back = self.net.names, self.net, self.back
        arcs = [(x, y, float(lb[k]), ("op", k)) for k, (x, y) in enumerate(net.arcs)]
        arcs += [(names[u], names[v], float(w), ("back", j))
                 for j, (u, v, w) in enumerate(zip(back.tails.tolist(), back.heads.tolist(), back.weights.tolist()))]
        return [label for *_, label in positive_cycle(arcs)]

    def root(self, cycle, n_rpm: float, g=None) -> float:
        """The speed at which `cycle` (positive at n) closes exactly: sum max(phi, g n) + the back
        arcs' weights = 0, found piece by piece going down from n (convex: each piece's line
        meets 0 at or above the root; the piece that holds its own root is exact)."""
        g = self.g if g is None else g
        ops = np.array([k for kind, k in cycle if kind == "op"], dtype=np.int64)
        c = math.fsum(self.back.weights[k] for kind, k in cycle if kind == "back") \
            - (self.cycle if ("cycle", 0) in cycle else 0.0)
        phi, g = self.phi[ops], g[ops]
        for _ in range(len(ops) + 2):
            active = g * n_rpm > phi
            slope = math.fsum(g[active])
            if slope <= 0:
                return 0.0                  # positive at rest: the n = 0 test says so first
            new = -(c + math.fsum(phi[~active])) / slope
            # the piece's line lies under the convex sum, so the sum at `new` is >= 0; where it is 0
            # (to tol) `new` is the root, also when it falls on a kink g n = phi (an operation of a
            # fixed angle, min_deg = max_deg, with a time floor: the next piece has no slope)
            closes = c + math.fsum(np.maximum(phi, g * new)) <= self.tol
            if new >= n_rpm or closes or np.array_equal(g * new > phi, active):
                return min(new, n_rpm)
            n_rpm = new
        return n_rpm

    def highest_speed(self, g=None):
        """(n*, the limiting cycle, Newton steps); n* None: no limit grows with n (UNBOUNDED)."""
        n, steps = UNBOUNDED_RPM, 0
        cycle = self.positive_cycle_at(n, g)
        if cycle is None:
            return None, [], 0
        while steps < NEWTON_MAX_STEPS:
            if not cycle:
                raise _Undecided(f"graph: a positive cycle at n = {n:.12g} rpm that Bellman-Ford cannot name "
                                 f"(round-off at the answer)")
            root = self.root(cycle, n, g)
            steps += 1
            if not root < n:
                raise _Undecided(f"graph: the cycle found at n = {n:.12g} rpm does not close below it "
                                 f"(round-off at the answer)")
            following = self.positive_cycle_at(root, g)
            n = root
            if following is None:
                return n, cycle, steps
            cycle = following
        raise _Undecided(f"graph: no answer after {NEWTON_MAX_STEPS} steps")

    def describe(self, cycle, n_rpm: float, why) -> list[str]:
        """The cycle in the designer's words: each operation with the law that sets it at n."""
        net, names, group = self.net, self.net.names, dict(self.task.graph.nodes(data="group"))
        out = []
        for kind, k in cycle:
            if kind == "op":
                x, y = net.arcs[k]
                speed_set = self.g[k] * n_rpm > self.phi[k]
                law = why[k] if speed_set else "min_angle"
                out.append(f"{law}[{x}->{y}] t >= {max(self.phi[k], self.g[k] * n_rpm):.6g} deg "
                           f"({group[x] or group[y] or '-'}"
                           + (f", {self.g[k]:.6g} deg/rpm)" if speed_set else ")")
                           + self.task.operation_names.get((x, y), ""))
            elif kind == "back":
                u, v, w = names[self.back.tails[k]], names[self.back.heads[k]], self.back.weights[k]
                out.append(f"sync p({u}) = p({v})" if self.kinds[k] == "sync"
                           else f"window p({u}) - p({v}) <= {-w:.6g} deg")
            else:
                out.append(f"cycle p({names[net.last]}) - p({names[net.first]}) <= {self.cycle:.6g} deg")
        return out

    def ranging(self, cycle, n_rpm: float, why) -> list[dict]:
        """Which limit to relax for the next rpm: per speed-set operation on the limiting cycle,
        d n / d g (rpm per deg/rpm of its slope), and the speed with that limit gone (the next
        cycle's root, one Newton solve) and the limit that then binds: the range over which
        relaxing it pays."""
        ops = [k for kind, k in cycle if kind == "op" and self.g[k] * n_rpm > self.phi[k]]
        slope = math.fsum(self.g[k] for k in ops)
        rows = []
        for k in ops[:RANGING_MAX_LIMITS]:
            x, y = self.net.arcs[k]
            g = self.g.copy()
            g[k] = 0.0
            n_next, nxt, _ = self.highest_speed(g)
            limits = [f"{why[j]}[{self.net.arcs[j][0]}->{self.net.arcs[j][1]}]" for kind, j in nxt
                      if kind == "op" and g[j] * n_next > self.phi[j]] if n_next is not None else []
            rows.append({"constraint": f"{why[k]}[{x}->{y}]", "deg_per_rpm": float(self.g[k]),
                         "rpm_per_deg_per_rpm": -n_rpm / slope if slope > 0 else -math.inf,
                         "rpm_without_it": n_next if n_next is not None else math.inf,
                         "then_limited_by": limits or ["cycle" if n_next is not None else "nothing: unbounded"]})
        return rows


def _speed_graph(task, net, phi, g, why):
    """maximise n on the graph (SpeedGraph): INFEASIBLE when n = 0 does not fit."""
    clock = Clock()
    sg = SpeedGraph(task, net, phi, g)
    build_s = clock.elapsed()
    if sg.positive_cycle_at(0.0) is not None:
        return None, Status.INFEASIBLE, "", build_s, {"graph": sg}
    try:
        n_max, cycle, steps = sg.highest_speed()
    except _Undecided as exc:
        return None, Status.FAILED, str(exc), build_s, {"graph": sg}
    if n_max is None:
        return None, Status.UNBOUNDED, f"graph: n = {UNBOUNDED_RPM:g} rpm still fits", build_s, {"graph": sg}
    extra = {"graph": sg, "newton_steps": steps, "limiting_cycle": sg.describe(cycle, n_max, why),
             "limiting_cycle_arcs": cycle}
    return n_max, Status.SOLVED, "", build_s, extra


def _certify_on_graph(sg, n_max, tol):
    """'' when the graph says n_max (1 - tol) fits and n_max (1 + tol) does not; else why not."""
    if sg.positive_cycle_at(n_max * (1 - tol)) is not None:
        return f"certificate failed: n = {n_max * (1 - tol):.9g} rpm (just under the answer) does not fit the cycle"
    if sg.positive_cycle_at(n_max * (1 + tol)) is None:
        return f"certificate failed: n = {n_max * (1 + tol):.9g} rpm (just over the answer) still fits the cycle"
    return ""
