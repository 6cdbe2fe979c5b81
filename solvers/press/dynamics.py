"""Motion of the crank press (paper 001, eqs. (1)-(2)): the paper's RK4, ours, and the peer.

* `rk4`:          fixed-step classical Runge-Kutta on the switched equations, the paper's method,
                  with its step refinement (halve until two runs agree); the baseline. It steps
                  across the jump at the end of the cut, so it is first order there.
* `events`:       CVODES (CasADi) integrating each smooth piece and restarting at located events:
                  U switching on, the jump, every full revolution, and friction sign changes
                  (crank stopping, sticking, breaking away). CasADi 3.8's own events fire on one
                  crossing direction only and never with a single output time, so events are
                  located here by Newton on the piece's duration instead (see `_locate`).
* `steady_state`: the periodic steady motion over one revolution, solved directly: in the crank
                  angle as independent variable the cut starts and ends at fixed angles, so one
                  revolution is three CVODES pieces composed symbolically, and CasADi's Newton
                  rootfinder finds the initial state that the revolution reproduces.
* `ivp`:          scipy's solve_ivp (Radau, LSODA, DOP853, RK45), with or without event location:
                  the peer a user would reach for, and the independent reference.

Every result reports the energy balance over the run (motor work = cutting + friction + belt
damping work + change of kinetic and potential energy; `energy_residual`, relative), the events
located, the speed fluctuation coefficient and the peaks of force, Q and belt torque.
"""
import functools
import time
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Literal

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from mechopt.models.press import FORCE_KEYS, WORK_NAMES, Dynamics, PressDrive, dynamics
from mechopt.models.errors import MechoptError, ModelError
from mechopt.solvers.result import Result, Status, Timing, from_casadi_integrator, from_ivp, from_rootfinder

__all__ = ["rk4", "events", "steady_state", "ivp"]

TWO_PI = 2 * np.pi
ANGLE_TOL_RAD = 1e-12          # events are located to this in crank angle (omega ~ 25: 4e-14 s)
Start = Literal["nominal", "rest"]


def _with_trace(solve):
    """A solver written to return (Result, Trace) exposed as one returning the Result; the
    samples stay reachable as `solver.with_trace(task, **settings)` (for figures)."""
    @functools.wraps(solve)
    def solver(task, **settings):
        return solve(task, **settings)[0]
    solver.with_trace = solve
    return solver


# --- shared pieces ------------------------------------------------------------------------------

@lru_cache(maxsize=32)
def _dynamics(task: PressDrive) -> Dynamics:
    return dynamics(task)


def initial_state(task: PressDrive, start: str) -> np.ndarray:
    """Physical states plus zero work integrals: at rest, or turning at the nominal speed with
    the pulley at the speed that feeds it (omega i = motor speed) and the belt untwisted."""
    w = 0.0 if start == "rest" else task.nominal_speed_rad_s
    values = {"twist_rad": 0.0, "omega_p_rad_s": w, "phi_rad": 0.0, "omega_rad_s": w}
    return np.r_[[values[k] for k in task.state_names], np.zeros(len(WORK_NAMES))]


@dataclass
class Trace:
    """What a run produced: samples (time, states, mode) and the events located."""
    t: list = field(default_factory=list)
    x: list = field(default_factory=list)
    mode: list = field(default_factory=list)
    events: list = field(default_factory=list)       # (kind, t_s, phi_rad)

    def add(self, t, x, mode):
        self.t.append(np.atleast_1d(t))
        self.x.append(np.atleast_2d(x).reshape(len(np.atleast_1d(t)), -1))
        self.mode.append(np.tile(mode, (len(np.atleast_1d(t)), 1)))

    def arrays(self):
        return np.concatenate(self.t), np.concatenate(self.x), np.concatenate(self.mode)


def _check_common(task, duration_s=None):
    if not isinstance(task, PressDrive):
        raise ModelError(f"task={type(task).__name__}: expected a PressDrive", key="task")
    if duration_s is not None and not duration_s > 0:
        raise ModelError(f"duration_s={duration_s} must be > 0", key="duration_s")


