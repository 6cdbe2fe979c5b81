"""The exact amplitude law a(t, n) of the first rebound (eq. (2)), vectorised over speed and phase
angle, and its tangent: the linear constraint the loom's LP takes."""
import numpy as np

from mechopt.models.errors import ModelError
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m, response_parts


def rebound_amplitude_mm(task: LeverStop, speed_rpm, t_deg, *, grid_points: int = 4097):
    """The exact first-rebound amplitude a(t, n) of eq. (2) [mm], vectorised over speed [rpm]
    and phase angle [deg] (broadcast).

    v0 and F scale as r = n / t and the preload does not, so q(s) = r g(s) + p(s) with g, p the
    responses per unit r and to the preload alone. Without preload a = r max g exactly. With it,
    on a time grid the largest q is the upper
    envelope of the lines r g_j + p_j: built once, then each point's grid maximum is a binary
    search in r. One Newton step on q' = 0 polishes it: it squares the time error of a 1/4096
    window cell, and the peak's value errs by the square of that (below 1e-14 relative). The
    step is kept inside the cells either side of the grid maximum, the value never below it.
    """
    speed, t = np.broadcast_arrays(np.asarray(speed_rpm, float), np.asarray(t_deg, float))
    unit = task.impact(1.0, 1.0)                      # v0 and F per unit n / t
    r = (speed / t).ravel()
    if unit.preload_N == 0.0:                         # q = r g(s): the peak's time does not move with r
        return (r * closed_form_amplitude_m(unit)[0] * 1e3).reshape(speed.shape)
    grid = np.linspace(0.0, unit.window_s, grid_points)
    g, p = (part[0] for part in response_parts(unit, grid))
    lines, breaks = _upper_envelope(g, p)
    j = lines[np.searchsorted(breaks, r)]
    s = grid[j]
    best = r * g[j] + p[j]
    lo, hi = np.maximum(s - grid[1], 0.0), np.minimum(s + grid[1], grid[-1])
    moving, pressed = response_parts(unit, s)
    qd, qdd = r * moving[1] + pressed[1], r * moving[2] + pressed[2]
    newton = s - qd / np.where(qdd < 0, qdd, -1.0)
    s = np.where((qdd < 0) & (newton > lo) & (newton < hi), newton, s)
    moving, pressed = response_parts(unit, s)
    peak = np.maximum(r * moving[0] + pressed[0], best)
    return (np.maximum(peak, 0.0) * 1e3).reshape(speed.shape)


def _upper_envelope(slopes, offsets):
    """Lines y = slope * r + offset: (indices of the lines on the upper envelope, in order of r,
    and the r where each hands over to the next)."""
    order = np.lexsort((offsets, slopes))            # by slope, then offset: the last of equals wins
    hull, breaks = [], []
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
    imp = task.impact(task.speed_nominal_rpm)
    a_m, when = closed_form_amplitude_m(imp)
    if a_m <= 0:
        raise ModelError(f"at t_deg={task.t_deg}, speed_nominal_rpm={task.speed_nominal_rpm} the lever does not "
                         f"leave the plate (amplitude 0): no tangent to linearise", key="t_deg")
    moving, _ = response_parts(imp, when)
    slope = -float(moving[0]) / task.t_deg * 1e3
    return slope, a_m * 1e3 - slope * task.t_deg
