"""The stop-impact solvers a scene names: frequencies, impact forces, the first rebound by any of
three methods with a cross-check, the amplitude law for the LP, and one operating point against
the limit (for maps)."""
import math
from typing import Literal

import numpy as np
from scipy.optimize import brentq

from mechopt.kit.errors import ModelError, SolverError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, Tolerance, check_settings
from mechopt.models.cam_follower import law_values
from mechopt.models.stop_impact import LeverStop, speed_tag
from mechopt.solvers.stop_impact.cam_follower import follow_cam, follow_cam_reference, follower_data
from mechopt.solvers.stop_impact.contact import simulate_contact
from mechopt.solvers.stop_impact.law import (
    RollerLeftCam,
    amplitude_law,
    approach_velocity_m_s,
    impact_at,
    rebound_amplitude_mm,
)
from mechopt.solvers.stop_impact.response import (
    closed_form_amplitude_m,
    closed_form_response,
    ode_amplitude_m,
    quadrature_amplitude_m,
)

__all__ = ["cam_dynamics", "impact_forces", "linearise_amplitude", "natural_frequencies", "operating_point", "rebound"]

AGREEMENT_REL = 1e-8            # the three methods must agree this well on every scene
CAM_AGREEMENT_REL = 1e-7        # CVODES (reltol 1e-10) and DOP853 (1e-12) on the approach velocity
HISTORY_POINTS = 513            # samples of a rebound history q(t) over the first rebound's window


def natural_frequencies(task: LeverStop) -> Result:
    """Reduced stiffness and natural frequencies of the lever moving (Fig. 5) and on the plate
    (Fig. 6), and the contact time tau = half the period on the plate."""
    clock = Clock()
    values = {"f_free_Hz": task.f_free_Hz, "f_stop_Hz": task.f_stop_Hz,
              "c_free_N_per_mm": task.c_free_N_per_m * 1e-3, "c_stop_N_per_mm": task.c_stop_N_per_m * 1e-3,
              "contact_time_s": task.contact_time_s}
    return clock.result(Status.SOLVED, values,
                        message="c = 3 E J_x / ((a + b) b^2), f = sqrt(c / m) / (2 pi)")


def impact_forces(task: LeverStop) -> Result:
    """Impact force F_ud = J_A omega_0 (1 + k) / (l tau) at each speed of `speeds_rpm`, with the
    impulse S_C = F tau and the approach velocity; `impact_force_N_<rpm>` etc."""
    task.need_effect("impact_pulse")
    _need_speeds(task)
    clock = Clock()
    values = {"contact_time_s": task.contact_time_s}
    table = {"speed_rpm": [], "impact_force_N": [], "impulse_Ns": [], "approach_velocity_m_s": []}
    for n in task.speeds_rpm:
        v0 = approach_velocity_m_s(task, n)
        F = float(task.impact_force_N(v0))
        values |= {f"impact_force_N_{speed_tag(n)}": F, f"impulse_Ns_{speed_tag(n)}": F * task.contact_time_s,
                   f"approach_velocity_m_s_{speed_tag(n)}": v0}
        for name, value in zip(table, (n, F, F * task.contact_time_s, v0)):
            table[name].append(value)            # the same, one row per speed (`--csv`)
    return clock.result(Status.SOLVED, values, message="tau = half the natural period on the plate", arrays=table)


