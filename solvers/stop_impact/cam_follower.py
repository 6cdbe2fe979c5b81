"""The lift cam's rise with an elastic link (models/cam_follower.py): where and how fast the
lever's end C meets its plate, the dynamic errors of the motion law, and whether the roller
stays on its cam.

* `follow_cam`            CasADi/CVODES, phase by phase (rise, then dwell: the law's kinks at the
                          ends are phase ends, never stepped over); the contact with the plate is
                          located by Newton on X(xi) = 1 - preload / H, each iterate integrated
                          afresh from the grid node before it; a contact force N < 0 is located
                          by bisection the same way. Closure "force": N < 0 is lift-off
                          (INFEASIBLE); "groove": a crossover to the other wall, each one
                          located with its flight and impact (solvers/stop_impact/crossover.py),
                          the rise followed on (the walls taken without backlash).
* `follow_cam_reference`  scipy's DOP853 with its own event location: an independent check.
"""
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import MechoptError
from mechopt.kit.result import Status, from_casadi_integrator, from_ivp
from mechopt.models.cam_follower import law_function, law_values, relative_acceleration, rise_duration_s
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.crossover import Crossover, Groove, crossovers, law_path

DWELL_PERIODS = 4.0         # how long after the rise C may still reach its plate [natural periods]


def dwell_length(lam, t_deg):
    """How far past the rise (in xi) C is followed: DWELL_PERIODS natural periods, but never past
    the cycle's end (the cam comes round); and whether the cycle cut it short."""
    periods, cycle = DWELL_PERIODS * 2 * math.pi / lam, 360.0 / t_deg - 1.0
    return min(periods, cycle), cycle < periods

_BUILDS = BuildCache("stop_impact.cam_integrators", maxsize=16, per_thread=True)    # CVODES: see BuildCache


@dataclass(frozen=True)
class CamRise:
    """One rise at one speed and phase angle: samples (xi, the rise's fraction; X = x / H and its
    xi-derivatives up to the contact), the contact, the roller's force and the outcome."""
    speed_rpm: float
    t_deg: float
    xi: np.ndarray
    X: np.ndarray
    dX: np.ndarray
    ddX: np.ndarray
    contact_xi: float | None          # where C meets the plate (None: it does not within the window)
    approach_velocity_m_s: float      # x' at the contact (0 without one)
    dynamic_error_mm: float           # max |x - s| over the samples up to the contact
    min_contact_force_N: float        # least roller force N = F_closure + m x'' before the contact
    leaves_cam_xi: float | None       # first N = 0 (the roller would lift off), located (closure "force")
    status: Status
    message: str
    build_s: float
    crossovers: tuple[Crossover, ...] = ()   # closure "groove": the roller's crossings, in order


def follower_data(task: LeverStop, speed_rpm, t_deg):
    """(lambda = omega_free T, zeta, H [m], target X at the plate, T [s]) of one rise."""
    task.need("stroke_mm", "law")
    T = float(rise_duration_s(speed_rpm, t_deg))
    zeta = task.damping_ratio if "damping" in task.effects else 0.0
    H = task.stroke_mm * 1e-3
    delta = task.preload_mm * 1e-3 if "preload" in task.effects else 0.0
    return task.omega_free_rad_s * T, zeta, H, 1.0 - delta / H, T


def _integrators(law, points, reltol):
    return _BUILDS.get((law, points, reltol), lambda: _build(law, points, reltol))


def _build(law, points, reltol):
    """CVODES on (e, e') over one phase, normalised time s in [0, 1]; parameters [lambda, zeta,
    xi at the phase start, phase length in xi, 1 in the rise / 0 in the dwell]."""
    y, p, s = ca.SX.sym("y", 2), ca.SX.sym("p", 5), ca.SX.sym("s")
    lam, zeta, xi0, length, rising = (p[i] for i in range(5))
    xi = xi0 + s * length
    ddS = rising * law_function(law)(xi)[2]
    rhs = length * ca.vertcat(y[1], relative_acceleration(ddS, y[0], y[1], lam, zeta))
    dae = {"x": y, "p": p, "t": s, "ode": rhs}
    opts = {"abstol": reltol / 100, "reltol": reltol, "max_num_steps": 200000}
    return (ca.integrator("cam_grid", "cvodes", dae, 0.0, list(np.linspace(0, 1, points)[1:]), opts),
            ca.integrator("cam_end", "cvodes", dae, 0.0, 1.0, opts))


