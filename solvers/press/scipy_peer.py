"""The press by scipy's solve_ivp (Radau, LSODA, DOP853, RK45, BDF), with or without event
location: the peer a user would reach for, and the independent reference."""
from typing import Literal

import casadi as ca
import numpy as np
from scipy.integrate import DOP853, RK45, solve_ivp

from mechopt.kit.result import Clock, Result, Status, from_ivp
from mechopt.kit.settings import NonNegative, Tolerance
from mechopt.models.press import PressDrive
from mechopt.solvers.press.problem import (
    TWO_PI,
    Duration,
    Trace,
    angle_events,
    belt_mode,
    belt_too_fast,
    check_task,
    checked,
    dynamics_of,
    initial_state,
    mode_at,
    paper_U,
    refuse_work,
    stable_step_s,
    summarise,
    top_speed_rad_s,
)

MAX_REVOLUTIONS = 100        # solve_ivp calls a Python right-hand side: ~0.25 s per revolution (Radau)
MAX_STEPS = 20_000           # steps an explicit method may need (~10 s)
EXPLICIT = {"RK45": (RK45.A, RK45.B), "DOP853": (DOP853.A, DOP853.B)}    # Butcher tableaux: stability limit


def ivp(task: PressDrive, *, method: Literal["Radau", "LSODA", "DOP853", "RK45", "BDF"] = "Radau",
        rtol: Tolerance = 1e-8, atol: Tolerance = 1e-10, duration_s: Duration = 1.0, locate_events: bool = True,
        max_step_s: NonNegative = 0.0) -> Result:
    """scipy's solve_ivp from the nominal state, the peer a user would reach for.

    With `locate_events`, each smooth piece ends at a terminal event (the next cut start, cut
    end or revolution angle) and the integration restarts in the new mode, as `events` does.
    Without it the paper's switched right-hand side is integrated in one go: at loose tolerance
    and with no `max_step_s` (0 = unbounded) the adaptive step can jump over the whole cut, and
    `values["cuts"]` then counts fewer cuts than revolutions (the test of a missed cut).
    Friction sticking is not handled here (the crank must keep turning). Refused before work:
    more than `MAX_REVOLUTIONS`, or more than `MAX_STEPS` steps (`max_step_s`, or an explicit
    method's stability limit for the belt mode: then LIMIT, saying so).
    """
    check_task(task, ivp, method=method, rtol=rtol, atol=atol, duration_s=duration_s, locate_events=locate_events,
               max_step_s=max_step_s)
    per_s = top_speed_rad_s(task) / TWO_PI
    refuse_work("duration_s", duration_s, duration_s * per_s, MAX_REVOLUTIONS, "revolutions (~0.25 s each with "
                "a Python right-hand side)", f"duration_s <= {MAX_REVOLUTIONS / per_s:.4g} s; `events` goes further")
    if max_step_s > 0:
        refuse_work("max_step_s", max_step_s, duration_s / max_step_s, MAX_STEPS, "steps",
                    f"max_step_s >= {duration_s / MAX_STEPS:.3g} s over duration_s={duration_s:g}, or 0")
    clock = Clock()
    if method in EXPLICIT:
        hz, eigenvalue = belt_mode(task)
        stable = stable_step_s(eigenvalue, EXPLICIT[method])
        too_fast = belt_too_fast(task, stable, duration_s / stable, MAX_STEPS, method,
                                 why=f" ({method}'s stability limit)", over=f" over duration_s={duration_s:g}")
        if too_fast:
            return clock.result(Status.LIMIT, {"belt_mode_Hz": hz, "step_needed_s": stable},
                                too_fast + "; Radau, LSODA or `events` integrate it")
    dyn = dynamics_of(task)
    iphi, iw = task.state_names.index("phi_rad"), task.state_names.index("omega_rad_s")
    x = initial_state(task, "nominal")
    x_sym, m_sym = ca.SX.sym("x", dyn.rhs.size1_in(0)), ca.SX.sym("m", 3)
    jac = ca.Function("rhs_jacobian", [x_sym, m_sym], [ca.jacobian(dyn.rhs(x_sym, m_sym), x_sym)])
    clock.built()           # the dynamics and the Jacobian's function
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
            trace.mode = [np.column_stack([paper_U(task, sol.y.T), np.ones(sol.t.size), np.zeros(sol.t.size)])]
        values, diagnostics, arrays = summarise(task, trace)
        diagnostics["rhs_calls"] = int(sol.nfev)
        diagnostics["switches_stepped_over"] = bool(task.cutting or "friction" in task.effects)
        if status is Status.SOLVED and diagnostics["switches_stepped_over"]:
            # the cut's jump and sign(omega) lie inside steps: the error there is uncontrolled
            status = Status.INACCURATE
        status, message, violated = checked(status, sol.message + (
            "; switched right-hand side integrated without event location: the cut's jump and the "
            "friction sign change were stepped over" if diagnostics["switches_stepped_over"] else ""), (), diagnostics)
        return clock.result(status, values, message, violated, diagnostics, arrays)
    mode = mode_at(task, dyn, x, 1.0)
    trace.add(t, x, mode)
    status, message, violated = Status.SOLVED, "", ()
    while t < duration_s * (1 - 1e-14):
        target, kind = angle_events(task, x[iphi])
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
            where = f"crank angle {np.degrees(x[iphi] % TWO_PI):.3f} deg, t = {t:.6g} s"
            status, violated = Status.INFEASIBLE, ("stall",)
            message = (f"the press stalls in the cut at {where}: the flywheel and motor cannot supply the cutting work"
                       if mode[0] > 0 else f"the crank stopped at {where} (what follows, friction sticking, is not "
                                           f"handled by ivp: `events` is)")
            break
        if sol.status == 1:
            trace.events.append((kind, t, float(target)))
            x[iphi] = target
            mode = mode_at(task, dyn, x, 1.0)
    values, diagnostics, arrays = summarise(task, trace)
    diagnostics["rhs_calls"] = int(calls)
    status, message, violated = checked(status, message or f"solve_ivp {method}", violated, diagnostics)
    return clock.result(status, values, message, violated, diagnostics, arrays)