def rebound(task: LeverStop, *, method: Literal["closed_form", "quadrature", "ode"] = "closed_form",
            cross_check: bool = True) -> Result:
    """First-rebound amplitude of eq. (2) at each speed of `speeds_rpm` and the phase angle
    `t_deg`: `rebound_mm_<rpm>`. With `cross_check` the other two methods run as well and must
    agree within 1e-8 relative (else INACCURATE), and the event-driven simulation reports how far
    the single-mass eq. (2) is from a contact that switches stiffness (`rebound_event_mm_<rpm>`).
    `arrays` hold each speed's history q(t) in closed form over the window of its first rebound
    (`t_s`, `q_mm_<rpm>`; one window: it depends on the plate alone, not on the speed).
    """
    check_settings(rebound, method=method)
    _need_speeds(task)
    task.need("t_deg")
    methods = {"closed_form": _by_closed_form, "quadrature": _by_quadrature, "ode": _by_ode}
    clock = Clock()
    values, diagnostics, status, notes = {}, {}, Status.SOLVED, []
    histories = {}
    for n in task.speeds_rpm:
        try:
            imp = impact_at(task, n)
        except RollerLeftCam as exc:
            return _without_cam(exc, values, clock)
        t_s = histories.setdefault("t_s", np.linspace(0.0, imp.window_s, HISTORY_POINTS))
        histories[f"q_mm_{speed_tag(n)}"] = closed_form_response(imp, t_s)[0] * 1e3
        runs = {name: methods[name](imp) for name in ([method] + [k for k in methods if k != method]
                                                      if cross_check else [method])}
        clock.build_s += sum(r[2] for r in runs.values())
        amp, own_status = runs[method][0], runs[method][1]
        if own_status is not Status.SOLVED or not math.isfinite(amp):
            return clock.result(Status.FAILED if own_status is Status.SOLVED else own_status, values,
                                message=f"{method}: {own_status.value} at {n:g} rpm, no amplitude reported",
                                diagnostics=diagnostics)
        values[f"rebound_mm_{speed_tag(n)}"] = amp * 1e3
        if cross_check:
            bad = [k for k, r in runs.items() if r[1] is not Status.SOLVED or not math.isfinite(r[0])]
            spread = max(abs(r[0] - amp) for k, r in runs.items() if k not in bad) / max(amp, 1e-300)
            diagnostics[f"methods_{speed_tag(n)}"] = {k: {"mm": r[0] * 1e3, "status": r[1].value} for k, r in runs.items()}
            values[f"methods_max_rel_diff_{speed_tag(n)}"] = spread
            if spread > AGREEMENT_REL or bad:
                status = Status.INACCURATE
                notes.append(f"{n:g} rpm: methods differ by {spread:.2e} relative"
                             + (f", {bad} not solved" if bad else ""))
            event_mm, contact_s, ev_status, ev_message = simulate_contact(task, n, v0_m_s=imp.v0_m_s)
            if ev_status is Status.SOLVED:
                values[f"rebound_event_mm_{speed_tag(n)}"] = event_mm
                values[f"contact_time_event_s_{speed_tag(n)}"] = contact_s
            diagnostics[f"event_driven_{speed_tag(n)}"] = ev_message
    values["contact_time_s"] = task.contact_time_s
    agreed = "closed form, quadrature and ODE agree within 1e-8" if cross_check else "no cross-check"
    message = f"{method}; " + ("; ".join(notes) if notes else agreed)
    return clock.result(status, values, message=message, diagnostics=diagnostics, arrays=histories)


