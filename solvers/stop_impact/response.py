"""The lever's first rebound off its stop (paper 004, eq. (2)), three independent ways.

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
"""
import math

import casadi as ca
import numpy as np
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import MechoptError
from mechopt.kit.result import Status, from_casadi_integrator, from_quadpack
from mechopt.models.stop_impact import Impact

GRID_POINTS = 257               # coarse search for the first rebound before Newton polishes it
SMALL_PULSE = 1e-3              # omega * tau below this: the pulse is expanded about its centre


# --- closed form

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
    moving, pressed = response_parts(imp, t)
    return tuple(x + y for x, y in zip(moving, pressed))


def response_parts(imp: Impact, t):
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


# --- quadrature

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
    floor = epsrel * response_scale_m(imp) * m

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


def response_scale_m(imp):
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


# --- ODE (CasADi)

_ODE_BUILDS = BuildCache("stop_impact.ode_integrators", maxsize=8, per_thread=True)    # CVODES: see BuildCache


def _ode_integrators(points, reltol=1e-13):
    """CVODES on eq. (2) in scaled form over one phase of Q_F, built once per process, and the
    seconds this call spent building (0 when kept): time theta = omega t, state (q, q' / omega)
    in units of the response scale L, forcing linear in time within a phase. Parameters:
    [2 zeta, force at phase start, force slope, duration]."""
    return _ODE_BUILDS.get((points, reltol), lambda: _build_ode_integrators(points, reltol))


def _build_ode_integrators(points, reltol):
    y, p, s = ca.SX.sym("y", 2), ca.SX.sym("p", 4), ca.SX.sym("s")
    two_zeta, f0, f1, duration = p[0], p[1], p[2], p[3]
    # normalised time s in [0, 1] over a phase of length `duration` (in theta)
    rhs = duration * ca.vertcat(y[1], f0 + f1 * s * duration - two_zeta * y[1] - y[0])
    dae = {"x": y, "p": p, "t": s, "ode": rhs}
    opts = {"abstol": reltol / 100, "reltol": reltol, "max_num_steps": 200000}
    return (ca.integrator("rebound_grid", "cvodes", dae, 0.0, list(np.linspace(0, 1, points)[1:]), opts),
            ca.integrator("rebound_end", "cvodes", dae, 0.0, 1.0, opts))


def ode_amplitude_m(imp: Impact, *, points=65, reltol=1e-13):
    """First-rebound amplitude [m] by integrating eq. (2) with CVODES, phase by phase (kinks of
    Q_F at tau and 2 tau are phase ends, never stepped over); the peak is located by Newton on
    q' = 0 with re-integration from the last grid point; CVODES to `reltol` (absolute: 1 %
    of it, the state being scaled to order one). Returns (amplitude, status, build s)."""
    (grid_int, end_int), build_s = _ode_integrators(points, reltol)
    w, m = imp.omega_rad_s, imp.mass_kg
    L = response_scale_m(imp)
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
