"""The lever's first rebound off its stop (paper 004, eq. (2)): three independent ways to it,
the stiffness and impact figures around it, an event-driven check, and the LP's amplitude law.

Eq. (2) is q'' + 2 n q' + omega^2 q = (Q_F(t) - P) / m, q(0) = 0, q'(0) = v0, with the
triangular pulse Q_F (peak F at tau, zero at 2 tau) and the preload P (see models/stop_impact.py
for every reading). The first rebound is the largest q in [0, 2 tau + 2 pi / omega].

* `closed_form_response`  the Duhamel integral of the triangle in closed form. It never divides
  by k1 = sqrt(omega^2 - n^2): cos(k1 t) and sin(k1 t)/k1 are entire functions of k1^2 t^2
  (`_damped_cos_sinc`): critical and overdamped damping need no special case; for omega tau < 1e-3
  the pulse is expanded about its centre (moments of the triangle), so tau -> 0 gives the impulse.
* `quadrature_response`   scipy's QUADPACK on the Duhamel integrals, split at the pulse's kinks.
* `ode_amplitude_m`       CasADi/CVODES on the ODE itself, integrated phase by phase so the
  integrator never steps over a kink of Q_F.

Solvers (scene entry points): `natural_frequencies`, `impact_forces`, `rebound`,
`linearise_amplitude`, `operating_point` (one speed and phase angle against the limit: maps).
For other code: `rebound_amplitude_mm` (the exact law a(t, n), vectorised), `amplitude_law`
(its tangent for the LP), `simulate_contact` (event-driven).
"""
import math
import time
from typing import Literal

import casadi as ca
import numpy as np
from scipy.integrate import quad, solve_ivp
from scipy.optimize import brentq, minimize_scalar

from mechopt.models.errors import MechoptError, ModelError
from mechopt.models.stop_impact import Impact, LeverStop
from mechopt.solvers.result import (Result, Status, Timing, from_casadi_integrator, from_ivp,
                                    from_quadpack)

__all__ = ["natural_frequencies", "impact_forces", "rebound", "linearise_amplitude", "operating_point"]

AGREEMENT_REL = 1e-8            # the three methods must agree this well on every scene
GRID_POINTS = 257               # coarse search for the first rebound before Newton polishes it
SMALL_PULSE = 1e-3              # omega * tau below this: the pulse is expanded about its centre


# ================================================================ closed form

def _damped_cos_sinc(n, kappa, s):
    """(e^{-n s} cos(k1 s), e^{-n s} sin(k1 s)/k1) with k1^2 = kappa of any sign, s >= 0, never
    dividing by k1: both are entire in kappa s^2 (series near zero); overdamped, cosh and sinh
    are written as exponentials with e^{-n s} folded in, so a heavy damping cannot overflow."""
    x = kappa * s * s
    r = np.sqrt(np.abs(x))
    safe = np.where(r > 1e-4, r, 1.0)
    e = np.exp(-n * s)
    c, sn = e * (1 - x / 2 + x * x / 24), e * (1 - x / 6 + x * x / 120)   # error below 1e-19 at |x| <= 1e-8
    small = r <= 1e-4
    if np.any(x > 0):
        big = (x > 0) & ~small
        c, sn = np.where(big, e * np.cos(safe), c), np.where(big, e * np.sin(safe) / safe, sn)
    if np.any(x < 0):
        big, grow = (x < 0) & ~small, np.where(x < 0, safe, 0.0)
        up, down = np.exp(grow - n * s), np.exp(-grow - n * s)
        c, sn = np.where(big, 0.5 * (up + down), c), np.where(big, 0.5 * (up - down) / safe, sn)
    return c, s * sn


def _kernel(imp: Impact, s, order=3):
    """h(s) = e^{-n s} sin(k1 s)/k1 and its derivatives up to `order`, zero for s < 0, plus the
    unit-step response U (integral of h) and unit-ramp response R (integral of U)."""
    s = np.asarray(s, dtype=float)
    n, w2 = imp.damping_rad_s, imp.omega_rad_s**2
    pos = np.maximum(s, 0.0)
    ec, es = _damped_cos_sinc(n, w2 - n * n, pos)
    on = s >= 0                                       # at s = 0 the right-hand limits: h' = 1
    h = [np.where(on, es, 0.0), np.where(on, ec - n * es, 0.0)]
    for _ in range(order - 1):
        h.append(-2 * n * h[-1] - w2 * h[-2])        # h'' = -2 n h' - omega^2 h
    U = np.where(on, (1 - (ec + n * es)) / w2, 0.0)
    R = np.where(on, pos / w2 - 2 * n / w2**2 + (2 * n / w2**2 * (ec + n * es) - es / w2), 0.0)
    return h, U, R


