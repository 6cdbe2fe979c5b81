"""The synthesis' search (solvers/stop_impact/synthesis.py): the best law at one phase angle, and
the least phase angle.

At one t (`design_law`): the window LP (solvers/stop_impact/window_lp.py) over the arrival
window's start xi_a, scanned (a few candidates, then the neighbours of the best; each candidate
one LP solve, status checked); then the dense check of the linear model between the sampled
speeds (every `dense_step_rpm`): a speed that breaks the limit (or the LP's bound) is added to the
samples and the LP solved again. With the cam's geometry, sequential LPs around the law
(solvers/stop_impact/synthesis_geometry.py).

The least phase (`least_phase`): regula falsi (Illinois) on r*(t) - limit in [phase_from_deg,
phase_to_deg] to `phase_tol_deg` or r* within ROOT_FTOL of the limit, r*(t) the least-rebound
LP's value, assumed to fall as t grows (more time, slower arrival: stated, not proven); a t below
the kinematic minimum is a bisection step.
"""
import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from mechopt.kit.result import Status
from mechopt.models.cam_law import SplineLaw
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.cam_rows import CamGeometry, GeometryCheck
from mechopt.solvers.stop_impact.lever_box import LeverBox
from mechopt.solvers.stop_impact.synthesis_geometry import geometry_steps
from mechopt.solvers.stop_impact.window_lp import (
    DWELL_XI,
    WindowLP,
    band_speeds,
    kinematic_conflict,
    lever_lines,
    linear_lever,
    predicted_rebounds_mm,
    speed_response,
)

__all__ = ["Design", "dense_worst", "design_law", "least_phase", "points_text", "scan_windows"]

WINDOW_CANDIDATES = (0.7, 0.8, 0.9)            # xi_a scanned first, then halved steps around the best
WINDOW_REFINE = 1               # halvings of the scan step around the best window
BOUND_MARGIN = 1e-3             # a window's bound rules it out only this far (relative) above a value found: the
                                # LP's tolerances move a window's value with a row more by ~3e-7 (measured), not more
ROOT_FTOL = 1e-4                # the least phase: r*(t) within this of the limit (relative) ends the search
MAX_PHASE_STEPS = 40
ROBUST_ROUNDS = 8               # rounds of the dense check over the box's grid for one LP (each adds every
                                # lever's worst point that fails: a count)


@dataclass
class Design:
    status: Status
    law: SplineLaw | None
    value: float
    window_xi: float
    speeds: list
    lps: int
    message: str = ""
    violated: tuple = ()
    given_up: int = 0               # windows HiGHS did not settle within its iteration limits (WindowLP.solve)
    retried: int = 0                # windows the dual simplex did not settle, retried by the interior point
    c: np.ndarray | None = None     # the law's free coefficients
    geometry: GeometryCheck | None = None   # its cam's exact geometry (with a CamGeometry)
    geometry_steps: int = 0         # the sequential geometry LPs taken


def design_law(task: LeverStop, t_deg: float, band_rpm: tuple, *, geometry: CamGeometry | None = None,
               **settings) -> Design:
    """The best law at phase angle `t_deg` (`_design`: its settings); with `geometry`, its cam's
    pressure angle and radius of curvature held too, by sequential LPs (`synthesis_geometry.geometry_steps`)."""
    if geometry is None:
        return _design(task, t_deg, band_rpm, **settings)
    return geometry_steps(task, t_deg, band_rpm, geometry, settings, _design)


