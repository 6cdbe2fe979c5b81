"""The machine's speed co-designed with the lift cam's law.

The lift's operation (3,7) is limited by the lever's rebound, and the rebound by the law. A law
of fixed shape S(xi) makes the rebound a function of n / t alone (the rise in its own time
depends on lambda = omega t / Omega only), so one synthesised law gives the lift a bound
t(3,7) >= n / r*: the same linear arc the graph engine already takes for the cycloid.

1. The law: `synthesise_law` (solvers/stop_impact/synthesis.py), objective least_phase, at the
   machine's reference speed n_ref = speed_rpm over the band [band_low_rpm, n_ref]. At a fixed t
   that band is the band of n / t the engine's exact bound is checked over (a <= limit for every
   t in [T, scan_to_deg] at n_ref means n / t in [n_ref / scan_to_deg, n_ref / T]): band_low_rpm
   = n_ref T / scan_to_deg covers it for T down to the law's t_min.
2. The machine re-planned: `max_machine_speed` with the lever's law replaced (the engine's own
   highest-speed solver, its exact bound by the chain, the limiting cycle named).
3. The loop closed: the chain (CVODES rise, eq. (2)) at the re-planned t(3,7) and speed must keep
   the limit; and the same machine with the cycloid (`max_machine_speed` on the task as given) is
   the baseline. The gain is reported whatever it is.
4. Robust (`robust`): the law synthesised on a box of the lever's uncertain inputs (frequency
   factor, damping, a speed margin: solvers/stop_impact/lever_box.py); the re-planned machine's
   worst rebound over that box is reported. The engine re-plans on the nominal lever's exact
   bound, so it may take back at t(3,7) the margin the law bought: the value says how much.
"""
import dataclasses

from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval
from mechopt.models.loom import Cyclogram
from mechopt.solvers.loom.speed import max_machine_speed
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox, takes_box
from mechopt.solvers.stop_impact.synthesis import box_values, law_of, linear_lever, synthesise_law

__all__ = ["codesign_machine_speed"]

BOX_STEP_RPM = 5.0          # the box's speeds at the re-planned t(3,7): every 5 rpm, as the synthesis' dense check