def closed_form_response(imp: Impact, t):
    """q(t), q'(t), q''(t) of eq. (2) in closed form [m, m/s, m/s^2] (t in s, array).

    q = v0 h(t) + F/(m tau) [R(t) - 2 R(t - tau) + R(t - 2 tau)] - P/m U(t): the triangle is a
    ramp, minus two ramps at tau, plus one at 2 tau. Once the pulse is over and omega tau is
    small, that second difference loses digits; there the pulse part is written instead as
    S/m [h + mu2/2 h'' + mu4/24 h''''](t - tau), mu2 = tau^2/6 and mu4 = tau^4/15 the moments of
    the triangle about its centre, S = F tau its impulse (the next term is below 1e-19 relative).
    """
    moving, pressed = _response_parts(imp, t)
    return tuple(x + y for x, y in zip(moving, pressed))


def _response_parts(imp: Impact, t):
    """(q, q', q'') split into the part driven by the approach (v0 and the pulse, both scale
    as n / t) and the part the preload drives."""
    t = np.asarray(t, dtype=float)
    m, F, tau, P, v0 = imp.mass_kg, imp.force_N, imp.tau_s, imp.preload_N, imp.v0_m_s
    expanding = imp.omega_rad_s * tau < SMALL_PULSE
    h0, U0, R0 = _kernel(imp, t)
    pressed = (-P / m * U0, -P / m * h0[0], -P / m * h0[1])
    moving = (v0 * h0[0], v0 * h0[1], v0 * h0[2])
    if F == 0.0:
        return moving, pressed
    h1, U1, R1 = _kernel(imp, t - tau, order=6 if expanding else 2)
    h2, U2, R2 = _kernel(imp, t - 2 * tau, order=2)
    k = F / (m * tau)
    pulse = (k * (R0 - 2 * R1 + R2), k * (U0 - 2 * U1 + U2), k * (h0[0] - 2 * h1[0] + h2[0]))
    if expanding:
        S, after = F * tau / m, t >= 2 * tau
        centred = [S * (h1[j] + tau**2 / 12 * h1[j + 2] + tau**4 / 360 * h1[j + 4]) for j in range(3)]
        pulse = tuple(np.where(after, c, r) for c, r in zip(centred, pulse))
    return tuple(x + y for x, y in zip(moving, pulse)), pressed


def _polish_peak(imp, t_grid, q_grid, derivatives):
    """Largest q on a grid, polished by safeguarded Newton on q' = 0 inside the grid cells either
    side (`derivatives(t) -> (q, q', q'')`): a Newton step that leaves the bracket is replaced by
    bisection, so a peak far narrower than a cell (heavy damping) is still found."""
    i = np.argmax(q_grid, axis=-1)
    t = t_grid[i]
    best = np.take_along_axis(q_grid, i[..., None], -1)[..., 0] if q_grid.ndim > 1 else q_grid[i]
    dt = t_grid[1] - t_grid[0]
    lo, hi = np.maximum(t - dt, t_grid[0]), np.minimum(t + dt, t_grid[-1])
    for _ in range(100):
        _, qd, qdd = derivatives(t)
        lo, hi = np.where(qd > 0, t, lo), np.where(qd > 0, hi, t)
        newton = t - qd / np.where(qdd < 0, qdd, -1.0)
        inside = (qdd < 0) & (newton > lo) & (newton < hi)
        t_next = np.where(inside, newton, 0.5 * (lo + hi))
        done = np.abs(t_next - t) <= 1e-15 * t_grid[-1]
        t = t_next
        if np.all(done):
            break
    return np.maximum(derivatives(t)[0], best), t