def _design(task: LeverStop, t_deg: float, band_rpm: tuple, *, objective="least_rebound", coefficients=100,
            continuity=2, sample_speeds=5, dense_step_rpm=5.0, bounds=None, rounds=4, samples=None,
            around=None, dense_bar_mm=None, explain=True, box: LeverBox | None = None, extra=None) -> Design:
    """The best law at phase angle `t_deg` over the speed band: the LP over the arrival window
    (`scan_windows`), the dense check between the sampled speeds, a failing speed added and the LP solved
    again (at most `rounds` times). The dense check holds the law to the LP's own value (least
    rebound) or to the limit (`dense_bar_mm`, the least phase's question: is the limit kept?).
    `explain`: when no window is feasible, a slack LP names the limits that bind (the least
    phase's search skips it).

    `box` (solvers/stop_impact/lever_box.py): the LP holds the box's nominal and corner levers at
    the sampled speeds of the band raised by its margin, the dense check runs over its grid of
    levers, and a failing (lever, speed) is added as a failing speed is. The samples are points
    (frequency factor, zeta, rpm); `rounds` counts the rounds of additions (each adds every lever's failing worst)."""
    bounds = bounds or {}
    box = box or LeverBox()
    lever = linear_lever(coefficients, continuity)
    limit = task.amplitude_limit_mm
    lo, hi = box.band(band_rpm)
    if samples is None:
        speeds0 = list(np.linspace(lo, hi, sample_speeds)) if sample_speeds > 1 else [hi]
        samples = [key + (float(n),) for key in box.corners(task) for n in speeds0]
    samples = sorted(tuple(map(float, point)) for point in samples)
    dense = band_speeds((lo, hi), dense_step_rpm)
    conflict = kinematic_conflict(lever, t_deg, task.stroke_mm, bounds)
    if conflict:
        return Design(Status.INFEASIBLE, None, math.inf, math.nan, samples, 1,
                       f"no law at t = {t_deg:.6g} deg keeps the kinematic bounds: binding: {', '.join(conflict)}",
                       conflict)
    levers = {key: LeverBox.lever(task, key) for key in box.grid_keys(task) + box.corners(task)}
    lines = {key: lever_lines(each, limit) for key, each in levers.items()}
    lps, counts, floors, responses = 0, {"given_up": 0, "retried": 0}, None, {}
    for _ in range(rounds):
        levers |= {p[:2]: LeverBox.lever(task, p[:2]) for p in samples if p[:2] not in levers}
        lines |= {key: lever_lines(each, limit) for key, each in levers.items() if key not in lines}
        responses |= {p: speed_response(levers[p[:2]], lever, p[2], t_deg, lines[p[:2]])
                      for p in samples if p not in responses}       # a round's samples are the last's and more
        speeds = [responses[p] for p in samples]
        nominal = lines[box.nominal(task)]
        lp = WindowLP(task, lever, speeds, t_deg, objective=objective, limit_mm=limit, bounds=bounds, lines=nominal,
                      extra=extra)
        (status, c, value, xa), count, floors = scan_windows(lp, around, floors)   # next round: these bound its windows
        lps = lps + count
        counts = {"given_up": counts["given_up"] + lp.given_up, "retried": counts["retried"] + lp.held.retried}
        if status is Status.INFEASIBLE and not explain:
            return Design(Status.INFEASIBLE, None, math.inf, xa, samples, lps,
                           f"no law at t = {t_deg:.6g} deg keeps every limit", **counts)
        if status is Status.INFEASIBLE:
            slack = WindowLP(task, lever, speeds, t_deg, objective=objective, limit_mm=limit, bounds=bounds,
                              lines=nominal, slack=True, extra=extra)
            (_, _, _, xa), count, _ = scan_windows(slack)
            sl = slack.solve(xa)[3]
            binding = tuple(k for k, v in sl.items() if v > 1e-9)
            return Design(Status.INFEASIBLE, None, math.inf, xa, samples, lps + count,
                           f"no law at t = {t_deg:.6g} deg keeps every limit at {points_text(samples)}; "
                           f"binding: {', '.join(binding) or 'none found'}", binding, **counts)
        if status is not Status.SOLVED:
            return Design(status, None, math.inf, xa, samples, lps, f"HiGHS: {status.value} at xi_a = {xa:g}",
                           **counts)
        law = lever.basis.law(c)
        bar = dense_bar_mm if dense_bar_mm is not None else value if objective == "least_rebound" else limit
        failing = [(mm, point) for key in box.grid_keys(task)
                   for mm, point in [dense_worst(levers, [key], law, t_deg, dense, lever)]
                   if mm > bar * (1 + 1e-3) + 1e-4 * limit and point not in samples]
        if not failing:
            return Design(Status.SOLVED, law, value, xa, samples, lps, **counts, c=c)
        worst = max(failing)[1]
        samples = sorted(samples + [point for _, point in failing])   # broken between samples: sample them too
    return Design(Status.LIMIT, law, value, xa, samples, lps,
                   f"the dense check still fails at {points_text([worst])} after {rounds} rounds", **counts, c=c)


