"""The press by CVODES (CasADi) integrating each smooth piece and restarting at located events:
U switching on, the jump, every full revolution, and friction sign changes (crank stopping,
sticking, breaking away). CasADi 3.8's own events fire on one crossing direction only and never
with a single output time, so events are located here by Newton on the piece's duration instead
(see `locate`)."""

import numpy as np

from mechopt.kit.errors import MechoptError, ModelError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, Positive, Tolerance
from mechopt.models.press import PressDrive
from mechopt.models.press_energy import stall_check
from mechopt.solvers.press.problem import (
    RIGID_LIMIT,
    TWO_PI,
    Duration,
    Limit,
    Samples,
    Stall,
    Start,
    Trace,
    belt_mode,
    casadi_failure,
    check_task,
    checked,
    initial_state,
    march,
    nominal_speed_note,
    piece_by_time,
    refuse_work,
    summarise,
    top_speed_rad_s,
)

MAX_PIECES = 50_000          # ~25 s of CVODES calls
MAX_SAMPLES = 1_000_000      # states and outputs kept: ~250 MB
MAX_BELT_STEPS = 500_000     # CVODES steps following the belt's oscillation (~1e-4 s each: ~50 s)
STEPS_PER_BELT_PERIOD = 10


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
    before any work (SettingError naming the key and its allowed range).
    Returns a Result: SOLVED; INFEASIBLE with violated ("stall",) when the crank stops inside the
    cut, never turns, or coasts to a stop and is held by friction at the end (with the mean load
    torque against the breakdown torque in `values` when the motor cannot carry the cycle);
    LIMIT after `max_events`; FAILED if CVODES fails.
    """
    check_task(task, events, tol=tol, duration_s=duration_s, start=start, max_step_s=max_step_s, samples=samples,
               max_events=max_events)
    # pieces: one per max_step_s at least, plus three events per revolution at the top speed
    per_s = 1 / max_step_s + 3 * top_speed_rad_s(task) / TWO_PI
    refuse_work("duration_s", duration_s, duration_s * per_s, MAX_PIECES, "CVODES pieces (~0.5 ms each)",
                f"duration_s <= {MAX_PIECES / per_s:.4g} s with max_step_s={max_step_s:g}")
    refuse_work("samples", samples, duration_s * per_s * samples, MAX_SAMPLES, "samples in memory",
                f"samples <= {max(int(MAX_SAMPLES / (duration_s * per_s)), 1)} over duration_s={duration_s:g}")
    _refuse_a_belt_too_fast(task, duration_s)
    clock = Clock()
    piece = piece_by_time(task, tol, samples)
    clock.built()
    trace = Trace()
    status, message, violated, failure = Status.SOLVED, "", (), {}
    try:
        march(task, piece, trace, initial_state(task, start), duration_s, max_step_s, max_events)
        message = f"CVODES tol {tol:g}, {len(trace.events)} events located" + nominal_speed_note(task)
    except Stall as stall:
        status, violated, message = Status.INFEASIBLE, ("stall",), str(stall)
    except Limit as limit:
        status, message = Status.LIMIT, str(limit)
    except RuntimeError as exc:        # CVODES gave up (e.g. too much work): a status, not a crash
        if isinstance(exc, MechoptError):
            raise
        t_fail = float(trace.t[-1][-1]) if trace.t else 0.0
        status, message, failure = casadi_failure(exc, f"at t = {t_fail:.6g} s of {duration_s} s")
    if not trace.t:
        return clock.result(status, {}, message, violated, failure)
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
    return clock.result(status, values, message, violated, diagnostics, arrays)


def _refuse_a_belt_too_fast(task, duration_s):
    """CVODES must follow an oscillating belt mode (`STEPS_PER_BELT_PERIOD` steps a period) however
    stiff its method: past `MAX_BELT_STEPS` over the run, refuse before any work, naming the stiffest
    belt (it grows with the square of the frequency) and the duration that fit."""
    _, eigenvalue = belt_mode(task)
    hz = abs(eigenvalue.imag) / TWO_PI         # an overdamped mode is only stiff: BDF steps over it
    steps = STEPS_PER_BELT_PERIOD * hz * duration_s
    if steps > MAX_BELT_STEPS:
        most_stiff = task.belt_stiffness_Nm_rad * (MAX_BELT_STEPS / steps) ** 2
        refuse_work("belt_stiffness_Nm_rad", task.belt_stiffness_Nm_rad, steps, MAX_BELT_STEPS,
                    f"CVODES steps following the belt mode at {hz:.4g} Hz for {duration_s:g} s (~1e-4 s each)",
                    f"belt_stiffness_Nm_rad <= {most_stiff:.3g} at duration_s={duration_s:g}, or duration_s <= "
                    f"{duration_s * MAX_BELT_STEPS / steps:.3g} s; {RIGID_LIMIT}", kind=ModelError)