def closed_form_amplitude_m(imp: Impact):
    """First-rebound amplitude [m] (0 when C never leaves the plate) and when it occurs [s]."""
    t = np.linspace(0.0, imp.window_s, GRID_POINTS)
    q = closed_form_response(imp, t)[0]
    peak, when = _polish_peak(imp, t, q, lambda s: closed_form_response(imp, s))
    return max(float(peak), 0.0), float(when)


# ================================================================ quadrature

def _h_direct(imp, s):
    """h(s) written the textbook way, branch by damping (independent of `_damped_cos_sinc`)."""
    n, w = imp.damping_rad_s, imp.omega_rad_s
    if s <= 0:
        return 0.0
    if n < w:
        k1 = math.sqrt(w * w - n * n)
        return math.exp(-n * s) * s * np.sinc(k1 * s / math.pi)
    r = math.sqrt(n * n - w * w)
    if r * s < 1e-8:
        return math.exp(-n * s) * s
    return (math.exp((r - n) * s) - math.exp(-(r + n) * s)) / (2 * r)     # sinh, without overflow


def quadrature_response(imp: Impact, t, *, epsrel=1e-13):
    """q(t) [m] by QUADPACK on the Duhamel integrals of eq. (2), split at the kinks of Q_F;
    returns (q, QUADPACK's messages: empty when every integral converged)."""
    m, F, tau, P = imp.mass_kg, imp.force_N, imp.tau_s, imp.preload_N
    total, messages = imp.v0_m_s * _h_direct(imp, t), []
    # an integral near zero (the kernel oscillates) cannot meet a relative tolerance: each gets an
    # absolute one worth 1e-13 of the response scale, its contribution to q being weighted by 1/m
    floor = epsrel * _response_scale_m(imp) * m

    def integrate(f, a, b, epsabs):
        if b <= a:
            return 0.0
        y, _, _, *message = quad(f, a, b, epsabs=epsabs, epsrel=epsrel, limit=200, full_output=1)
        messages.extend(message[:1])        # full_output: a message instead of a warning
        return y

    if F:
        total += integrate(lambda u: F * u / tau * _h_direct(imp, t - u), 0.0, min(t, tau), floor) / m
        total += integrate(lambda u: F * (2 * tau - u) / tau * _h_direct(imp, t - u), tau, min(t, 2 * tau), floor) / m
    if P:
        total -= P / m * integrate(lambda u: _h_direct(imp, u), 0.0, t, floor / P)
    return total, messages


def _response_scale_m(imp):
    """A length the response is measured against [m]: what v0, the impulse and the preload each
    alone would move C, summed (1 m when all are zero)."""
    w, m = imp.omega_rad_s, imp.mass_kg
    return (abs(imp.v0_m_s) + imp.force_N * imp.tau_s / m + imp.preload_N / (m * w)) / w or 1.0


def quadrature_amplitude_m(imp: Impact, *, epsrel=1e-13):
    """First-rebound amplitude [m] from quadrature (QUADPACK to `epsrel`): grid, then a bounded
    scalar search around the grid's best; and the status of the worst QUADPACK message met."""
    messages = []

    def q(t):
        y, said = quadrature_response(imp, float(t), epsrel=epsrel)
        messages.extend(said)
        return y

    grid = np.linspace(0.0, imp.window_s, 129)
    values = np.array([q(t) for t in grid])
    i = int(np.argmax(values))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    found = minimize_scalar(lambda t: -q(t), bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-14 * imp.window_s, "maxiter": 200})
    worst = max((from_quadpack(msg) for msg in messages), key=_SEVERITY.index, default=Status.SOLVED)
    return max(-found.fun, values[i], 0.0), worst


_SEVERITY = [Status.SOLVED, Status.INACCURATE, Status.LIMIT, Status.FAILED]


# ================================================================ ODE (CasADi)

_ODE_BUILDS: dict = {}