def dense_worst(levers, keys, law, t_deg, dense, lever):
    """(the linear model's largest rebound [mm], its point (frequency factor, zeta, rpm)) over the
    levers `keys` at every speed of `dense`."""
    best = (-math.inf, None)
    for key in keys:
        pred = [p[0] for p in predicted_rebounds_mm(levers[key], law, t_deg, dense, lever=lever)]
        j = int(np.argmax(pred))
        if pred[j] > best[0]:
            best = (pred[j], key + (float(dense[j]),))
    return best


def points_text(points):
    """Sampled points for a message: the speeds alone when every point is one lever."""
    if len({p[:2] for p in points}) == 1:
        return f"{', '.join(f'{p[2]:g}' for p in points)} rpm"
    return ", ".join(f"(f x{p[0]:g}, zeta {p[1]:g}, {p[2]:g} rpm)" for p in points)


def scan_windows(lp, around=None, floors=None):
    """((status, c, value, xi_a) of the best window, LPs solved, {xi_a: (status, value or its
    lower bound)} of the windows tried): WINDOW_CANDIDATES (or, `around` a window that was best at
    a neighbouring t, it and its neighbours), then steps halved around the best (the value is not
    convex in xi_a: a scan, stated, not a proof).

    `floors`: the windows tried of the same LP with fewer rows (the dense check's round before: a
    sample more is rows more, so its values are lower bounds here and its infeasible windows stay
    infeasible). Each stage's windows are solved lowest bound first; a window proven infeasible
    there, or whose bound exceeds by BOUND_MARGIN a value already solved here, is not solved: it
    cannot be the best, so the scan takes the same steps to the same best window and law."""
    floors, tried, bounded = floors or {}, {}, set()
    step = WINDOW_CANDIDATES[1] - WINDOW_CANDIDATES[0]
    first = WINDOW_CANDIDATES if around is None else (around - step / 2, around, around + step / 2)

    def stage(windows):
        todo = [xa for xa in dict.fromkeys(round(float(w), 12) for w in windows)
                if xa not in tried and 0.0 < xa <= 1.0 + DWELL_XI]
        got = {}
        for xa in sorted(todo, key=lambda w: floors.get(w, (None, -math.inf))[1]):     # stable: no floors, in order
            found = [v[2] for k, v in (tried | got).items() if k not in bounded]
            got[xa] = _floor_rules_out(floors.get(xa), found)
            if got[xa] is None:
                got[xa] = lp.solve(xa)
            else:
                bounded.add(xa)
        tried.update((xa, got[xa]) for xa in todo)          # in the scan's order: min() breaks ties as before
    stage(first)
    if around is not None:
        step /= 2
        if not any(math.isfinite(v[2]) for v in tried.values()):      # lost it: the full scan
            best, count, seen = scan_windows(lp, floors=floors)
            return best, count + len(tried) - len(bounded), seen
    for _ in range(WINDOW_REFINE):
        best = min(tried, key=lambda k: tried[k][2])
        if not math.isfinite(tried[best][2]):
            break
        step /= 2
        stage((best - step, best + step))
    best = min(tried, key=lambda k: tried[k][2])
    solved = {k: v for k, v in tried.items() if k not in bounded}
    seen = {k: (v[0], v[2]) for k, v in tried.items()}     # a lower bound stays one with more rows
    status, c, value, _ = tried[best]
    if status is Status.INFEASIBLE:         # a window HiGHS failed on is no proof of infeasibility
        failed = [k for k, v in solved.items() if v[0] not in (Status.SOLVED, Status.INFEASIBLE)]
        if failed:
            return (tried[failed[0]][0], None, math.inf, failed[0]), len(solved), seen
    return (status, c, value, best), len(solved), seen


