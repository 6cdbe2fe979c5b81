"""The exact amplitude law a(t, n) of the first rebound (eq. (2)), vectorised over speed and phase
angle, and its tangent: the linear constraint the loom's LP takes.

Two sources of the approach velocity v0, by the task's effects:

* `cam_drive` (the chain): cam law -> elastic lever (solvers/stop_impact/cam_follower.py) ->
  v0 at the located contact -> impact pulse and eq. (2) -> first rebound. In a groove (closure
  "groove") whose roller crosses to the other wall before C meets its plate, v0 is the hybrid
  model's with the backlash (solvers/stop_impact/groove.py): the crossover comes before the
  stop impact, and its flight moves the approach (eq. (2) itself starts after the stop impact).
  Where the groove's exact phases apply (groove.follow_groove_exact), v0 is theirs, crossing or
  not; elsewhere the CVODES rise decides. v0 is no longer proportional to n / t (the dynamic
  error grows with speed), so each (n, t) is its own rise.
* otherwise the fitted proportionality v0 = velocity_factor * stroke * Omega / t.
"""
import numpy as np

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError, SolverError
from mechopt.kit.result import Status
from mechopt.models.stop_impact import Impact, LeverStop
from mechopt.solvers.stop_impact.cam_follower import follow_cam
from mechopt.solvers.stop_impact.groove import follow_groove, follow_groove_exact
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m, response_parts
from mechopt.solvers.stop_impact.rise_batch import ROLLER_LEFT, TAKEN, rise_batch


class RollerLeftCam(SolverError):
    """The cam's rise at some (n, t) is not SOLVED (the roller leaves its cam, or CVODES gave up):
    no approach velocity, so no rebound. `status` says which."""

    def __init__(self, message, status):
        super().__init__(message)
        self.status = status


CHAIN_RELTOL = 1e-12            # CVODES on the rise for the law: its tangent is a difference quotient
TANGENT_STEP_DEG = 1e-2         # central differences of a(t) at +-1, +-2 steps (fourth order)


def approach_velocity_m_s(task: LeverStop, speed_rpm: float, t_deg: float | None = None) -> float:
    """v0 at one speed [rpm] and phase angle [deg]: from the cam's rise with the effect
    `cam_drive` (a rise that is not SOLVED, e.g. the roller leaving its cam, is an error naming
    it; a C that only settles onto its plate has v0 = 0), else the task's fitted proportionality."""
    if "cam_drive" not in task.effects:
        return float(task.approach_velocity_m_s(speed_rpm, t_deg))
    return _rise_velocity(task, float(speed_rpm), None if t_deg is None else float(t_deg))


@memoised(maxsize=4096)     # the chain asks for the same rise again (a law's tangent, a walk, its check)
def _rise_velocity(task: LeverStop, speed_rpm: float, t_deg: float | None) -> float:
    if task.closure == "groove" and "damping" in task.effects and task.damping_ratio:
        # the groove's exact rise (ms, against the chain's CVODES rise, which it agrees with to
        # CVODES' error, ~1e-10): a flight before its contact is the crossover before the plate
        # below (both ride the driving wall until then); without one it is the driving wall's
        # rise itself, exact, so CVODES is not run at all
        real = follow_groove_exact(task, speed_rpm, t_deg)
        if real is not None and real.status is Status.SOLVED and real.contact_xi is not None:
            return real.approach_velocity_m_s
    rise = follow_cam(task, speed_rpm, t_deg, reltol=CHAIN_RELTOL)
    if rise.status is not Status.SOLVED:        # (no contact at all: C settles onto the plate, v0 = 0)
        raise RollerLeftCam(f"speed {speed_rpm:g} rpm, t = {rise.t_deg:g} deg: no approach velocity: {rise.message}",
                            rise.status)
    if rise.crossovers and (rise.contact_xi is None or rise.crossovers[0].xi < rise.contact_xi):
        # a groove's crossover before the plate: its flight across the backlash moves C's approach
        # (the walls taken with their play: the hybrid model, solvers/stop_impact/groove.py)
        real = follow_groove(task, speed_rpm, t_deg)
        if real.status is not Status.SOLVED:
            raise RollerLeftCam(f"speed {speed_rpm:g} rpm, t = {rise.t_deg:g} deg: the groove's rise with its "
                                f"backlash: {real.message}", real.status)
        return real.approach_velocity_m_s
    return rise.approach_velocity_m_s