def _ode_integrators(points, reltol=1e-13):
    """CVODES on eq. (2) in scaled form over one phase of Q_F, built once per process: time
    theta = omega t, state (q, q' / omega) in units of the response scale L, forcing linear in
    time within a phase. Parameters: [2 zeta, force at phase start, force slope, duration]."""
    if (points, reltol) in _ODE_BUILDS:
        return _ODE_BUILDS[points, reltol], 0.0
    start = time.perf_counter()
    y, p, s = ca.SX.sym("y", 2), ca.SX.sym("p", 4), ca.SX.sym("s")
    two_zeta, f0, f1, duration = p[0], p[1], p[2], p[3]
    # normalised time s in [0, 1] over a phase of length `duration` (in theta)
    rhs = duration * ca.vertcat(y[1], f0 + f1 * s * duration - two_zeta * y[1] - y[0])
    dae = {"x": y, "p": p, "t": s, "ode": rhs}
    opts = {"abstol": reltol / 100, "reltol": reltol, "max_num_steps": 200000}
    built = (ca.integrator("rebound_grid", "cvodes", dae, 0.0, list(np.linspace(0, 1, points)[1:]), opts),
             ca.integrator("rebound_end", "cvodes", dae, 0.0, 1.0, opts))
    _ODE_BUILDS[points, reltol] = built
    return built, time.perf_counter() - start


def ode_amplitude_m(imp: Impact, *, points=65, reltol=1e-13):
    """First-rebound amplitude [m] by integrating eq. (2) with CVODES, phase by phase (kinks of
    Q_F at tau and 2 tau are phase ends, never stepped over); the peak is located by Newton on
    q' = 0 with re-integration from the last grid point; CVODES to `reltol` (absolute: 1 %
    of it, the state being scaled to order one). Returns (amplitude, status, build s)."""
    (grid_int, end_int), build_s = _ode_integrators(points, reltol)
    w, m = imp.omega_rad_s, imp.mass_kg
    L = _response_scale_m(imp)
    scale = 1.0 / (m * w * w * L)              # force [N] -> scaled acceleration
    two_zeta = 2 * imp.damping_rad_s / w
    theta_tau = w * imp.tau_s
    F, P = imp.force_N, imp.preload_N
    phases = [(0.0, theta_tau, -P, F / theta_tau), (theta_tau, theta_tau, F - P, -F / theta_tau),
              (2 * theta_tau, 2 * math.pi, -P, 0.0)] if F else [(0.0, w * imp.window_s, -P, 0.0)]
    state = np.array([0.0, imp.v0_m_s / (w * L)])
    best = 0.0
    try:
        for _, length, f_start, slope in phases:
            p = [two_zeta, f_start * scale, slope * scale, length]
            traj = np.asarray(grid_int(x0=state, p=p)["xf"])        # 2 x (points-1)
            nodes = np.hstack([state[:, None], traj])
            for j in np.flatnonzero((nodes[1, :-1] > 0) & (nodes[1, 1:] <= 0)):   # q' falls through zero
                best = max(best, _ode_peak(end_int, nodes[:, j], j / (points - 1), 1 / (points - 1), length,
                                           two_zeta, f_start * scale, slope * scale))
            best = max(best, float(nodes[0].max()))
            state = traj[:, -1]
    except RuntimeError as exc:       # CVODES gave up: a status, not an exception, for the caller
        if isinstance(exc, MechoptError):
            raise
        return float("nan"), from_casadi_integrator(str(exc)), build_s
    return best * L, from_casadi_integrator(None), build_s


def _ode_peak(end_int, y_start, s_start, ds, length, two_zeta, f0, f1):
    """Scaled q at q' = 0 inside one grid interval [s_start, s_start + ds] of a phase: Newton,
    each iterate integrated afresh from the interval's start."""
    s = ds / 2
    for _ in range(30):
        y = np.asarray(end_int(x0=y_start, p=[two_zeta, f0 + f1 * s_start * length, f1, s * length])["xf"]).ravel()
        acc = f0 + f1 * (s_start + s) * length - two_zeta * y[1] - y[0]       # d(q'/omega)/dtheta
        if acc >= 0:
            break
        step = -y[1] / (acc * length)
        s = min(max(s + step, 0.0), ds)
        if abs(step) < 1e-15:
            break
    return float(y[0])


# ================================================================ the exact law a(t, n)

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
    g, p = (part[0] for part in _response_parts(unit, grid))
    lines, breaks = _upper_envelope(g, p)
    j = lines[np.searchsorted(breaks, r)]
    s = grid[j]
    best = r * g[j] + p[j]
    lo, hi = np.maximum(s - grid[1], 0.0), np.minimum(s + grid[1], grid[-1])
    moving, pressed = _response_parts(unit, s)
    qd, qdd = r * moving[1] + pressed[1], r * moving[2] + pressed[2]
    newton = s - qd / np.where(qdd < 0, qdd, -1.0)
    s = np.where((qdd < 0) & (newton > lo) & (newton < hi), newton, s)
    moving, pressed = _response_parts(unit, s)
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
    moving, _ = _response_parts(imp, when)
    slope = -float(moving[0]) / task.t_deg * 1e3
    return slope, a_m * 1e3 - slope * task.t_deg