def follow_cam(task: LeverStop, speed_rpm, t_deg=None, *, reltol: float = 1e-10, points: int = 1001) -> CamRise:
    """One rise of the lift cam at `speed_rpm` over the phase angle `t_deg` (the task's by default).

    Returns a `CamRise`; its status is SOLVED, INFEASIBLE when the roller leaves the cam (the
    contact force N would have to pull: the model no longer holds past that point; the values
    up to it are kept), or the integrator's failure (LIMIT, FAILED).
    """
    t_deg = task.t_deg if t_deg is None else t_deg
    lam, zeta, H, target, T = follower_data(task, speed_rpm, t_deg)
    (grid_int, end_int), build_s = _integrators(task.law, points, reltol)
    dwell, cut = dwell_length(lam, t_deg)
    phases = [(0.0, 1.0, 1.0), (1.0, dwell, 0.0)]
    state = np.zeros(2)
    xs, es, des = [np.zeros(1)], [np.zeros(1)], [np.zeros(1)]
    contact = None
    try:
        for xi0, length, rising in phases:
            p = [lam, zeta, xi0, length, rising]
            traj = np.asarray(grid_int(x0=state, p=p)["xf"])
            nodes = np.hstack([state[:, None], traj])
            xi = xi0 + length * np.linspace(0, 1, points)
            X = law_values(task.law, xi)[0] + nodes[0] if rising else 1.0 + nodes[0]
            hit = np.flatnonzero((X[:-1] < target) & (X[1:] >= target))
            if hit.size:
                j = int(hit[0])
                contact, y_c = _locate(end_int, task.law, nodes[:, j], xi[j], xi[j + 1], lam, zeta, rising, target)
                keep = slice(1, j + 1)
                xs += [xi[keep], [contact]]
                es += [nodes[0, keep], [y_c[0]]]
                des += [nodes[1, keep], [y_c[1]]]
                break
            xs.append(xi[1:])
            es.append(nodes[0, 1:])
            des.append(nodes[1, 1:])
            state = traj[:, -1]
    except RuntimeError as exc:       # CVODES gave up: a status for the caller, not an exception
        if isinstance(exc, MechoptError):
            raise
        status = from_casadi_integrator(str(exc))
        empty = np.zeros(0)
        return CamRise(float(speed_rpm), float(t_deg), empty, empty, empty, empty, None, 0.0, 0.0, 0.0, None,
                       status, f"CVODES: {exc}", build_s)
    xi, e, de = (np.concatenate([np.asarray(a, float) for a in arrays]) for arrays in (xs, es, des))
    S, dS, ddS = law_values(task.law, xi)
    dde = relative_acceleration(np.where(xi <= 1.0, ddS, 0.0), e, de, lam, zeta)
    X, dX, ddX = S + e, dS + de, ddS + dde
    if xi[-1] > 1.0:            # past the rise: the law's end values (its own ddS(1) may jump to 0)
        ddX = np.where(xi > 1.0, dde, ddX)
    force = _contact_force_N(task, H, T, ddX)
    leaves = None
    status, message = Status.SOLVED, "C meets its plate" if contact is not None else \
        f"C does not reach its plate within the rise and {DWELL_PERIODS:g} periods of dwell"
    if contact is None and cut:         # a lever slower than its cycle: the next rise comes first
        status = Status.LIMIT
        message = (f"the lever (f_free = {task.f_free_Hz:.4g} Hz) is slower than its cycle at {speed_rpm:g} rpm "
                   f"({60 / speed_rpm * 1e3:.4g} ms a turn): C does not reach its plate before the cam comes round, "
                   "outside the one-rise model; stiffen the lever (E_GPa, J_x_mm4) or lighten it (mass_kg)")
    below = np.flatnonzero(force < 0)
    crossed = ()
    if below.size and task.closure == "groove":     # a crossover to the other wall, not lift-off
        def located(j):          # (xi, X, X') where N changes sign between samples j - 1 and j
            at = _locate_sign_change(end_int, task, xi, e, de, j, lam, zeta, H, T, before=bool(force[j - 1] >= 0))
            y = _at(end_int, task.law, [e[j - 1], de[j - 1]], float(xi[j - 1]), at, lam, zeta, 1.0 if at <= 1 else 0.0)
            S, dS = (float(v[0]) for v in law_values(task.law, at)[:2])
            return at, S + y[0], dS + y[1]
        crossed, capped = crossovers(xi, force, located, groove_of(task, lam, zeta, H, T))
        message += "; " + crossover_text(crossed, t_deg, task.backlash_mm)
        if capped:
            status = Status.LIMIT
            message += f" (stopped at {len(crossed)} crossovers: a count limit, the rest not followed)"
    elif below.size:
        j = int(below[0])
        leaves = _locate_sign_change(end_int, task, xi, e, de, j, lam, zeta, H, T)
        status = Status.INFEASIBLE
        message = (f"the roller leaves the cam at xi = {leaves:.4f} (cam angle {leaves * t_deg:.3f} deg of the rise): "
                   f"contact force {force.min():.4g} N < 0 at {speed_rpm:g} rpm; closure_force_N="
                   f"{task.closure_force_N:g} does not hold it")
    v0 = float(dX[-1]) * H / T if contact is not None else 0.0
    return CamRise(float(speed_rpm), float(t_deg), xi, X, dX, ddX, contact, v0,
                   _largest(xi, e, de, dde) * H * 1e3, float(force.min()), leaves, status, message, build_s,
                   tuple(crossed))