def impact_at(task: LeverStop, speed_rpm: float, t_deg: float | None = None) -> Impact:
    """The inputs of eq. (2) at one speed and phase angle, v0 from `approach_velocity_m_s`."""
    return task.impact(speed_rpm, t_deg, v0_m_s=approach_velocity_m_s(task, speed_rpm, t_deg))


def rebound_amplitude_mm(task: LeverStop, speed_rpm, t_deg, *, grid_points: int = 4097, lost=None):
    """The exact first-rebound amplitude a(t, n) of eq. (2) [mm], vectorised over speed [rpm]
    and phase angle [deg] (broadcast). Where the roller leaves its cam (effect `cam_drive`) there
    is no rebound: `RollerLeftCam` is raised, or, with `lost` a number (a figure's NaN), that
    number stands there (only there: a rise the integrator failed on is raised whatever `lost`).

    v0 and F scale as r = n / t and the preload does not, so q(s) = r g(s) + p(s) with g, p the
    responses per unit r and to the preload alone. Without preload a = r max g exactly. With it,
    on a time grid the largest q is the upper
    envelope of the lines r g_j + p_j: built once, then each point's grid maximum is a binary
    search in r. One Newton step on q' = 0 polishes it: it squares the time error of a 1/4096
    window cell, and the peak's value errs by the square of that (below 1e-14 relative). The
    step is kept inside the cells either side of the grid maximum, the value never below it.
    """
    speed, t = np.broadcast_arrays(np.asarray(speed_rpm, float), np.asarray(t_deg, float))
    if "cam_drive" in task.effects:                   # each (n, t) its own rise, each pair once
        pairs = {(n, tt) for n, tt in zip(speed.ravel(), t.ravel())}
        amp = {pair: _amplitude_or(lost, task, *pair) for pair in pairs}
        return np.array([amp[pair] for pair in zip(speed.ravel(), t.ravel())]).reshape(speed.shape)
    unit = task.impact(1.0, 1.0)                      # v0 and F per unit n / t
    return (envelope_amplitude_m((speed / t).ravel(), unit, grid_points) * 1e3).reshape(speed.shape)


def envelope_amplitude_m(r, unit, grid_points: int = 4097):
    """The first rebound [m] where v0 and F are r times those of `unit` (an Impact) and the
    preload is not: `rebound_amplitude_mm`'s envelope and one Newton step (its docstring)."""
    r = np.asarray(r, float)
    if unit.preload_N == 0.0:                         # q = r g(s): the peak's time does not move with r
        return r * closed_form_amplitude_m(unit)[0]
    grid, g, p, lines, breaks = _envelope(unit, grid_points)
    j = lines[np.searchsorted(breaks, r)]
    s = grid[j]
    best = r * g[j] + p[j]
    lo, hi = np.maximum(s - grid[1], 0.0), np.minimum(s + grid[1], grid[-1])
    moving, pressed = response_parts(unit, s)
    qd, qdd = r * moving[1] + pressed[1], r * moving[2] + pressed[2]
    newton = s - qd / np.where(qdd < 0, qdd, -1.0)
    s = np.where((qdd < 0) & (newton > lo) & (newton < hi), newton, s)
    moving, pressed = response_parts(unit, s)
    return np.maximum(np.maximum(r * moving[0] + pressed[0], best), 0.0)


@memoised(maxsize=32)
def _envelope(unit, grid_points):
    """The time grid, the responses per unit r and to the preload on it, their upper envelope."""
    grid = np.linspace(0.0, unit.window_s, grid_points)
    g, p = (part[0] for part in response_parts(unit, grid))
    return (grid, g, p, *upper_envelope(g, p))