# ================================================================ event-driven check

def simulate_contact(task: LeverStop, speed_rpm, *, rtol: float = 1e-11):
    """The lever's contact with the plate and its separation as a piecewise-linear event-driven
    simulation: C arrives at the plate (x = 0) with the approach velocity; on the plate the
    stiffness is c_stop (Fig. 6), off it c_free (Fig. 5) about the cam's position -preload; the
    plate only pushes. Located events: separation (x rises through 0), first rebound peak
    (x' = 0 off the plate). Damping zeta of each configuration's own frequency.

    Returns (rebound_mm, contact_s, status, message): 0 mm when C never leaves the plate.
    """
    m, cf, cs = task.mass_kg, task.c_free_N_per_m, task.c_stop_N_per_m
    zeta = task.damping_ratio if "damping" in task.effects else 0.0
    delta = task.preload_mm * 1e-3 if "preload" in task.effects else 0.0
    v0 = float(task.approach_velocity_m_s(speed_rpm))

    def on_plate(t, y):
        return [y[1], (-cf * (y[0] + delta) - (cs - cf) * y[0] - 2 * zeta * math.sqrt(cs * m) * y[1]) / m]

    def off_plate(t, y):
        return [y[1], (-cf * (y[0] + delta) - 2 * zeta * math.sqrt(cf * m) * y[1]) / m]

    def separation(t, y):
        return y[0]
    separation.terminal, separation.direction = True, 1

    def peak(t, y):
        return y[1]
    peak.terminal, peak.direction = True, -1

    horizon = 4 * math.pi / task.omega_stop_rad_s
    # start a hair inside the plate so the separation event is not the start point
    contact = solve_ivp(on_plate, (0.0, horizon), [-1e-15 * v0, -v0], method="DOP853", rtol=rtol,
                        atol=1e-14 * v0 / task.omega_stop_rad_s, events=separation)
    status = from_ivp(contact.status)
    if status is not Status.SOLVED:
        return 0.0, 0.0, status, f"contact phase: {contact.message}"
    if not contact.t_events[0].size:
        return 0.0, horizon, Status.SOLVED, "C stays on the plate (the preload holds it)"
    t_sep, y_sep = contact.t_events[0][0], contact.y_events[0][0]
    free = solve_ivp(off_plate, (t_sep, t_sep + 2 * math.pi / task.omega_free_rad_s), [0.0, y_sep[1]],
                     method="DOP853", rtol=rtol, atol=1e-14 * v0 / task.omega_free_rad_s, events=peak)
    status = from_ivp(free.status)
    if status is not Status.SOLVED or not free.t_events[0].size:
        return 0.0, t_sep, Status.FAILED if status is Status.SOLVED else status, f"free phase: {free.message}"
    return float(free.y_events[0][0][0]) * 1e3, float(t_sep), Status.SOLVED, "separated and peaked"


# ================================================================ solvers (scene entry points)

def natural_frequencies(task: LeverStop) -> Result:
    """Reduced stiffness and natural frequencies of the lever moving (Fig. 5) and on the plate
    (Fig. 6), and the contact time tau = half the period on the plate."""
    start = time.perf_counter()
    values = {"f_free_Hz": task.f_free_Hz, "f_stop_Hz": task.f_stop_Hz,
              "c_free_N_per_mm": task.c_free_N_per_m * 1e-3, "c_stop_N_per_mm": task.c_stop_N_per_m * 1e-3,
              "contact_time_s": task.contact_time_s}
    return Result(Status.SOLVED, values, Timing(0.0, time.perf_counter() - start),
                  message="c = 3 E J_x / ((a + b) b^2), f = sqrt(c / m) / (2 pi)")


