"""The press by CVODES (CasADi) integrating each smooth piece and restarting at located events:
U switching on, the jump, every full revolution, and friction sign changes (crank stopping,
sticking, breaking away). CasADi 3.8's own events fire on one crossing direction only and never
with a single output time, so events are located here by Newton on the piece's duration instead
(see `_locate`)."""
import time

import casadi as ca
import numpy as np

from mechopt.models.cache import memoised
from mechopt.models.errors import MechoptError, ModelError
from mechopt.models.press import PressDrive
from mechopt.solvers.press.problem import (
    ANGLE_TOL_RAD,
    TWO_PI,
    Duration,
    Samples,
    Start,
    Trace,
    angle_events,
    casadi_failure,
    check_task,
    checked,
    drive_torque,
    dynamics_of,
    initial_state,
    mode_at,
    refuse_work,
    stall_check,
    summarise,
    top_speed_rad_s,
)
from mechopt.solvers.result import Result, Status, Timing
from mechopt.solvers.settings import Annotated, Interval, Positive, Tolerance


@memoised(maxsize=32)
def _piece(task: PressDrive, tol: float, samples: int) -> ca.Function:
    """CVODES over a piece of duration p[0] in mode p[1:] (time scaled to [0, 1]): the states at
    `samples` equally spaced times, the last being the end of the piece."""
    rhs = dynamics_of(task).rhs
    x = ca.SX.sym("x", rhs.size1_in(0))
    p = ca.SX.sym("p", 4)
    grid = np.linspace(0, 1, samples + 1)[1:]
    return ca.integrator("piece", "cvodes", {"x": x, "p": p, "ode": p[0] * rhs(x, p[1:])}, 0.0, grid,
                         {"abstol": tol, "reltol": tol, "max_num_steps": 100000})


MAX_PIECES = 50_000          # ~25 s of CVODES calls
MAX_SAMPLES = 1_000_000      # states and outputs kept: ~250 MB


class _Stall(Exception):
    pass


def events(task: PressDrive, *, tol: Tolerance = 1e-10, duration_s: Duration = 1.0, start: Start = "nominal",
           max_step_s: Positive = 0.02, samples: Samples = 8,
           max_events: Annotated[int, Interval(ge=1, le=100_000)] = 10000) -> Result:
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
    A request that implies more than `MAX_PIECES` pieces or `MAX_SAMPLES` samples is refused
    before any work (ModelError naming the key and its allowed range).
    Returns a Result: SOLVED; INFEASIBLE with violated ("stall",) when the crank stops inside the
    cut, never turns, or coasts to a stop and is held by friction at the end (with the mean load
    torque against the breakdown torque in `values` when the motor cannot carry the cycle);
    LIMIT after `max_events`; FAILED if CVODES fails.
    """
    check_task(task, duration_s)
    for key, value in (("tol", tol), ("max_step_s", max_step_s)):
        if not value > 0:
            raise ModelError(f"{key}={value} must be > 0", key=key)
    if samples < 1:
        raise ModelError(f"samples={samples} must be >= 1", key="samples")
    # pieces: one per max_step_s at least, plus three events per revolution at the top speed
    per_s = 1 / max_step_s + 3 * top_speed_rad_s(task) / TWO_PI
    refuse_work("duration_s", duration_s, duration_s * per_s, MAX_PIECES, "CVODES pieces (~0.5 ms each)",
                f"duration_s <= {MAX_PIECES / per_s:.4g} s with max_step_s={max_step_s:g}")
    refuse_work("samples", samples, duration_s * per_s * samples, MAX_SAMPLES, "samples in memory",
                f"samples <= {max(int(MAX_SAMPLES / (duration_s * per_s)), 1)} over duration_s={duration_s:g}")
    t_start = time.perf_counter()
    piece = _piece(task, tol, samples)
    build = time.perf_counter() - t_start
    trace = Trace()
    status, message, violated, failure = Status.SOLVED, "", (), {}
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
        t_fail = float(trace.t[-1][-1]) if trace.t else 0.0
        status, message, failure = casadi_failure(exc, f"at t = {t_fail:.6g} s of {duration_s} s")
    if not trace.t:
        return Result(status, {}, Timing(build, time.perf_counter() - t_start - build), message, violated, failure)
    values, diagnostics, arrays = summarise(task, trace)
    diagnostics |= failure
    if status is Status.SOLVED and values["revolutions"] < 1 and values["final_omega_rad_s"] <= 0:
        status, violated = Status.INFEASIBLE, ("stall",)
        turned = float(np.degrees(values["final_phi_rad"] - arrays["phi_rad"][0]))
        message = ((f"the crank turned only {turned:.1f} deg in {duration_s} s and ended at rest or going back"
                    if turned > 1.0 else f"the crank never turned in {duration_s} s")
                   + ": the drive cannot overcome friction and the load")
    held = [e for e in trace.events if e[0] in ("stick", "slip")]
    if status is Status.SOLVED and held and held[-1][0] == "stick":
        status, violated = Status.INFEASIBLE, ("stall",)
        message = (f"the press coasted to a stop: static friction holds the crank at {np.degrees(held[-1][2] % TWO_PI):.3f}"
                   f" deg from t = {held[-1][1]:.6g} s to the end, after {values['revolutions']:.0f} revolutions")
    stall = stall_check(task)
    if stall is not None:       # the mean load is beyond the motor: a run that still turns is slowing to a stall
        values |= stall[0]
        message += "; " + stall[1] + ("" if violated else ": this run is slowing down toward a stall")
    status, message, violated = checked(status, message, violated, diagnostics)
    timing = Timing(build, time.perf_counter() - t_start - build)
    return Result(status, values, timing, message, violated, diagnostics, arrays)


class _Limit(Exception):
    pass


def _march(task, piece, trace, x, duration_s, max_step_s, max_events):
    dyn = dynamics_of(task)
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
            target, kind = angle_events(task, x[iphi])
            if x[iw] > 0:
                T = min(T, (target - x[iphi]) / x[iw])
        xs = _run(piece, x, T, mode)
        end = xs[-1]
        # friction events: omega crossing zero while moving, breakaway while stuck
        if stuck:
            g = lambda s: abs(drive_torque(dyn, s, mode)) - friction
            gs = [g(s) for s in xs]
            hit = next((i for i, v in enumerate(gs) if v > 0), None)
            if hit is not None:
                T_ev, xe = _locate(piece, x, mode, T * hit / len(xs), T * (hit + 1) / len(xs), g)
                xs = _run(piece, x, T_ev, mode)
                t = _commit(trace, t, T_ev, xs, mode)
                x = xs[-1]
                sign = np.sign(drive_torque(dyn, x, mode))
                mode = mode_at(task, dyn, x, sign)
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
            mode = mode_at(task, dyn, x, 1.0)
            continue
        t = _commit(trace, t, T, xs, mode)
        x = end


def _start_mode(task, dyn, x, friction):
    """Mode for a state at rest or moving: stuck if static friction holds it."""
    w = x[task.state_names.index("omega_rad_s")]
    if w != 0:
        return mode_at(task, dyn, x, np.sign(w))
    rest = np.array([0.0, 0.0, 1.0])
    drive = drive_torque(dyn, x, rest)
    if abs(drive) <= friction:
        return rest
    return mode_at(task, dyn, x, np.sign(drive))


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
