"""The periodic steady motion of the press over one revolution, solved directly: in the crank
angle as independent variable the cut starts and ends at fixed angles, so one revolution is three
CVODES pieces composed symbolically, and Newton's method finds the initial state that the
revolution reproduces; a what-if re-solves on the structure's build from the last orbit."""

import numpy as np

from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import MechoptError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, Tolerance
from mechopt.models.press import PressDrive
from mechopt.models.press_energy import breakdown_torque_at_crank_Nm, cut_work_J, required_mean_torque_Nm, stall_check
from mechopt.models.press_equations import structure
from mechopt.solvers.press.problem import (
    CUT_END,
    CUT_START,
    TWO_PI,
    Limit,
    Samples,
    Stall,
    Trace,
    belt_mode,
    belt_too_fast_per_revolution,
    casadi_failure,
    check_task,
    checked,
    dynamics_of,
    initial_state,
    march,
    nominal_speed_note,
    piece_by_time,
    refuse_neutral_speed,
    revolution,
    summarise,
)

STEPS_PER_REVOLUTION = 2500     # belt-mode steps per revolution steady_state takes on (1 kHz belt: ~3 s)
CHORD_STEPS = 4                 # warm start: Broyden steps from the last monodromy before a full Newton solve
LAST_ORBIT = BuildCache("press.periodic.last_orbit", 16, per_thread=True)   # per (structure, tol, samples): y0, Jacobian


def steady_state(task: PressDrive, *, tol: Tolerance = 1e-10, samples: Samples = 60,
                 max_iter: Annotated[int, Interval(ge=1, le=100)] = 30) -> Result:
    """The periodic steady motion (the paper's assumption: the whole cut happens in steady
    motion), found directly instead of integrating until transients die.

    Unknowns: the states at phi = 0 other than phi (belt twist, pulley and crank speeds); the
    revolution maps them, through three CVODES pieces in the crank angle (idle, cut, idle: the
    cut's ends are fixed angles there, so no event location is needed), to the states at
    phi = 2 pi. Newton's method, with CVODES sensitivities for the monodromy, makes the two equal
    (to 100 tol in every state). The build is the structure's (`problem.revolution`): a what-if
    with other numbers re-solves on it, warm-started from the last orbit of the same structure
    by chord steps with its monodromy, Broyden-updated from each step's secant (at most
    `CHORD_STEPS`, then a full Newton solve from the usual guess); `diagnostics["warm_start"]` says which.
    Assumes the crank keeps turning forward (omega > 0); a solution that violates it is FAILED.
    A belt far stiffer than the drive makes the CVODES sensitivities very expensive (1e4 times
    the KD2322 value: 25 s; 1e6: minutes, and Newton stalls at ~1e-7): past `STEPS_PER_REVOLUTION`
    steps of a tenth of the belt mode's period per revolution it returns LIMIT before any work;
    the rigid-belt model is that motion's limit (to 1e-7 rad: a test pins it with `events`).

    Parameters
    ----------
    tol : CVODES tolerance (relative and absolute); the periodicity residual is held to 100 tol.
    samples : outputs per piece (peaks, plots).  max_iter : Newton iterations.
    """
    check_task(task, steady_state, tol=tol, samples=samples, max_iter=max_iter)
    refuse_neutral_speed(task, "press.steady_state")
    clock = Clock()
    # Newton's CVODES sensitivities must follow the belt mode: minutes past ~2 kHz
    too_fast = belt_too_fast_per_revolution(task, STEPS_PER_REVOLUTION, "steady_state")
    if too_fast:
        hz, _ = belt_mode(task)
        return clock.result(Status.LIMIT, {"belt_mode_Hz": hz, "step_needed_s": 0.1 / hz},
                            too_fast + "; `events` integrates it")
    stall = stall_check(task)
    if stall is not None:           # no forward periodic motion can exist: say so before any work
        return clock.result(Status.INFEASIBLE, stall[0], stall[1], ("stall",))
    build = Clock()
    key = (structure(task), tol, samples)
    rev = revolution(*key)
    p = dynamics_of(task).p
    clock.build_s = build.elapsed()
    guess = np.delete(initial_state(task, "nominal")[:rev.n], task.state_names.index("phi_rad"))
    if task.motor:      # start near the motor's idle speed rather than the nominal one
        guess[[i for i, k in enumerate(np.delete(np.array(task.state_names), task.state_names.index("phi_rad")))
               if k.startswith("omega")]] = task.motor_sync_speed_rad_s / task.gear_ratio * 0.99
    guess_speed = float(guess[task.state_names.index("omega_rad_s") - 1])
    last, _ = LAST_ORBIT.get(key, dict)
    try:                # the re-integration of the found orbit can fail as well as the Newton solve
        warm = _chord(rev, last, p, tol) if last else None
        if warm is not None:
            solution, trace, iterations = warm
            converged = True
        else:
            solution, iterations, converged, jacobian = _newton(rev, guess, p, tol, max_iter)
            trace, _ = rev.trace(solution, p)
            if converged:
                last |= {"y": solution, "jacobian": jacobian}
        miss = float(np.max(np.abs(_periodicity(rev, trace, solution))))
    except (RuntimeError, np.linalg.LinAlgError) as exc:
        if isinstance(exc, MechoptError):
            raise
        status, message, diagnostics = casadi_failure(exc, "integrating a revolution inside the periodic Newton "
                                                           "solve: no periodic motion found")
        values, violated = {}, ()
        stalled = _stalls_from(task, guess, tol)
        if stalled is not None:
            status, violated = Status.INFEASIBLE, ("stall",)
            values = {"required_mean_torque_Nm": required_mean_torque_Nm(task),
                      "breakdown_torque_at_crank_Nm": breakdown_torque_at_crank_Nm(task),
                      "cut_work_J": cut_work_J(task)}
            message = (f"no periodic motion: started at the Newton guess (crank at {guess_speed:.4g} rad/s, the "
                       f"motor's idle speed), {stalled}; the motor could carry the mean load torque "
                       f"{values['required_mean_torque_Nm']:.4g} N m (breakdown {values['breakdown_torque_at_crank_Nm']:.4g}"
                       f" N m at the crank), but the flywheel cannot carry the cut ({values['cut_work_J']:.4g} J)")
        return clock.result(status, values, message, violated, diagnostics)
    status = Status.SOLVED if converged else Status.LIMIT
    window = (float(p[CUT_START]), float(p[CUT_END])) if task.cutting else None     # p holds the cut's angles
    values, diagnostics, arrays = summarise(task, trace, cut_angles=window)
    values["periodicity_residual"] = miss
    diagnostics |= {"newton_iterations": iterations, "initial_state": solution.tolist(),
                    "warm_start": warm is not None}
    how = (f"chord steps with the last orbit's monodromy (Broyden-updated), {iterations}" if warm
           else f"Newton shooting, {iterations}")
    if status is Status.SOLVED and diagnostics["min_omega_rad_s"] <= 0:
        status = Status.FAILED
        message = (f"no forward periodic motion: {how} iterations converged to an orbit on "
                   f"which the crank stops or turns back (min omega {diagnostics['min_omega_rad_s']:.3g} rad/s)")
    elif status is Status.SOLVED and miss > 1e3 * tol:
        status = Status.INACCURATE
        message = (f"not a periodic orbit to trust: {how} iterations left the "
                   f"periodicity residual {miss:.3g} > 1000 tol = {1e3 * tol:.3g}")
    elif status is Status.SOLVED:
        message = f"periodic orbit by {how} iterations, residual {miss:.3g}" + nominal_speed_note(task)
    else:               # never a message that reads like an answer
        message = (f"no periodic orbit found: Newton shooting stopped after {iterations} of max_iter={max_iter} "
                   f"iterations with periodicity residual {miss:.3g}")
    status, message, violated = checked(status, message, (), diagnostics)
    return clock.result(status, values, message, violated, diagnostics, arrays)