def impact_forces(task: LeverStop) -> Result:
    """Impact force F_ud = J_A omega_0 (1 + k) / (l tau) at each speed of `speeds_rpm`, with the
    impulse S_C = F tau and the approach velocity; `impact_force_N_<rpm>` etc."""
    task.need_effect("impact_pulse")
    _need_speeds(task)
    start = time.perf_counter()
    values = {"contact_time_s": task.contact_time_s}
    for n in task.speeds_rpm:
        v0 = float(task.approach_velocity_m_s(n))
        F = float(task.impact_force_N(v0))
        values |= {f"impact_force_N_{_tag(n)}": F, f"impulse_Ns_{_tag(n)}": F * task.contact_time_s,
                   f"approach_velocity_m_s_{_tag(n)}": v0}
    return Result(Status.SOLVED, values, Timing(0.0, time.perf_counter() - start),
                  message="tau = half the natural period on the plate")


def rebound(task: LeverStop, *, method: Literal["closed_form", "quadrature", "ode"] = "closed_form",
            cross_check: bool = True) -> Result:
    """First-rebound amplitude of eq. (2) at each speed of `speeds_rpm` and the phase angle
    `t_deg`: `rebound_mm_<rpm>`. With `cross_check` the other two methods run as well and must
    agree within 1e-8 relative (else INACCURATE), and the event-driven simulation reports how far
    the single-mass eq. (2) is from a contact that switches stiffness (`rebound_event_mm_<rpm>`).
    """
    _need_speeds(task)
    task.need("t_deg")
    methods = {"closed_form": _by_closed_form, "quadrature": _by_quadrature, "ode": _by_ode}
    start = time.perf_counter()
    build_s, values, diagnostics, status, notes = 0.0, {}, {}, Status.SOLVED, []
    for n in task.speeds_rpm:
        imp = task.impact(n)
        runs = {name: methods[name](imp) for name in ([method] + [k for k in methods if k != method]
                                                      if cross_check else [method])}
        build_s += sum(r[2] for r in runs.values())
        amp, own_status = runs[method][0], runs[method][1]
        if own_status is not Status.SOLVED or not math.isfinite(amp):
            return Result(Status.FAILED if own_status is Status.SOLVED else own_status, values,
                          Timing(build_s, time.perf_counter() - start - build_s),
                          message=f"{method}: {own_status.value} at {n:g} rpm, no amplitude reported",
                          diagnostics=diagnostics)
        values[f"rebound_mm_{_tag(n)}"] = amp * 1e3
        if cross_check:
            bad = [k for k, r in runs.items() if r[1] is not Status.SOLVED or not math.isfinite(r[0])]
            spread = max(abs(r[0] - amp) for k, r in runs.items() if k not in bad) / max(amp, 1e-300)
            diagnostics[f"methods_{_tag(n)}"] = {k: {"mm": r[0] * 1e3, "status": r[1].value} for k, r in runs.items()}
            values[f"methods_max_rel_diff_{_tag(n)}"] = spread
            if spread > AGREEMENT_REL or bad:
                status = Status.INACCURATE
                notes.append(f"{n:g} rpm: methods differ by {spread:.2e} relative"
                             + (f", {bad} not solved" if bad else ""))
            event_mm, contact_s, ev_status, ev_message = simulate_contact(task, n)
            if ev_status is Status.SOLVED:
                values[f"rebound_event_mm_{_tag(n)}"] = event_mm
                values[f"contact_time_event_s_{_tag(n)}"] = contact_s
            diagnostics[f"event_driven_{_tag(n)}"] = ev_message
    values["contact_time_s"] = task.contact_time_s
    agreed = "closed form, quadrature and ODE agree within 1e-8" if cross_check else "no cross-check"
    message = f"{method}; " + ("; ".join(notes) if notes else agreed)
    return Result(status, values, Timing(build_s, time.perf_counter() - start - build_s), message=message,
                  diagnostics=diagnostics)