def _floor_rules_out(floor, found):
    """A window's (status, None, value, {}) standing for its LP when its floor (`scan_windows`) rules it
    out: infeasible there, or a bound above the least value `found` so far; else None."""
    if floor is None:
        return None
    status, value = floor
    if status is Status.INFEASIBLE:
        return Status.INFEASIBLE, None, math.inf, {}
    least = min((v for v in found if math.isfinite(v)), default=math.inf)
    if status is Status.SOLVED and math.isfinite(least) and value > least + BOUND_MARGIN * abs(least):
        return Status.SOLVED, None, value, {}
    return None


def least_phase(task, band, lo, hi, tol, common):
    """The least t with the least rebound over the band <= limit: regula falsi (Illinois) on
    r*(t) - limit, r*(t) the least-rebound LP's value, assumed to fall as t grows (stated, not
    proven); a t with no law at all (below the kinematic minimum, or every window given up by
    HiGHS: counted, the search moves up) is a bisection step. The speeds the dense check added and
    the best window are carried to the next t."""
    limit = task.amplitude_limit_mm
    state = {"samples": None, "around": None, "steps": 0, "given_up": 0, "retried": 0}

    def excess(t):
        d = design_law(task, t, band, objective="least_rebound", samples=state["samples"], around=state["around"],
                       dense_bar_mm=limit, explain=False, **common)
        state["steps"] += 1
        state["given_up"] += d.given_up
        state["retried"] += d.retried
        if d.status is Status.SOLVED:
            state["samples"], state["around"] = d.speeds, d.window_xi
            return d.value - limit, d
        # no window solved, some given up (LIMIT): no law found here, the search moves up (counted)
        return (math.inf if d.status in (Status.INFEASIBLE, Status.LIMIT) and d.law is None else math.nan), d
    f_hi, best = excess(hi)
    if not f_hi <= 0:
        if best.status is Status.INFEASIBLE:         # no law even at the bracket's top: name what binds
            best = design_law(task, hi, band, objective="least_rebound", dense_bar_mm=limit, **common)
        if best.status is Status.SOLVED:
            best = dataclasses.replace(best, status=Status.INFEASIBLE, violated=("amplitude",),
                                       message=f"no law keeps amplitude_limit_mm={limit:g} over {band[0]:g}-{band[1]:g} "
                                               f"rpm even at t = {hi:g} deg: the best is {best.value:.4g} mm")
        return best, hi, state
    f_lo, low = excess(lo)
    if f_lo <= 0:                                   # the bracket's bottom already keeps it
        return low, lo, state
    side = 0
    while hi - lo > tol:
        if math.isfinite(f_lo):
            mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            mid = min(max(mid, lo + 0.1 * tol), hi - 0.1 * tol)
        else:
            mid = 0.5 * (lo + hi)
        f_mid, d = excess(mid)
        if math.isnan(f_mid):
            return d, mid, state
        if f_mid <= 0:
            hi, f_hi, best = mid, f_mid, d
            if side == -1 and math.isfinite(f_lo):
                f_lo /= 2                           # Illinois: the stale end's weight halved
            side = -1
        else:
            lo, f_lo = mid, f_mid
            if side == 1:
                f_hi /= 2
            side = 1
        if -f_hi <= ROOT_FTOL * limit or state["steps"] >= MAX_PHASE_STEPS:   # r*(hi) is the limit to the LP's digits
            break
    return best, hi, state