def _periodicity(rev, trace, y0):
    """y(2 pi) - y(0) over the states other than phi, from a revolution's trace."""
    iphi = rev.state_names.index("phi_rad")
    return np.delete(trace.x[-1][-1, :rev.n], iphi) - y0


def _newton(rev, y, p, tol, max_iter):
    """Newton on the periodicity residual from y: (y, iterations, converged, Jacobian at the last y).
    Converged when every state's residual is within 100 tol (as CasADi's rootfinder's abstol)."""
    y = np.asarray(y, dtype=float)
    for k in range(max_iter + 1):
        miss, jacobian = (np.asarray(v) for v in rev.residual(y, p))
        miss = miss.ravel()
        if not np.all(np.isfinite(miss)):
            raise np.linalg.LinAlgError(f"the periodicity residual is not finite after {k} Newton steps")
        if np.max(np.abs(miss)) <= 100 * tol or k == max_iter:
            return y, k, bool(np.max(np.abs(miss)) <= 100 * tol), jacobian
        y = y - np.linalg.solve(jacobian, miss)
    raise AssertionError("unreachable")


def _chord(rev, last, p, tol):
    """From the last orbit of this structure, quasi-Newton steps starting from its Jacobian (the
    monodromy minus I), each step's secant folded in by Broyden's update, so that a what-if far
    from the last orbit (a flywheel 50 % heavier: linear convergence at ~0.08 a step with the old
    Jacobian) converges superlinearly instead of falling back to the cold Newton solve: (y, trace,
    steps) once the residual is within 100 tol, or None (then a full Newton solve follows)."""
    y, jacobian, before = last["y"], np.array(last["jacobian"], dtype=float), None
    for k in range(CHORD_STEPS + 1):
        try:
            trace, _ = rev.trace(y, p)
        except RuntimeError as exc:        # CVODES gave up from this start: the cold solve decides
            if isinstance(exc, MechoptError):
                raise
            return None
        miss = _periodicity(rev, trace, y)
        if not np.all(np.isfinite(miss)):
            return None
        if np.max(np.abs(miss)) <= 100 * tol:
            last["y"] = y
            return y, trace, k
        if before is not None:          # Broyden: the Jacobian that maps the last step onto its change of miss
            step, change = y - before[0], miss - before[1]
            jacobian += np.outer(change - jacobian @ step, step) / (step @ step)
        before = (y, miss)
        y = y - np.linalg.solve(jacobian, miss)
    return None


def _stalls_from(task, guess, tol):
    """The stall message of `events` run for three revolutions from the Newton guess (phi = 0, the
    motor's idle speed: the fastest a periodic motion turns), or None if the crank keeps turning."""
    iphi = task.state_names.index("phi_rad")
    x = initial_state(task, "nominal")
    x[[i for i in range(len(task.state_names)) if i != iphi]] = guess
    speed = max(float(x[task.state_names.index("omega_rad_s")]), 1e-3)
    try:
        march(task, piece_by_time(task, tol, 8), Trace(), x, 3 * TWO_PI / speed, 0.02, 10_000)
    except Stall as stall:
        return str(stall)
    except (Limit, RuntimeError):
        return None
    return None
