"""The paper's method for the press: fixed-step classical Runge-Kutta on the switched equations,
with its step refinement (halve until two runs agree); the baseline. It steps across the jump at
the end of the cut, so it is first order there."""

import casadi as ca
import numpy as np

from mechopt.kit.cache import memoised
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, NonNegative, Positive
from mechopt.models.press import PressDrive
from mechopt.solvers.press.problem import (
    Duration,
    Start,
    Trace,
    belt_mode,
    belt_too_fast,
    check_task,
    checked,
    dynamics_of,
    initial_state,
    paper_U,
    stable_step_s,
    summarise,
)

MAX_STEPS = 500_000         # per run (refinement included): ~200 MB of samples and outputs, seconds


@memoised(maxsize=64)
def _rk4_steps(task: PressDrive, step_s: float, count: int) -> ca.Function:
    f = dynamics_of(task).switched
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
        raise SettingError(f"step_s={step_s} does not divide duration_s={duration_s} into whole steps", key="step_s")
    x0 = initial_state(task, start)
    xs = np.asarray(_rk4_steps(task, step_s, count)(x0)).T
    trace = Trace()
    dyn = dynamics_of(task)
    xs = np.vstack([x0, xs])
    t = np.arange(count + 1) * step_s
    # the mode each sample saw, as the paper's U and sign(omega) evaluate it (for the outputs)
    u = paper_U(task, xs)
    trace.add(t, xs, np.zeros(3))
    trace.mode = [np.column_stack([u, np.sign(xs[:, task.state_names.index("omega_rad_s")]), np.zeros_like(u)])]
    on = np.flatnonzero(np.diff(u) > 0) + 1
    off = np.flatnonzero(np.diff(u) < 0) + 1
    iphi = task.state_names.index("phi_rad")
    trace.events = sorted([("cut_start", t[i], xs[i, iphi]) for i in on]
                          + [("cut_end", t[i], xs[i, iphi]) for i in off], key=lambda e: e[1])
    return trace, dyn


def _first_stop(task, trace):
    """(t, phi, in the cut) of the first sample where the crank, having turned, stops or turns
    back (omega <= 0); None if it keeps turning."""
    w = trace.x[0][:, task.state_names.index("omega_rad_s")]
    turned = np.maximum.accumulate(w) > 0
    hits = np.flatnonzero((w <= 0) & np.r_[False, turned[:-1]])
    if not hits.size:
        return None
    k = int(hits[0])
    return float(trace.t[0][k]), float(trace.x[0][k, task.state_names.index("phi_rad")]), bool(trace.mode[0][k - 1, 0])


def rk4(task: PressDrive, *, step_s: Positive = 1e-4, duration_s: Duration = 1.0, start: Start = "nominal",
        refine_tol_rad: NonNegative = 1e-6, max_halvings: Annotated[int, Interval(ge=0, le=20)] = 4) -> Result:
    """Fixed-step RK4 on eqs. (2) with the paper's switching function U (Sec. "DYNAM").

    The step is halved (`max_halvings` at most) until two successive runs agree on the final
    crank angle within `refine_tol_rad` (the paper's "refinement of the integration step");
    0 disables refining.
    U and sign(omega) are evaluated at every stage, so the step that contains the jump at the
    end of the cut is only first-order accurate: the method's error is O(h), not O(h^4).

    Parameters
    ----------
    step_s : first step [s]; must divide `duration_s` into at most `MAX_STEPS` steps, and lie
        within RK4's stability limit for the belt mode (else FAILED at once, saying so).
    duration_s : simulated time [s].
    start : "nominal" (turning at the nominal speed) or "rest".
    Returns a Result: SOLVED, or INACCURATE when refinement did not reach `refine_tol_rad`;
    INFEASIBLE with violated ("stall",) when the crank, having turned, stops (in the cut or not).
    """
    check_task(task, rk4, step_s=step_s, duration_s=duration_s, start=start, refine_tol_rad=refine_tol_rad,
               max_halvings=max_halvings)
    if duration_s / step_s > MAX_STEPS:
        raise SettingError(f"step_s={step_s} with duration_s={duration_s} means {duration_s / step_s:.3g} RK4 steps; "
                         f"allowed at most {MAX_STEPS} (step_s >= {duration_s / MAX_STEPS:.3g} s)", key="step_s")
    clock = Clock()
    hz, eigenvalue = belt_mode(task)
    stable = stable_step_s(eigenvalue)
    if step_s > stable:         # it would diverge: say why before integrating
        return clock.result(Status.FAILED, {"belt_mode_Hz": hz, "step_needed_s": stable, "step_s": step_s},
                            belt_too_fast(task, stable, float("inf"), 0, f"RK4 at step_s={step_s:g}",
                                          why=" (RK4's stability limit)")
                            + f"; reduce step_s below {stable:.3g} s or use events")
    trace, _ = _rk4_trace(task, step_s, duration_s, start)
    iphi = task.state_names.index("phi_rad")
    change, halvings, h, capped = np.inf, 0, step_s, ""
    while refine_tol_rad > 0 and halvings < max_halvings and np.all(np.isfinite(trace.x[0])):
        if 2 * duration_s / h > MAX_STEPS:
            capped = f"; refining stopped: the next halving needs {2 * duration_s / h:.3g} steps > {MAX_STEPS}"
            break
        finer, _ = _rk4_trace(task, h / 2, duration_s, start)
        change = abs(finer.x[0][-1, iphi] - trace.x[0][-1, iphi])
        trace, h, halvings = finer, h / 2, halvings + 1
        if change <= refine_tol_rad:
            break
    if not np.all(np.isfinite(trace.x[0])):     # explicit RK4 beyond its stability limit: say so, no NaN
        return clock.result(Status.FAILED, {"step_s": h},
                            message=f"RK4 diverged at step {h:.3g} s: the step exceeds the stability limit of the "
                                    f"stiffest mode (the belt); reduce step_s or use events")
    values, diagnostics, arrays = summarise(task, trace)
    values["step_s"] = h
    diagnostics |= {"halvings": halvings, "last_change_rad": float(change) if np.isfinite(change) else None}
    ok = refine_tol_rad <= 0 or change <= refine_tol_rad
    diagnostics["switches_stepped_over"] = True      # fixed steps: first order across the jump
    stop = _first_stop(task, trace)
    if stop is not None:
        t_stop, phi_stop, in_cut = stop
        where = f"crank angle {np.degrees(phi_stop % (2 * np.pi)):.3f} deg, t = {t_stop:.6g} s"
        message = (f"the press stalls in the cut at {where}: the flywheel and motor cannot supply the cutting work"
                   if in_cut else f"the crank stops at {where}: the drive cannot keep it turning")
        status, message, violated = checked(Status.INFEASIBLE, message, ("stall",), diagnostics)
        return clock.result(status, values, message, violated, diagnostics, arrays)
    status, message, violated = checked(Status.SOLVED if ok else Status.INACCURATE,
                                         f"RK4, step {h:.3g} s after {halvings} halvings; fixed steps cross "
                                         "the jump at the end of the cut and the friction sign change "
                                         "(first order there: the paper's method as published)"
                                         + ("" if ok else f"; last halving still moved phi by {change:.3g} rad > "
                                                          f"{refine_tol_rad:g}{capped}"), (), diagnostics)
    return clock.result(status, values, message, violated, diagnostics, arrays)