def linearise_amplitude(task: LeverStop) -> Result:
    """The amplitude law for the LP: tangent of a(t) at `t_deg`, `speed_nominal_rpm`; the bound on
    t(3,7) that a <= `amplitude_limit_mm` gives, by the tangent and by the exact law (a falls
    with t: the exact bound is the root of a(t) = limit). Where the roller leaves its cam on the
    way (effect cam_drive) the answer is INFEASIBLE (violated `cam_contact`), the tangent kept.
    `arrays`: the exact a(t) at every t the root search evaluated, beside the tangent there."""
    task.need("amplitude_limit_mm")
    clock = Clock()
    limit = task.amplitude_limit_mm
    n = task.speed_nominal_rpm
    values = {}
    try:
        slope, intercept = amplitude_law(task)
        t_linear = (limit - intercept) / slope
        values = {"slope_mm_per_deg": slope, "intercept_mm": intercept, "t_3_7_min_deg": t_linear}
        seen = {}           # a(t) at every t the root search asked for: the law's curve, at no cost

        def exact(t):
            seen[float(t)] = float(rebound_amplitude_mm(task, n, t))
            return seen[float(t)] - limit
        lo, hi = _bracket(exact, task.t_deg, limit, n)
    except RollerLeftCam as exc:
        return _without_cam(exc, values, clock)
    t_exact = brentq(exact, lo, hi, xtol=1e-12, rtol=1e-14)
    values |= {"t_3_7_min_exact_deg": t_exact, "span_gain_deg": t_exact - t_linear,
               "amplitude_nominal_mm": float(rebound_amplitude_mm(task, n, task.t_deg))}
    t_deg = np.array(sorted(seen))
    exact_mm = np.array([seen[t] for t in t_deg])
    arrays = {"t_deg": t_deg, "amplitude_mm": exact_mm, "tangent_mm": intercept + slope * t_deg}    # t ascending
    return clock.result(Status.SOLVED, values, arrays=arrays,
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
    clock = Clock()
    n, t, limit = task.speed_nominal_rpm, task.t_deg, task.amplitude_limit_mm
    try:
        imp = impact_at(task, n)
    except RollerLeftCam as exc:
        return _without_cam(exc, {}, clock)
    amplitude_mm = float(rebound_amplitude_mm(task, n, t))
    ode_m, ode_status, clock.build_s = ode_amplitude_m(imp)
    values = {"rebound_mm": amplitude_mm, "margin_mm": limit - amplitude_mm,
              "approach_velocity_m_s": imp.v0_m_s, "contact_time_s": task.contact_time_s}
    if "impact_pulse" in task.effects:
        values["impact_force_N"] = float(task.impact_force_N(values["approach_velocity_m_s"]))
    t_s = np.linspace(0.0, imp.window_s, HISTORY_POINTS)
    history = {"t_s": t_s, "q_mm": closed_form_response(imp, t_s)[0] * 1e3}     # the rebound q(t)
    if ode_status is not Status.SOLVED:
        return clock.result(Status.INACCURATE, values, arrays=history,
                            message=f"the ODE cross-check gave {ode_status.value}: the law's "
                                    f"{amplitude_mm:.4g} mm is unconfirmed")
    spread = abs(ode_m * 1e3 - amplitude_mm) / max(amplitude_mm, 1e-300)
    values["methods_rel_diff"] = spread
    if spread > AGREEMENT_REL:
        return clock.result(Status.INACCURATE, values, arrays=history,
                            message=f"exact law and ODE differ by {spread:.2e} relative at {n:g} rpm, {t:g} deg")
    within = amplitude_mm <= limit
    return clock.result(Status.SOLVED if within else Status.INFEASIBLE, values, arrays=history,
                        violated=() if within else ("amplitude",),
                        message=f"{amplitude_mm:.4g} mm at {n:g} rpm, t = {t:g} deg: "
                                f"{'within' if within else 'above'} amplitude_limit_mm={limit:g}; "
                                f"the ODE agrees to {spread:.1e}")


def _without_cam(exc, values, clock: Clock) -> Result:
    """No rebound where the cam's rise fails: INFEASIBLE (violated cam_contact) when the roller
    leaves its cam, else the integrator's status; the values found so far are kept."""
    infeasible = exc.status is Status.INFEASIBLE
    return clock.result(exc.status, values, message=str(exc), violated=("cam_contact",) if infeasible else ())


def _bracket(excess, t_deg, limit, speed_rpm, factor=1.25, steps=40):
    """(lo, hi) around the root of a(t) = limit, grown geometrically from t_deg (a falls with t)."""
    lo = hi = t_deg
    try:
        if excess(t_deg) > 0:
            for _ in range(steps):
                hi = min(hi * factor, 359.0)
                if excess(hi) <= 0:
                    return lo, hi
                lo = hi
        else:
            for _ in range(steps):
                lo = lo / factor
                if excess(lo) >= 0:
                    return lo, hi
                hi = lo
    except RollerLeftCam as exc:        # the roller leaves its cam on the way: a status, for the caller
        if exc.status is Status.INFEASIBLE:
            raise
        raise ModelError(f"amplitude_limit_mm={limit}: no exact bound on t at {speed_rpm:g} rpm: {exc}",
                         key="amplitude_limit_mm") from None
    except SolverError as exc:          # an integrator's failure on the way: no exact bound there
        raise ModelError(f"amplitude_limit_mm={limit}: no exact bound on t at {speed_rpm:g} rpm: {exc}",
                         key="amplitude_limit_mm") from None
    raise ModelError(f"amplitude_limit_mm={limit}: a(t) at {speed_rpm:g} rpm does not cross it for t in "
                     f"({t_deg / factor**steps:g}, 359) deg", key="amplitude_limit_mm")


def _by_closed_form(imp):
    return closed_form_amplitude_m(imp)[0], Status.SOLVED, 0.0


def _by_quadrature(imp):
    return *quadrature_amplitude_m(imp), 0.0


def _by_ode(imp):
    return ode_amplitude_m(imp)


def _need_speeds(task):
    if not task.speeds_rpm:
        raise ModelError("speeds_rpm=[]: give the main-shaft speeds to report (structure table)", key="speeds_rpm")


def cam_dynamics(task: LeverStop, *, reltol: Tolerance = 1e-10,
                 points: Annotated[int, Interval(ge=11, le=100_000)] = 1001) -> Result:
    """The lift cam's rise with the elastic lever (paper 004, Fig. 4) at each speed of
    `speeds_rpm` and at `speed_nominal_rpm`: the approach velocity at the located contact with
    the plate (`approach_velocity_m_s`, and `_<rpm>`), the largest dynamic error of the
    displacement, velocity and acceleration analogues over the rise up to the contact, the rigid
    lever's (kinematic) approach velocity beside it, and the roller's least contact force.

    The nominal rise is checked by scipy's DOP853 with its own event location (within 1e-7
    relative, else INACCURATE). A roller that leaves its cam (contact force < 0) at any speed
    makes the answer INFEASIBLE (violated `cam_contact`), naming where and at which speed.
    """
    task.need("speed_nominal_rpm", "law")
    task.need_effect("cam_drive")
    clock = Clock()
    speeds = [task.speed_nominal_rpm] + [n for n in task.speeds_rpm if n != task.speed_nominal_rpm]
    values, left, arrays, rises = {}, [], {}, {}
    for n in speeds:
        rise = rises[n] = follow_cam(task, n, reltol=reltol, points=points)
        clock.build_s += rise.build_s
        if rise.status not in (Status.SOLVED, Status.INFEASIBLE):
            return clock.result(rise.status, values, message=f"{n:g} rpm: {rise.message}")
        if rise.status is Status.INFEASIBLE:
            left.append(rise.message)
        suffix = "" if n == task.speed_nominal_rpm else f"_{speed_tag(n)}"
        values[f"approach_velocity_m_s{suffix}"] = rise.approach_velocity_m_s
        values[f"dynamic_error_mm{suffix}"] = rise.dynamic_error_mm
        values[f"min_contact_force_N{suffix}"] = rise.min_contact_force_N
        if task.closure == "groove":        # N < 0 a crossover to the other wall: where, how many, how hard
            values |= _crossover_values(rise, suffix)
        if rise.contact_xi is not None and suffix:
            values[f"contact_angle_deg{suffix}"] = rise.contact_xi * task.t_deg
        if n == task.speed_nominal_rpm:
            nominal = rise
    rad = math.radians(task.t_deg)
    S, dS, ddS = law_values(task.law, nominal.xi)
    H_mm = task.stroke_mm
    values |= {"velocity_analogue_error_mm_per_rad": float(np.max(np.abs(nominal.dX - dS))) * H_mm / rad,
               "acceleration_analogue_error_mm_per_rad2": float(np.max(np.abs(nominal.ddX - ddS))) * H_mm / rad**2,
               "approach_velocity_rigid_m_s": _rigid_approach_m_s(task, task.speed_nominal_rpm)}
    if nominal.contact_xi is not None:
        values["contact_angle_deg"] = nominal.contact_xi * task.t_deg
    arrays = {"phi_deg": nominal.xi * task.t_deg, "x_mm": nominal.X * H_mm, "s_mm": S * H_mm,
              "dx_dphi_mm_per_rad": nominal.dX * H_mm / rad, "d2x_dphi2_mm_per_rad2": nominal.ddX * H_mm / rad**2,
              "ds_dphi_mm_per_rad": dS * H_mm / rad, "d2s_dphi2_mm_per_rad2": ddS * H_mm / rad**2}
    # every other speed's rise on the nominal's angles (one table for --csv; NaN past its own end):
    # (interpolated: at the grid points of xi the rises share, the samples are the rise's own)
    for n, rise in rises.items():
        if n != task.speed_nominal_rpm:
            for name, series, scale in (("x_mm", rise.X, H_mm), ("dx_dphi_mm_per_rad", rise.dX, H_mm / rad),
                                        ("d2x_dphi2_mm_per_rad2", rise.ddX, H_mm / rad**2)):
                arrays[f"{name}_{speed_tag(n)}"] = np.interp(nominal.xi, rise.xi, series * scale, right=np.nan)
    ref_xi, ref_v0, ref_status = follow_cam_reference(task, task.speed_nominal_rpm)
    spread = abs(ref_v0 - nominal.approach_velocity_m_s) / max(abs(ref_v0), 1e-300)
    values["reference_rel_diff"] = spread
    if left:
        return clock.result(Status.INFEASIBLE, values, violated=("cam_contact",), message="; ".join(left),
                            arrays=arrays)
    if ref_status is not Status.SOLVED or (ref_xi is None) != (nominal.contact_xi is None) or spread > CAM_AGREEMENT_REL:
        return clock.result(Status.INACCURATE, values, arrays=arrays,
                            message=f"CVODES and DOP853 differ on the approach velocity by {spread:.2e} relative")
    return clock.result(Status.SOLVED, values, arrays=arrays,
                        message=f"{task.law} rise, {nominal.message} at {nominal.contact_xi * task.t_deg:.4f} deg; "
                                f"DOP853 agrees to {spread:.1e}" if nominal.contact_xi is not None else nominal.message)


def _crossover_values(rise, suffix):
    """A grooved cam's crossovers in one rise (solvers/stop_impact/crossover.py): their count, the
    first's cam angle [deg] and the largest impact speed across the backlash [m/s]."""
    out = {f"crossovers{suffix}": float(len(rise.crossovers))}
    if rise.crossovers:
        out[f"crossover_angle_deg{suffix}"] = rise.crossovers[0].angle_deg(rise.t_deg)
    speeds = [c.impact_m_s for c in rise.crossovers if c.impact_m_s is not None]
    if speeds:
        out[f"crossover_impact_max_m_s{suffix}"] = max(speeds)
    return out


def _rigid_approach_m_s(task, speed_rpm):
    """The approach velocity of a rigid lever: H S'(xi) / T where S(xi) = 1 - preload / H (0 at the
    rise's end when there is no preload)."""
    _, _, H, target, T = follower_data(task, speed_rpm, task.t_deg)
    if target >= 1.0:
        return 0.0
    xi = brentq(lambda x: law_values(task.law, x)[0][0] - target, 0.0, 1.0, xtol=1e-15)
    return float(law_values(task.law, xi)[1][0]) * H / T