def linearise_amplitude(task: LeverStop) -> Result:
    """The amplitude law for the LP: tangent of a(t) at `t_deg`, `speed_nominal_rpm`; the bound on
    t(3,7) that a <= `amplitude_limit_mm` gives, by the tangent and by the exact law (a falls
    with t: the exact bound is the root of a(t) = limit)."""
    task.need("amplitude_limit_mm")
    start = time.perf_counter()
    slope, intercept = amplitude_law(task)
    limit = task.amplitude_limit_mm
    n = task.speed_nominal_rpm
    exact = lambda t: float(rebound_amplitude_mm(task, n, t)) - limit      # noqa: E731
    lo, hi = 1e-3 * task.t_deg, 359.0
    if exact(lo) < 0 or exact(hi) > 0:
        raise ModelError(f"amplitude_limit_mm={limit}: a(t) at {n:g} rpm does not cross it for t in "
                         f"({lo:g}, {hi:g}) deg", key="amplitude_limit_mm")
    t_exact = brentq(exact, lo, hi, xtol=1e-12, rtol=1e-14)
    t_linear = (limit - intercept) / slope
    values = {"slope_mm_per_deg": slope, "intercept_mm": intercept, "t_3_7_min_deg": t_linear,
              "t_3_7_min_exact_deg": t_exact, "span_gain_deg": t_exact - t_linear,
              "amplitude_nominal_mm": float(rebound_amplitude_mm(task, n, task.t_deg))}
    return Result(Status.SOLVED, values, Timing(0.0, time.perf_counter() - start),
                  message=f"tangent at t = {task.t_deg:g} deg, n = {n:g} rpm; a(t) is convex, so the tangent's "
                          f"bound is looser than the exact one by span_gain_deg")


def operating_point(task: LeverStop) -> Result:
    """The first rebound at one operating point, main-shaft speed `speed_nominal_rpm` and phase
    angle `t_deg`, against `amplitude_limit_mm`: swept over both, the map of where the lift meets
    the weft-transfer limit. The exact law `rebound_amplitude_mm` is checked at the point by
    CasADi/CVODES on eq. (2) itself (within 1e-8 relative, else INACCURATE). SOLVED when the
    rebound keeps the limit, INFEASIBLE (violated amplitude) when it does not; `margin_mm` is
    the limit left over (negative when exceeded)."""
    task.need("speed_nominal_rpm", "t_deg", "amplitude_limit_mm")
    start = time.perf_counter()
    n, t, limit = task.speed_nominal_rpm, task.t_deg, task.amplitude_limit_mm
    amplitude_mm = float(rebound_amplitude_mm(task, n, t))
    ode_m, ode_status, build_s = ode_amplitude_m(task.impact(n))
    values = {"rebound_mm": amplitude_mm, "margin_mm": limit - amplitude_mm,
              "approach_velocity_m_s": float(task.approach_velocity_m_s(n)), "contact_time_s": task.contact_time_s}
    if "impact_pulse" in task.effects:
        values["impact_force_N"] = float(task.impact_force_N(values["approach_velocity_m_s"]))
    timing = Timing(build_s, time.perf_counter() - start - build_s)
    if ode_status is not Status.SOLVED:
        return Result(Status.INACCURATE, values, timing,
                      message=f"the ODE cross-check gave {ode_status.value}: the law's "
                              f"{amplitude_mm:.4g} mm is unconfirmed")
    spread = abs(ode_m * 1e3 - amplitude_mm) / max(amplitude_mm, 1e-300)
    values["methods_rel_diff"] = spread
    if spread > AGREEMENT_REL:
        return Result(Status.INACCURATE, values, timing,
                      message=f"exact law and ODE differ by {spread:.2e} relative at {n:g} rpm, {t:g} deg")
    within = amplitude_mm <= limit
    return Result(Status.SOLVED if within else Status.INFEASIBLE, values, timing,
                  violated=() if within else ("amplitude",),
                  message=f"{amplitude_mm:.4g} mm at {n:g} rpm, t = {t:g} deg: "
                          f"{'within' if within else 'above'} amplitude_limit_mm={limit:g}; "
                          f"the ODE agrees to {spread:.1e}")


def _by_closed_form(imp):
    return closed_form_amplitude_m(imp)[0], Status.SOLVED, 0.0


def _by_quadrature(imp):
    return *quadrature_amplitude_m(imp), 0.0


def _by_ode(imp):
    return ode_amplitude_m(imp)


def _need_speeds(task):
    if not task.speeds_rpm:
        raise ModelError("speeds_rpm=[]: give the main-shaft speeds to report (structure table)", key="speeds_rpm")


def _tag(speed_rpm):
    """Speed as a value-name suffix: 280.0 -> '280', 177.5 -> '177p5'."""
    return f"{speed_rpm:g}".replace(".", "p")