def groove_of(task, lam, zeta, H, T) -> Groove:
    """The rise's data for its flights (solvers/stop_impact/crossover.py): the walls' pitch path is
    the law's S over the rise, the dwell's 1 past it."""
    law = law_path(task.law)

    def path(xi):
        S, dS, _ = law(xi)
        return np.where(xi > 1.0, 1.0, S), np.where(xi > 1.0, 0.0, dS)
    return Groove(lam, zeta, task.closure_force_N * T**2 / (task.mass_kg * H), task.backlash_mm * 1e-3 / H, T, H, path)


def crossover_text(crossed, t_deg, backlash_mm) -> str:
    """The crossovers in words: how many, the first's cam angle and the largest impact speed."""
    if not crossed:
        return "groove: no crossover"
    speeds = [c.impact_m_s for c in crossed if c.impact_m_s is not None]
    first = crossed[0]
    text = (f"groove: {len(crossed)} crossover(s) across backlash_mm={backlash_mm:g}, the first off the "
            f"{first.leaves} wall at cam angle {first.angle_deg(t_deg):.3f} deg of the rise")
    if speeds:
        text += f", impacts up to {max(speeds):.4g} m/s"
    if any(c.impact_m_s is None for c in crossed):
        text += "; one still in flight when the followed window ends"
    return text


def _largest(xi, e, de, dde):
    """max |e| over the samples, polished by one Taylor step to e' = 0 inside the sample's cells
    (the error of the step is (lambda dxi)^3 / 6 relative, below 1e-6 at 1001 samples)."""
    i = int(np.argmax(np.abs(e)))
    best = abs(float(e[i]))
    if 0 < i < xi.size - 1 and dde[i] != 0:
        step = float(np.clip(-de[i] / dde[i], xi[i - 1] - xi[i], xi[i + 1] - xi[i]))
        best = max(best, abs(float(e[i] + de[i] * step + 0.5 * dde[i] * step * step)))
    return best