def summarise(task: PressDrive, trace: Trace, *, cut_angles=None) -> tuple[dict, dict]:
    """`values` and `diagnostics` of a run from its samples and events (see the module doc)."""
    dyn = _dynamics(task)
    t, x, mode = trace.arrays()
    out = np.asarray(dyn.outputs.map(len(t))(x.T, mode.T))
    names = dict(zip(Dynamics.OUTPUT_NAMES, out))
    n = dyn.n_states
    iphi, iw = task.state_names.index("phi_rad"), task.state_names.index("omega_rad_s")
    phi, w = x[:, iphi], x[:, iw]
    works = x[-1, n:] - x[0, n:]
    energy = (names["kinetic_J"][-1] + names["potential_J"][-1]) - (names["kinetic_J"][0] + names["potential_J"][0])
    motor, cut, fric, damp = works
    scale = max(abs(motor), abs(cut) + abs(fric) + abs(damp) + abs(energy), 1e-300)
    residual = abs(motor - cut - fric - damp - energy) / scale
    values = {"duration_s": float(t[-1] - t[0]), "energy_residual": float(residual),
              "motor_work_J": float(motor), "cut_work_J": float(cut), "friction_work_J": float(fric),
              "damping_work_J": float(damp), "energy_change_J": float(energy),
              "peak_force_N": float(np.max(names["force_N"])), "peak_Q_N": float(np.max(np.abs(names["Q_N"]))),
              "peak_belt_torque_Nm": float(np.max(np.abs(names["belt_torque_Nm"]))),
              "final_phi_rad": float(phi[-1]), "final_omega_rad_s": float(w[-1]),
              "revolutions": float(np.floor(phi[-1] / TWO_PI + 1e-9) - np.floor(phi[0] / TWO_PI + 1e-9))}
    # the last full revolution: mean speed and fluctuation coefficient (omega_max - omega_min) / omega_mean
    marks = np.arange(np.ceil(phi[0] / TWO_PI - 1e-9), np.floor(phi[-1] / TWO_PI + 1e-9) + 1) * TWO_PI
    if len(marks) >= 2 and np.all(np.diff(phi) >= -1e-12):
        t0, t1 = (np.interp(m, phi, t) for m in marks[-2:])
        inside = (t >= t0 - 1e-12) & (t <= t1 + 1e-12)
        mean = TWO_PI / (t1 - t0)
        values |= {"omega_mean_rad_s": float(mean),
                   "speed_fluctuation": float((_extreme(t[inside], w[inside], max)
                                               - _extreme(t[inside], w[inside], min)) / mean),
                   "period_s": float(t1 - t0)}
    cuts_on = [e for e in trace.events if e[0] == "cut_start"]
    cuts_off = [e for e in trace.events if e[0] == "cut_end"]
    if cut_angles is not None:
        values |= {"cut_start_deg": float(np.degrees(cut_angles[0])), "cut_end_deg": float(np.degrees(cut_angles[1]))}
    elif cuts_on and cuts_off:
        values |= {"cut_start_deg": float(np.degrees(cuts_on[-1][2] % TWO_PI)),
                   "cut_end_deg": float(np.degrees(cuts_off[-1][2] % TWO_PI))}
    diagnostics_cut = None
    if task.cutting:
        coeffs = [getattr(task, k) for k in FORCE_KEYS]
        Z = task.blank_thickness_mm
        antiderivative = [0, 0, *[c / (i + 2) for i, c in enumerate(coeffs)]]      # of eq. (1), N mm
        per_cut_J = float(np.polynomial.polynomial.polyval(Z, antiderivative)) / 1000
        values["cuts"] = float(cut / per_cut_J) if per_cut_J > 0 else 0.0
        window = task.cut_window_rad()
        turns = np.arange(np.floor(phi[0] / TWO_PI) - 1, np.floor(phi[-1] / TWO_PI) + 2) * TWO_PI
        whole = int(np.sum((turns + window[0] >= phi[0] - 1e-9) & (turns + window[1] <= phi[-1] + 1e-9)))
        partial = int(np.sum((turns + window[0] < phi[-1]) & (turns + window[1] > phi[-1] + 1e-9)))
        values["cut_windows"] = float(whole)
        if per_cut_J > 0 and not whole - 1e-3 <= values["cuts"] <= whole + partial + 1e-3:
            diagnostics_cut = (f"the cutting work is {values['cuts']:.4g} cuts' worth over {whole} cut windows "
                               f"crossed: a cut was missed or mis-integrated")
    diagnostics = {"events": [(k, float(tt), float(np.degrees(p))) for k, tt, p in trace.events],
                   "event_count": len(trace.events), "samples": int(len(t)),
                   "min_omega_rad_s": float(w.min()), "states": list(task.state_names),
                   "cut_work_mismatch": diagnostics_cut}
    return values, diagnostics


def _extreme(t, w, pick):
    """The largest (pick=max) or smallest sample of w, refined by a parabola through it and its
    neighbours when it lies between samples (a smooth extremum, not a kink at an event)."""
    i = int(np.argmax(w) if pick is max else np.argmin(w))
    if 0 < i < len(w) - 1 and t[i - 1] < t[i] < t[i + 1]:
        c = np.polyfit(t[i - 1:i + 2] - t[i], w[i - 1:i + 2], 2)
        if c[0] != 0:
            vertex = -c[1] / (2 * c[0])
            if t[i - 1] - t[i] < vertex < t[i + 1] - t[i]:
                return pick(w[i], float(np.polyval(c, vertex)))
    return float(w[i])