def chain_rebounds_mm(task: LeverStop, speed_rpm, t_deg, *, lost=None):
    """`rebound_amplitude_mm` of the chain (effect cam_drive) at many (n, t) [rpm, deg] at once:
    the rises by their exact solution in one pass (solvers/stop_impact/rise_batch.py), eq. (2)
    for all v0 at once on the envelope of `envelope_amplitude_m` (its peak within 1e-13 of the
    chain's per-point Newton); where that path does not go (and where the roller leaves its cam
    without `lost`), the per-point chain. Agrees with it to CVODES' own error (~1e-10 relative)."""
    speed, t = np.broadcast_arrays(np.asarray(speed_rpm, float), np.asarray(t_deg, float))
    if "cam_drive" not in task.effects:
        return rebound_amplitude_mm(task, speed, t, lost=lost)
    v0, outcome = rise_batch(task, speed.ravel(), t.ravel())
    out = np.zeros(v0.size)
    taken, gone = outcome == TAKEN, (outcome == ROLLER_LEFT) & (lost is not None)
    if taken.any():             # eq. (2)'s v0 and F scale with v0, the preload does not: the envelope
        out[taken] = envelope_amplitude_m(v0[taken], task.impact(1.0, 1.0, v0_m_s=1.0)) * 1e3
    out[gone] = lost
    for i in np.flatnonzero(~taken & ~gone):
        out[i] = _amplitude_or(lost, task, speed.ravel()[i], t.ravel()[i])
    return out.reshape(speed.shape)


def _amplitude_or(lost, task, speed_rpm, t_deg):
    """One (n, t) of the chain [mm]; `lost` where the roller leaves its cam, unless it is None."""
    try:
        return closed_form_amplitude_m(impact_at(task, speed_rpm, t_deg))[0] * 1e3
    except RollerLeftCam as exc:
        if lost is None or exc.status is not Status.INFEASIBLE:    # an integrator's failure is no gap
            raise
        return lost


def upper_envelope(slopes, offsets):
    """Lines y = slope * r + offset: (indices of the lines on the upper envelope, in order of r,
    and the r where each hands over to the next)."""
    order = np.lexsort((offsets, slopes)).tolist()   # by slope, then offset: the last of equals wins
    slopes, offsets = np.asarray(slopes, float).tolist(), np.asarray(offsets, float).tolist()   # Python floats:
    hull, breaks = [], []                            # the same arithmetic, without numpy's per-scalar cost
    for i in order:
        if hull and slopes[hull[-1]] == slopes[i]:
            hull.pop()
            if breaks:
                breaks.pop()
        while hull:
            j = hull[-1]
            x = (offsets[j] - offsets[i]) / (slopes[i] - slopes[j])       # where line i overtakes j
            if breaks and x <= breaks[-1]:
                hull.pop()
                breaks.pop()
                continue
            breaks.append(x)
            break
        hull.append(i)
    return np.array(hull), np.array(breaks)


def amplitude_law(task: LeverStop):
    """The tangent of a(t) at the nominal phase angle and speed, for the LP's constraint
    a(3,7) = slope * t(3,7) + intercept: returns (slope_mm_per_deg, intercept_mm).

    By the envelope theorem the peak's sensitivity is that of q at the peak's time; v0 and F
    scale as 1/t, the preload does not: da/dt = -(a + P/m U(t*)) / t.
    """
    task.need("t_deg", "speed_nominal_rpm")
    if "cam_drive" in task.effects:
        return _chain_tangent(task)
    imp = task.impact(task.speed_nominal_rpm)
    a_m, when = closed_form_amplitude_m(imp)
    if a_m <= 0:
        raise ModelError(f"at t_deg={task.t_deg}, speed_nominal_rpm={task.speed_nominal_rpm} the lever does not "
                         f"leave the plate (amplitude 0): no tangent to linearise", key="t_deg")
    moving, _ = response_parts(imp, when)
    slope = -float(moving[0]) / task.t_deg * 1e3
    return slope, a_m * 1e3 - slope * task.t_deg


def _chain_tangent(task):
    """The tangent of the chain's a(t) at (t_deg, speed_nominal_rpm): fourth-order central
    differences (the peak moves with t, and so does the contact on the cam)."""
    n, t, h = task.speed_nominal_rpm, task.t_deg, TANGENT_STEP_DEG
    a = rebound_amplitude_mm(task, n, np.array([t - 2 * h, t - h, t, t + h, t + 2 * h]))
    if a[2] <= 0:
        raise ModelError(f"at t_deg={t}, speed_nominal_rpm={n} the lever does not leave the plate (amplitude 0): "
                         "no tangent to linearise", key="t_deg")
    slope = (a[0] - 8 * a[1] + 8 * a[3] - a[4]) / (12 * h)
    return float(slope), float(a[2] - slope * t)