@takes_box
def codesign_machine_speed(task: Cyclogram, *, coefficients: Annotated[int, Interval(ge=2, le=2000)] = 40,
                           band_low_rpm: Annotated[float, Interval(gt=0, le=1e5)] = 180.0,
                           sample_speeds: Annotated[int, Interval(ge=1, le=50)] = 5,
                           max_acceleration_mm_per_rad2: Annotated[float, Interval(ge=0)] = 0.0,
                           phase_from_deg: Annotated[float, Interval(gt=0, lt=360)] = 20.0,
                           phase_to_deg: Annotated[float, Interval(gt=0, lt=360)] = 45.0,
                           phase_tol_deg: Annotated[float, Interval(gt=0, le=1)] = 0.05,
                           scan_to_deg: Annotated[float, Interval(gt=0.0, le=360.0)] = 60.0,
                           scan_step_deg: Annotated[float, Interval(ge=1e-3, le=10.0)] = 0.25,
                           box: LeverBox | None = None,
                           robust: bool = False) -> Result:
    """The machine's highest speed with the lift's law synthesised (module docstring), against the
    same machine with its lever's own law (`speed_baseline_rpm`).

    Parameters
    ----------
    task : the machine (loom.Cyclogram) with its lever table (effect stop_vibration) and its
        amplitude_limit_mm; speed_rpm the reference speed n_ref [rpm].
    coefficients, sample_speeds, max_acceleration_mm_per_rad2, phase_from_deg, phase_to_deg,
        phase_tol_deg : the synthesis' (`synthesise_law`); the band is [band_low_rpm, speed_rpm].
    scan_to_deg, scan_step_deg : the engine's exact-bound scan (`max_machine_speed`).
    box, robust : the lever's box (`synthesise_law`; a scene's box_frequency_low ... box_grid): with robust the law
        is synthesised on the whole box; given, the chain's worst rebound over the box at the
        re-planned t(3,7) over [band_low_rpm, speed] (the margin added) is `rebound_worst_box_mm`.

    Values: speed_rpm, speed_baseline_rpm, gain_percent, t_min_synthesized_deg (at n_ref),
    t_3_7_deg and the chain's rebound there (rebound_chain_mm); diagnostics: the limiting cycle
    and constraint of both plans.
    """
    if task.lever is None or task.amplitude_limit_mm is None or task.speed_rpm is None:
        raise ModelError("codesign: needs the lever's table [structure.lever], amplitude_limit_mm and speed_rpm",
                         key="lever")
    if band_low_rpm >= task.speed_rpm:
        raise SettingError(f"band_low_rpm={band_low_rpm} must be below speed_rpm={task.speed_rpm} (the band's top)",
                           key="band_low_rpm")
    box = box or LeverBox()
    clock = Clock()
    speed_settings = dict(scan_to_deg=scan_to_deg, scan_step_deg=scan_step_deg)
    baseline = max_machine_speed(task, **speed_settings)
    if baseline.status is not Status.SOLVED:
        return clock.result(baseline.status, {}, message=f"the baseline machine: {baseline.message}",
                            violated=baseline.violated)
    lever = dataclasses.replace(task.lever_model, amplitude_limit_mm=task.amplitude_limit_mm,
                                speed_nominal_rpm=task.speed_rpm)
    synthesis = Clock()
    law_run = synthesise_law(lever, objective="least_phase", coefficients=coefficients, band_low_rpm=band_low_rpm,
                             band_high_rpm=task.speed_rpm, sample_speeds=sample_speeds,
                             max_acceleration_mm_per_rad2=max_acceleration_mm_per_rad2,
                             phase_from_deg=phase_from_deg, phase_to_deg=phase_to_deg, phase_tol_deg=phase_tol_deg,
                             compare=False, robust=robust, box=box)
    values = {"speed_baseline_rpm": baseline.values["max_speed_rpm"]}
    took = {"synthesis_s": synthesis.elapsed()}                     # timings go to diagnostics: values are results
    if law_run.status is not Status.SOLVED:
        return clock.result(law_run.status, values, message=f"the lift's law: {law_run.message}",
                            violated=law_run.violated)
    law = law_of(law_run)
    values["t_min_synthesized_deg"] = law_run.values["t_min_synthesized_deg"]
    replan = Clock()
    designed = dataclasses.replace(task, lever={**task.lever, "law": law})
    plan = max_machine_speed(designed, **speed_settings)
    took["replan_s"] = replan.elapsed()
    if plan.status is not Status.SOLVED:
        return clock.result(plan.status, values, message=f"the re-planned machine: {plan.message}",
                            violated=plan.violated)
    n, t37 = plan.values["max_speed_rpm"], plan.values["t_3_7_deg"]
    chain = float(rebound_amplitude_mm(designed.lever_model, n, t37))     # the loop closed by the chain
    values |= {"speed_rpm": n, "gain_percent": 100.0 * (n / values["speed_baseline_rpm"] - 1.0), "t_3_7_deg": t37,
               "t_3_7_baseline_deg": baseline.values["t_3_7_deg"], "rebound_chain_mm": chain}
    values |= {k: v for k, v in plan.values.items()
               if (k.startswith(("p_", "t_", "sigma_", "amplitude_")) or k == "span_deg") and k not in values}
    diagnostics = {}
    if not box.trivial:     # the machine as re-planned, on every lever of the box's grid
        diagnostics = box_values(designed.lever_model, law, t37, (band_low_rpm, n), box, BOX_STEP_RPM,
                                 linear_lever(coefficients, 2), values, "")
    status = Status.SOLVED if chain <= task.amplitude_limit_mm * (1 + 1e-6) else Status.INACCURATE
    limiting = plan.diagnostics.get("limiting_constraint", "-")
    lift = _lift_bound(plan) or "no speed bound (its angle floor)"
    message = (f"{n:.6g} rpm with the synthesised lift law against {values['speed_baseline_rpm']:.6g} rpm with "
               f"{task.lever_model.law} ({values['gain_percent']:+.2f} %); the lift's t(3,7) now set by {lift} "
               f"(baseline: {_lift_bound(baseline) or '-'}); limiting: {limiting} "
               f"(baseline {baseline.diagnostics.get('limiting_constraint', '-')}); the chain at t(3,7) = {t37:.4g} deg: "
               f"{chain:.4g} mm")
    diagnostics |= {"limiting_constraint": limiting, "limiting_group": plan.diagnostics.get("limiting_group"),
                   "critical_chain": plan.diagnostics.get("critical_chain"),
                   "critical_ops": plan.diagnostics.get("critical_ops", []),
                   "float_deg": plan.diagnostics.get("float_deg", {}),
                   "baseline_limiting_constraint": baseline.diagnostics.get("limiting_constraint"),
                   "lift_bound": lift, "timing": took, "baseline_lift_bound": _lift_bound(baseline),
                   "windows_given_up": law_run.diagnostics.get("windows_given_up", 0),
                   "limiting": plan.diagnostics.get("limiting"),
                   "law": str(law), "law_knots": list(law.knots), "law_coefficients": list(law.coefficients)}
    arrays = dict(law_run.arrays) | plan.arrays
    return clock.result(status, values, message=message, diagnostics=diagnostics, arrays=arrays,
                        warnings=plan.warnings)


def _lift_bound(plan):
    """Which speed bound sets the lift's operation (3,7) on the plan's critical chain, if one does."""
    for row in plan.diagnostics.get("limiting") or ():
        if row["constraint"].endswith("[3->7]"):
            return row["constraint"]
    return None