def _checked(status, message, violated, diagnostics):
    """A run whose cutting work disagrees with the cut windows it crossed says so, and is at best
    INACCURATE."""
    if diagnostics.get("cut_work_mismatch"):
        return (Status.INACCURATE if status is Status.SOLVED else status,
                f"{message}; {diagnostics['cut_work_mismatch']}", violated + ("cut_work",))
    return status, message, violated


# --- the paper's method: fixed-step RK4 ----------------------------------------------------------

@lru_cache(maxsize=64)
def _rk4_steps(task: PressDrive, step_s: float, count: int) -> ca.Function:
    f = _dynamics(task).switched
    x = ca.SX.sym("x", f.size1_in(0))
    k1 = f(x)
    k2 = f(x + step_s / 2 * k1)
    k3 = f(x + step_s / 2 * k2)
    k4 = f(x + step_s * k3)
    step = ca.Function("rk4", [x], [x + step_s / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    return step.mapaccum("rk4_run", count)


def _rk4_trace(task, step_s, duration_s, start):
    count = int(round(duration_s / step_s))
    if abs(count * step_s - duration_s) > 1e-9 * duration_s or count < 1:
        raise ModelError(f"step_s={step_s} does not divide duration_s={duration_s} into whole steps", key="step_s")
    x0 = initial_state(task, start)
    xs = np.asarray(_rk4_steps(task, step_s, count)(x0)).T
    trace = Trace()
    dyn = _dynamics(task)
    xs = np.vstack([x0, xs])
    t = np.arange(count + 1) * step_s
    # the mode each sample saw, as the paper's U and sign(omega) evaluate it (for the outputs)
    u = _paper_U(task, xs)
    trace.add(t, xs, np.zeros(3))
    trace.mode = [np.column_stack([u, np.sign(xs[:, task.state_names.index("omega_rad_s")]), np.zeros_like(u)])]
    on = np.flatnonzero(np.diff(u) > 0) + 1
    off = np.flatnonzero(np.diff(u) < 0) + 1
    iphi = task.state_names.index("phi_rad")
    trace.events = sorted([("cut_start", t[i], xs[i, iphi]) for i in on]
                          + [("cut_end", t[i], xs[i, iphi]) for i in off], key=lambda e: e[1])
    return trace, dyn


def _paper_U(task, xs):
    if not task.cutting:
        return np.zeros(len(xs))
    phi = xs[:, task.state_names.index("phi_rad")]
    w = xs[:, task.state_names.index("omega_rad_s")]
    pen = task.travel(phi) * 1000 - (task.stroke_mm - task.blank_thickness_mm - task.shortfall_mm)
    down = w * np.sin(phi) > 0          # dX/dphi = r sin(phi) (1 + lambda cos(phi) ...) has the sign of sin(phi)
    return ((pen >= 0) & (pen <= task.blank_thickness_mm) & down).astype(float)


@_with_trace
def rk4(task: PressDrive, *, step_s: float = 1e-4, duration_s: float = 1.0, start: Start = "nominal",
        refine_tol_rad: float = 1e-6, max_halvings: int = 4) -> Result:
    """Fixed-step RK4 on eqs. (2) with the paper's switching function U (Sec. "DYNAM").

    The step is halved (`max_halvings` at most) until two successive runs agree on the final
    crank angle within `refine_tol_rad` (the paper's "refinement of the integration step");
    0 disables refining.
    U and sign(omega) are evaluated at every stage, so the step that contains the jump at the
    end of the cut is only first-order accurate: the method's error is O(h), not O(h^4).

    Parameters
    ----------
    step_s : first step [s]; must divide `duration_s`.
    duration_s : simulated time [s].
    start : "nominal" (turning at the nominal speed) or "rest".
    Returns a Result: SOLVED, or INACCURATE when refinement did not reach `refine_tol_rad`.
    """
    _check_common(task, duration_s)
    if not step_s > 0:
        raise ModelError(f"step_s={step_s} must be > 0", key="step_s")
    t_start = time.perf_counter()
    build = 0.0
    trace, _ = _rk4_trace(task, step_s, duration_s, start)
    iphi = task.state_names.index("phi_rad")
    change, halvings, h = np.inf, 0, step_s
    while refine_tol_rad > 0 and halvings < max_halvings and np.all(np.isfinite(trace.x[0])):
        finer, _ = _rk4_trace(task, h / 2, duration_s, start)
        change = abs(finer.x[0][-1, iphi] - trace.x[0][-1, iphi])
        trace, h, halvings = finer, h / 2, halvings + 1
        if change <= refine_tol_rad:
            break
    if not np.all(np.isfinite(trace.x[0])):     # explicit RK4 beyond its stability limit: say so, no NaN
        return Result(Status.FAILED, {"step_s": h}, Timing(build, time.perf_counter() - t_start - build),
                      message=f"RK4 diverged at step {h:.3g} s: the step exceeds the stability limit of the "
                              f"stiffest mode (the belt); reduce step_s or use events"), trace
    values, diagnostics = summarise(task, trace)
    values["step_s"] = h
    diagnostics |= {"halvings": halvings, "last_change_rad": float(change) if np.isfinite(change) else None}
    ok = refine_tol_rad <= 0 or change <= refine_tol_rad
    diagnostics["switches_stepped_over"] = True      # fixed steps: first order across the jump
    status, message, violated = _checked(Status.SOLVED if ok else Status.INACCURATE,
                                         f"RK4, step {h:.3g} s after {halvings} halvings; fixed steps cross "
                                         "the jump at the end of the cut and the friction sign change "
                                         "(first order there: the paper's method as published)"
                                         + ("" if ok else f"; last halving still moved phi by {change:.3g} rad > "
                                                          f"{refine_tol_rad:g}"), (), diagnostics)
    timing = Timing(build, time.perf_counter() - t_start - build)
    return Result(status, values, timing, message, violated, diagnostics), trace


# --- events: CVODES piecewise, restarted at located events ----------------------------------------

@lru_cache(maxsize=32)
def _piece(task: PressDrive, tol: float, samples: int) -> ca.Function:
    """CVODES over a piece of duration p[0] in mode p[1:] (time scaled to [0, 1]): the states at
    `samples` equally spaced times, the last being the end of the piece."""
    rhs = _dynamics(task).rhs
    x = ca.SX.sym("x", rhs.size1_in(0))
    p = ca.SX.sym("p", 4)
    grid = np.linspace(0, 1, samples + 1)[1:]
    return ca.integrator("piece", "cvodes", {"x": x, "p": p, "ode": p[0] * rhs(x, p[1:])}, 0.0, grid,
                         {"abstol": tol, "reltol": tol, "max_num_steps": 100000})


class _Stall(Exception):
    pass


@_with_trace
def events(task: PressDrive, *, tol: float = 1e-10, duration_s: float = 1.0, start: Start = "nominal",
           max_step_s: float = 0.02, samples: int = 8, max_events: int = 10000) -> Result:
    """CVODES between located events, restarted at each (see the module doc).

    Events: "cut_start" and "cut_end" (the crank angles where X = H - Z - delta and X = H - delta
    on the way down), "revolution" (every 2 pi), "stop" (omega reaches 0), "stick" / "slip"
    (static friction holds the crank / lets it go). The crank angle is monotone while the crank
    turns, so the next angle event is known in advance: each piece aims at it, and Newton on the
    piece's duration (d phi / dT = omega) lands on it to `ANGLE_TOL_RAD`. A piece never exceeds
    `max_step_s`, so a sign change of omega (friction) cannot hide inside a long piece; no angle
    event can be stepped over whatever `tol` is, because it is located from the angle itself.

    Parameters
    ----------
    tol : CVODES relative and absolute tolerance.
    duration_s : simulated time [s].  start : "nominal" or "rest".
    max_step_s : longest piece [s].  samples : outputs per piece (for peaks and plots).
    Returns a Result: SOLVED; INFEASIBLE with violated ("stall",) when the crank stops inside the
    cut or never turns; LIMIT after `max_events`; FAILED if CVODES fails.
    """
    _check_common(task, duration_s)
    for key, value in (("tol", tol), ("max_step_s", max_step_s)):
        if not value > 0:
            raise ModelError(f"{key}={value} must be > 0", key=key)
    if samples < 1:
        raise ModelError(f"samples={samples} must be >= 1", key="samples")
    t_start = time.perf_counter()
    piece = _piece(task, tol, samples)
    build = time.perf_counter() - t_start
    trace = Trace()
    status, message, violated = Status.SOLVED, "", ()
    try:
        _march(task, piece, trace, initial_state(task, start), duration_s, max_step_s, max_events)
        message = f"CVODES tol {tol:g}, {len(trace.events)} events located"
    except _Stall as stall:
        status, violated, message = Status.INFEASIBLE, ("stall",), str(stall)
    except _Limit as limit:
        status, message = Status.LIMIT, str(limit)
    except RuntimeError as exc:        # CVODES gave up (e.g. too much work): a status, not a crash
        if isinstance(exc, MechoptError):
            raise
        status, message = from_casadi_integrator(str(exc)), f"CVODES failed: {exc}"
    if not trace.t:
        return Result(status, {}, Timing(build, time.perf_counter() - t_start - build), message, violated), trace
    values, diagnostics = summarise(task, trace)
    if status is Status.SOLVED and values["revolutions"] < 1 and values["final_omega_rad_s"] <= 0:
        status, violated = Status.INFEASIBLE, ("stall",)
        message = f"the crank never turned in {duration_s} s: the drive cannot overcome friction and the load"
    status, message, violated = _checked(status, message, violated, diagnostics)
    timing = Timing(build, time.perf_counter() - t_start - build)
    return Result(status, values, timing, message, violated, diagnostics), trace


class _Limit(Exception):
    pass


def _angle_events(task, phi):
    """The next angle event strictly after phi: (angle, kind)."""
    base = np.floor(phi / TWO_PI) * TWO_PI
    marks = [(0.0, "revolution")]
    window = task.cut_window_rad()
    if window is not None and window[0] < window[1]:
        marks += [(window[0], "cut_start"), (window[1], "cut_end")]
    for turn in (0, 1):
        for angle, kind in sorted(marks):
            a = base + turn * TWO_PI + angle
            if a > phi + ANGLE_TOL_RAD:
                return a, kind
    raise AssertionError("unreachable")


def _mode_at(task, dyn, x, moving_sign):
    """[U, friction sign, stuck] for a state: U from the crank angle (half-open window)."""
    phi = x[task.state_names.index("phi_rad")]
    window = task.cut_window_rad()
    u = 0.0
    if window is not None and moving_sign > 0:
        a = phi % TWO_PI
        u = float(window[0] - ANGLE_TOL_RAD <= a < window[1] - ANGLE_TOL_RAD)
    return np.array([u, float(moving_sign), 0.0])


def _drive_torque(dyn, x, mode):
    return float(dyn.outputs(x, mode)[8])


def _march(task, piece, trace, x, duration_s, max_step_s, max_events):
    dyn = _dynamics(task)
    iphi, iw = task.state_names.index("phi_rad"), task.state_names.index("omega_rad_s")
    friction = task.friction_torque_Nm if task.friction else 0.0
    t = 0.0
    mode = _start_mode(task, dyn, x, friction)
    trace.add(t, x, mode)
    while t < duration_s * (1 - 1e-14):
        if len(trace.events) > max_events:
            raise _Limit(f"more than max_events={max_events} events by t = {t:.6g} s")
        stuck = mode[2] > 0
        T = min(max_step_s, duration_s - t)
        target = kind = None
        if not stuck and mode[1] > 0:
            target, kind = _angle_events(task, x[iphi])
            if x[iw] > 0:
                T = min(T, (target - x[iphi]) / x[iw])
        xs = _run(piece, x, T, mode)
        end = xs[-1]
        # friction events: omega crossing zero while moving, breakaway while stuck
        if stuck:
            g = lambda s: abs(_drive_torque(dyn, s, mode)) - friction
            gs = [g(s) for s in xs]
            hit = next((i for i, v in enumerate(gs) if v > 0), None)
            if hit is not None:
                T_ev, xe = _locate(piece, x, mode, T * hit / len(xs), T * (hit + 1) / len(xs), g)
                xs = _run(piece, x, T_ev, mode)
                t = _commit(trace, t, T_ev, xs, mode)
                x = xs[-1]
                sign = np.sign(_drive_torque(dyn, x, mode))
                mode = _mode_at(task, dyn, x, sign)
                trace.events.append(("slip", t, float(x[iphi])))
                continue
        elif mode[1] != 0:
            ws = xs[:, iw] * mode[1]
            hit = next((i for i, v in enumerate(ws) if v <= 0), None)
            if hit is not None:
                lo = T * hit / len(xs)
                T_ev, xe = _locate(piece, x, mode, lo, T * (hit + 1) / len(xs), lambda s: s[iw] * mode[1])
                xs = _run(piece, x, T_ev, mode)
                t = _commit(trace, t, T_ev, xs, mode)
                x = xs[-1].copy()
                x[iw] = 0.0            # exactly at rest: the event's definition
                trace.events.append(("stop", t, float(x[iphi])))
                if mode[0] > 0:
                    raise _Stall(f"the press stalls in the cut at crank angle {np.degrees(x[iphi] % TWO_PI):.3f} deg, "
                                 f"t = {t:.6g} s: the flywheel and motor cannot supply the cutting work")
                mode = _start_mode(task, dyn, x, friction)
                if mode[2] > 0:
                    trace.events.append(("stick", t, float(x[iphi])))
                continue
        if target is not None and end[iphi] >= target - ANGLE_TOL_RAD:
            if abs(end[iphi] - target) > ANGLE_TOL_RAD:
                T, xs = _newton_angle(piece, x, mode, T, target, iphi, iw)
            t = _commit(trace, t, T, xs, mode)
            x = xs[-1]
            trace.events.append((kind, t, float(target)))
            x = x.copy()
            x[iphi] = target               # remove the last 1e-12 rad so the next window is clean
            mode = _mode_at(task, dyn, x, 1.0)
            continue
        t = _commit(trace, t, T, xs, mode)
        x = end


def _start_mode(task, dyn, x, friction):
    """Mode for a state at rest or moving: stuck if static friction holds it."""
    w = x[task.state_names.index("omega_rad_s")]
    if w != 0:
        return _mode_at(task, dyn, x, np.sign(w))
    rest = np.array([0.0, 0.0, 1.0])
    drive = _drive_torque(dyn, x, rest)
    if abs(drive) <= friction:
        return rest
    return _mode_at(task, dyn, x, np.sign(drive))


def _run(piece, x, T, mode):
    out = piece(x0=x, p=np.r_[T, mode])["xf"]
    return np.asarray(out).T


def _commit(trace, t, T, xs, mode):
    n = len(xs)
    trace.add(t + T * np.arange(1, n + 1) / n, xs, mode)
    return t + T


def _newton_angle(piece, x, mode, T, target, iphi, iw):
    """Duration T at which phi reaches `target` (Newton: d phi / dT = omega)."""
    for _ in range(50):
        xs = _run(piece, x, T, mode)
        miss = xs[-1, iphi] - target
        if abs(miss) <= ANGLE_TOL_RAD:
            return T, xs
        T -= miss / xs[-1, iw]
    raise _Limit(f"event at crank angle {target:.12g} rad not located to {ANGLE_TOL_RAD} rad in 50 Newton steps")


def _locate(piece, x, mode, lo, hi, g):
    """Duration in [lo, hi] where g(state) changes sign (Illinois false position)."""
    g_lo = g(_run(piece, x, lo, mode)[-1]) if lo > 0 else g(x)
    g_hi = g(_run(piece, x, hi, mode)[-1])
    side = 0
    for _ in range(200):
        mid = hi - g_hi * (hi - lo) / (g_hi - g_lo) if g_hi != g_lo else 0.5 * (lo + hi)
        state = _run(piece, x, mid, mode)[-1]
        g_mid = g(state)
        if abs(hi - lo) < 1e-14 or g_mid == 0:
            return mid, state
        if (g_mid > 0) == (g_hi > 0):
            hi, g_hi = mid, g_mid
            if side == 1:
                g_lo /= 2
            side = 1
        else:
            lo, g_lo = mid, g_mid
            if side == -1:
                g_hi /= 2
            side = -1
        if abs(g_mid) < 1e-12:
            return mid, state
    raise _Limit(f"an event was not located to 1e-12 in 200 false-position steps (bracket {hi - lo:.3g} s, "
                 f"g = {g_mid:.3g})")


# --- steady_state: the periodic motion over one revolution, solved directly ------------------------

@lru_cache(maxsize=16)
def _revolution(task: PressDrive, tol: float, samples: int):
    """The revolution as CVODES pieces in the crank angle (d/dphi = (d/dt) / omega): the states
    other than phi, then time, then the work integrals. Returns (pieces, their angle spans, U)."""
    dyn = _dynamics(task)
    n = dyn.n_states
    iphi = task.state_names.index("phi_rad")
    y = ca.SX.sym("y", n - 1 + 1 + len(WORK_NAMES))      # other states, time, works
    phi = ca.SX.sym("phi")
    u = ca.SX.sym("u")
    states = ca.vertcat(y[:iphi], phi, y[iphi:n - 1])
    xdot = dyn.rhs(ca.vertcat(states, y[n:]), ca.vertcat(u, 1, 0))
    w = states[task.state_names.index("omega_rad_s")]
    dy = ca.vertcat(xdot[:iphi], xdot[iphi + 1:n], 1, xdot[n:]) / w
    window = task.cut_window_rad()
    cuts = [0.0, window[0], window[1], TWO_PI] if window is not None and window[0] < window[1] else [0.0, TWO_PI]
    pieces = []
    for k, (a, b) in enumerate(zip(cuts[:-1], cuts[1:])):
        grid = np.linspace(a, b, samples + 1)[1:]
        pieces.append((ca.integrator(f"rev{k}", "cvodes", {"x": y, "t": phi, "p": u, "ode": dy}, a, grid,
                                     {"abstol": tol, "reltol": tol, "max_num_steps": 100000}),
                       grid, float(len(cuts) == 4 and k == 1)))
    return pieces, n


@_with_trace
def steady_state(task: PressDrive, *, tol: float = 1e-10, samples: int = 60, max_iter: int = 30) -> Result:
    """The periodic steady motion (the paper's assumption: the whole cut happens in steady
    motion), found directly instead of integrating until transients die.

    Unknowns: the states at phi = 0 other than phi (belt twist, pulley and crank speeds); the
    revolution maps them, through three CVODES pieces in the crank angle (idle, cut, idle: the
    cut's ends are fixed angles there, so no event location is needed), to the states at
    phi = 2 pi. CasADi's Newton rootfinder, with CVODES sensitivities, makes the two equal.
    Assumes the crank keeps turning forward (omega > 0); a solution that violates it is FAILED.
    A belt far stiffer than the drive (1e6 times the KD2322 value) makes the CVODES
    sensitivities very expensive (minutes, and Newton stalls at ~1e-7): use the rigid-belt
    model there, which is the same motion to 1e-7 rad (a test pins that with `events`).

    Parameters
    ----------
    tol : CVODES tolerance (relative and absolute); the periodicity residual is held to 100 tol.
    samples : outputs per piece (peaks, plots).  max_iter : Newton iterations.
    """
    _check_common(task)
    if not tol > 0:
        raise ModelError(f"tol={tol} must be > 0", key="tol")
    t_start = time.perf_counter()
    pieces, n = _revolution(task, tol, samples)
    m = n - 1
    y0 = ca.MX.sym("y0", m)
    y = ca.vertcat(y0, ca.MX.zeros(1 + len(WORK_NAMES)))
    for integ, _, u in pieces:
        y = integ(x0=y, p=u)["xf"][:, -1]
    residual = ca.Function("periodic", [y0], [y[:m] - y0])
    rf = ca.rootfinder("rf", "newton", residual, {"max_iter": max_iter, "error_on_fail": False,
                                                  "abstol": 100 * tol})
    build = time.perf_counter() - t_start
    guess = np.delete(initial_state(task, "nominal")[:n], task.state_names.index("phi_rad"))
    if task.motor:      # start near the motor's idle speed rather than the nominal one
        guess[[i for i, k in enumerate(np.delete(np.array(task.state_names), task.state_names.index("phi_rad")))
               if k.startswith("omega")]] = task.motor_sync_speed_rad_s / task.gear_ratio * 0.99
    try:                # the re-integration of the found orbit can fail as well as the Newton solve
        solution = np.asarray(rf(guess)).ravel()
        status = from_rootfinder(rf.stats()["return_status"])
        trace = _revolution_trace(task, pieces, n, solution)
        miss = float(np.max(np.abs(np.asarray(residual(solution)).ravel())))
    except RuntimeError as exc:
        if isinstance(exc, MechoptError):
            raise
        return Result(from_casadi_integrator(str(exc)), {}, Timing(build, time.perf_counter() - t_start - build),
                      message=f"CVODES failed inside the periodic Newton solve: {exc}"), Trace()
    values, diagnostics = summarise(task, trace, cut_angles=task.cut_window_rad())
    values["periodicity_residual"] = miss
    diagnostics |= {"newton_iterations": rf.stats()["iter_count"], "initial_state": solution.tolist()}
    message = f"periodic orbit by Newton shooting, {rf.stats()['iter_count']} iterations, residual {miss:.3g}"
    if status is Status.SOLVED and diagnostics["min_omega_rad_s"] <= 0:
        status, message = Status.FAILED, message + "; the crank does not keep turning forward: no such orbit"
    if status is Status.SOLVED and miss > 1e3 * tol:
        status = Status.INACCURATE
    status, message, violated = _checked(status, message, (), diagnostics)
    return Result(status, values, Timing(build, time.perf_counter() - t_start - build), message, violated,
                  diagnostics), trace


def _revolution_trace(task, pieces, n, y0):
    """Samples over the revolution from the initial states y0 (other than phi) [as a Trace]."""
    iphi = task.state_names.index("phi_rad")
    trace = Trace()
    y = np.r_[y0, np.zeros(1 + len(WORK_NAMES))]

    def full(ycol, phi):
        return np.r_[ycol[:iphi], phi, ycol[iphi:n - 1], ycol[n:]], ycol[n - 1]

    x, t = full(y, 0.0)
    trace.add(t, x, np.array([0.0, 1.0, 0.0]))
    for integ, grid, u in pieces:
        ys = np.asarray(integ(x0=y, p=u)["xf"]).T
        rows = [full(row, a) for row, a in zip(ys, grid)]
        trace.add(np.array([r[1] for r in rows]), np.array([r[0] for r in rows]), np.array([u, 1.0, 0.0]))
        kind = "cut_start" if u == 0 and grid[-1] < TWO_PI else ("cut_end" if u == 1 else "revolution")
        trace.events.append((kind, float(rows[-1][1]), float(grid[-1])))
        y = ys[-1]
    return trace


# --- the peer: scipy's solve_ivp ---------------------------------------------------------------------

@_with_trace
def ivp(task: PressDrive, *, method: Literal["Radau", "LSODA", "DOP853", "RK45", "BDF"] = "Radau",
        rtol: float = 1e-8, atol: float = 1e-10, duration_s: float = 1.0, locate_events: bool = True,
        max_step_s: float = 0.0) -> Result:
    """scipy's solve_ivp from the nominal state, the peer a user would reach for.

    With `locate_events`, each smooth piece ends at a terminal event (the next cut start, cut
    end or revolution angle) and the integration restarts in the new mode, as `events` does.
    Without it the paper's switched right-hand side is integrated in one go: at loose tolerance
    and with no `max_step_s` (0 = unbounded) the adaptive step can jump over the whole cut, and
    `values["cuts"]` then counts fewer cuts than revolutions (the test of a missed cut).
    Friction sticking is not handled here (the crank must keep turning).
    """
    _check_common(task, duration_s)
    dyn = _dynamics(task)
    iphi, iw = task.state_names.index("phi_rad"), task.state_names.index("omega_rad_s")
    t_start = time.perf_counter()
    x = initial_state(task, "nominal")
    x_sym, m_sym = ca.SX.sym("x", dyn.rhs.size1_in(0)), ca.SX.sym("m", 3)
    jac = ca.Function("rhs_jacobian", [x_sym, m_sym], [ca.jacobian(dyn.rhs(x_sym, m_sym), x_sym)])
    trace, t, calls = Trace(), 0.0, 0
    options = {"method": method, "rtol": rtol, "atol": atol}
    if max_step_s > 0:
        options["max_step"] = max_step_s
    if not locate_events:
        sol = solve_ivp(lambda tt, xx: np.asarray(dyn.switched(xx)).ravel(), (0.0, duration_s), x,
                        dense_output=False, **options)
        status = from_ivp(sol.status)
        if sol.t.size:
            trace.add(sol.t, sol.y.T, np.zeros(3))
            trace.mode = [np.column_stack([_paper_U(task, sol.y.T), np.ones(sol.t.size), np.zeros(sol.t.size)])]
        values, diagnostics = summarise(task, trace)
        diagnostics["rhs_calls"] = int(sol.nfev)
        diagnostics["switches_stepped_over"] = bool(task.cutting or "friction" in task.effects)
        if status is Status.SOLVED and diagnostics["switches_stepped_over"]:
            # the cut's jump and sign(omega) lie inside steps: the error there is uncontrolled
            status = Status.INACCURATE
        status, message, violated = _checked(status, sol.message + (
            "; switched right-hand side integrated without event location: the cut's jump and the "
            "friction sign change were stepped over" if diagnostics["switches_stepped_over"] else ""), (), diagnostics)
        timing = Timing(0.0, time.perf_counter() - t_start)
        return Result(status, values, timing, message, violated, diagnostics), trace
    mode = _mode_at(task, dyn, x, 1.0)
    trace.add(t, x, mode)
    status, message = Status.SOLVED, ""
    while t < duration_s * (1 - 1e-14):
        target, kind = _angle_events(task, x[iphi])
        f = (lambda m: lambda tt, xx: np.asarray(dyn.rhs(xx, m)).ravel())(mode)
        J = (lambda m: lambda tt, xx: np.asarray(jac(xx, m)))(mode)
        hit = (lambda a: lambda tt, xx: xx[iphi] - a)(target)
        hit.terminal, hit.direction = True, 1
        stop = lambda tt, xx: xx[iw]
        stop.terminal, stop.direction = True, -1
        extra = {"jac": J} if method in ("Radau", "BDF", "LSODA") else {}
        sol = solve_ivp(f, (t, duration_s), x, events=[hit, stop], **options, **extra)
        calls += sol.nfev
        if from_ivp(sol.status) is not Status.SOLVED:
            status, message = Status.FAILED, sol.message
            break
        trace.add(sol.t[1:], sol.y.T[1:], mode)
        t, x = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status == 1 and sol.t_events[1].size:
            status, message = Status.INFEASIBLE, f"the crank stopped at t = {t:.6g} s (not handled by ivp)"
            break
        if sol.status == 1:
            trace.events.append((kind, t, float(target)))
            x[iphi] = target
            mode = _mode_at(task, dyn, x, 1.0)
    values, diagnostics = summarise(task, trace)
    diagnostics["rhs_calls"] = int(calls)
    status, message, violated = _checked(status, message or f"solve_ivp {method}", (), diagnostics)
    timing = Timing(0.0, time.perf_counter() - t_start)
    return Result(status, values, timing, message, violated, diagnostics), trace