def _contact_force_N(task, H, T, ddX):
    """N = F_closure + m x'': what the cam must push on the roller (closure 0 without the effect)."""
    closure = task.closure_force_N if "cam_drive" in task.effects else 0.0
    return closure + task.mass_kg * H * np.asarray(ddX) / T**2


def _at(end_int, law, y0, xi0, xi, lam, zeta, rising):
    """(e, e') at `xi`, integrated afresh from (xi0, y0)."""
    if xi <= xi0:
        return np.asarray(y0, float)
    return np.asarray(end_int(x0=y0, p=[lam, zeta, xi0, xi - xi0, rising])["xf"]).ravel()


def _locate(end_int, law, y0, lo, hi, lam, zeta, rising, target):
    """The xi in [lo, hi] where X = S + e reaches `target` rising: safeguarded Newton on X - target."""
    S = (lambda x: law_values(law, x)[:2]) if rising else (lambda x: (np.ones(1), np.zeros(1)))
    a, b, xi = lo, hi, 0.5 * (lo + hi)
    y = _at(end_int, law, y0, lo, xi, lam, zeta, rising)
    for _ in range(60):
        s, ds = (float(v[0]) for v in S(xi))
        gap, slope = s + y[0] - target, ds + y[1]
        a, b = (xi, b) if gap < 0 else (a, xi)
        step = xi - gap / slope if slope > 0 else 0.5 * (a + b)
        nxt = step if a < step < b else 0.5 * (a + b)
        if abs(nxt - xi) <= 1e-15:
            break
        xi = nxt
        y = _at(end_int, law, y0, lo, xi, lam, zeta, rising)
    return xi, y


def _locate_sign_change(end_int, task, xi, e, de, j, lam, zeta, H, T, before=True):
    """The xi where the roller force changes sign between samples j-1 and j (`before`: it pushes,
    N >= 0, at j-1; so for the first lift-off): bisection, each midpoint integrated afresh from
    sample j-1."""
    if j == 0:
        return float(xi[0])
    lo, hi = float(xi[j - 1]), float(xi[j])
    y0 = np.array([e[j - 1], de[j - 1]])
    rising = 1.0 if hi <= 1.0 else 0.0

    def pushes(x):
        y = _at(end_int, task.law, y0, float(xi[j - 1]), x, lam, zeta, rising)
        ddS = law_values(task.law, x)[2][0] if rising else 0.0
        return _contact_force_N(task, H, T, ddS + relative_acceleration(ddS, y[0], y[1], lam, zeta)) >= 0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if pushes(mid) == before else (lo, mid)
    return 0.5 * (lo + hi)


def follow_cam_reference(task: LeverStop, speed_rpm, t_deg=None, *, rtol: float = 1e-12):
    """(contact xi, approach velocity [m/s], status) by scipy's DOP853 on X itself (not the
    relative error), with its own event location: the independent check of `follow_cam`."""
    t_deg = task.t_deg if t_deg is None else t_deg
    lam, zeta, H, target, T = follower_data(task, speed_rpm, t_deg)

    def rhs(rising):
        def f(xi, y):
            S, dS, _ = (v[0] for v in law_values(task.law, xi)) if rising else (1.0, 0.0, 0.0)
            return [y[1], -2 * zeta * lam * (y[1] - dS) - lam * lam * (y[0] - S)]
        return f

    def plate(xi, y):
        return y[0] - target
    plate.terminal, plate.direction = True, 1
    state = [0.0, 0.0]
    for span, rising in (((0.0, 1.0), True), ((1.0, 1.0 + dwell_length(lam, t_deg)[0]), False)):
        run = solve_ivp(rhs(rising), span, state, method="DOP853", rtol=rtol, atol=rtol * 1e-2, events=plate)
        status = from_ivp(run.status)
        if status is not Status.SOLVED:
            return None, 0.0, status
        if run.t_events[0].size:
            return float(run.t_events[0][0]), float(run.y_events[0][0][1]) * H / T, Status.SOLVED
        state = run.y[:, -1]
    return None, 0.0, Status.SOLVED
