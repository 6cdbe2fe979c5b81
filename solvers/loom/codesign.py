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
   the limit; and the same machine with its lever's own law (`max_machine_speed` on the task as
   given, on the same box) is the baseline. The gain is reported whatever it is.
4. The box (`box`, `robust`): with robust the law is synthesised on a box of the lever's uncertain
   inputs (frequency factor, damping, a speed margin: solvers/stop_impact/lever_box.py). Given a
   box, both machines are planned on it: the lift's bound is the largest over the box's levers at
   the speed raised by the margin (`box_amplitude_bound`), so the highest speed is the least over
   the levers of each lever's highest speed; the chain's worst rebound over the box's grid at the
   re-planned t(3,7) (`rebound_worst_box_mm`) must keep the limit too.
5. The lift cam's contact stress (`lift_stress`). The machine's stress model sigma = sigma_ref
   t_ref / t is calibrated for the lever's own law (models/loom.py). Hertz line contact gives
   sigma ~ sqrt(F) and the inertial force F ~ Ca / t^2 (Ca = max |S''| of the unit rise), so a law
   of another shape scales sigma_ref by sqrt(Ca_law / Ca_own) ("law_shape": sqrt(4.78 / 6.28) =
   0.872 for loom/machine-speed-codesign's law against the cycloid). Assumed: the closure force's constant
   part (the groove's 1500 N holds the roller whatever the law) and the change of the profile's
   curvature with the law are ignored. "given" keeps the model as calibrated, blind to the law's
   shape. The machine is planned under both readings (speed_stress_law_shape_rpm,
   speed_stress_given_rpm); speed_rpm is the chosen one's.
"""
import dataclasses
import math
from typing import Literal

import numpy as np

from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, check_settings
from mechopt.models.cam_laws import law as library_law
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram.speed import max_machine_speed
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox, takes_box
from mechopt.solvers.stop_impact.synthesis import box_values, law_of, linear_lever, synthesise_law

__all__ = ["codesign_machine_speed"]

BOX_STEP_RPM = 5.0          # the box's speeds at the re-planned t(3,7): every 5 rpm, as the synthesis' dense check
PEAK_GRID = 200001          # xi points for a spline's max |S''|: its error ~ h^2 max|S''''| / 8, below 1e-8 here
READINGS = ("law_shape", "given")


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
                           robust: bool = False,
                           lift_stress: Literal["law_shape", "given"] = "law_shape") -> Result:
    """The machine's highest speed with the lift's law synthesised (module docstring), against the
    same machine with its lever's own law (`speed_baseline_rpm`).

    Parameters
    ----------
    task : the machine (loom.Cyclogram) with its lever table (effect stop_vibration) and its
        amplitude_limit_mm; speed_rpm the reference speed n_ref [rpm].
    coefficients, sample_speeds, max_acceleration_mm_per_rad2, phase_from_deg, phase_to_deg,
        phase_tol_deg : the synthesis' (`synthesise_law`); the band is [band_low_rpm, speed_rpm].
    scan_to_deg, scan_step_deg : the engine's exact-bound scan (`max_machine_speed`).
    box, robust : the lever's box (`synthesise_law`; a scene's box_frequency_low ... box_grid): with
        robust the law is synthesised on the whole box; given, both machines are planned on it
        (module docstring, 4.) and the chain's worst rebound over the box's grid at the re-planned
        t(3,7) over [band_low_rpm, speed] (the margin added) is `rebound_worst_box_mm`.
    lift_stress : the lift cam's stress reading (module docstring, 5.): "law_shape" or "given".

    Values: speed_rpm, speed_baseline_rpm, gain_percent, t_min_synthesized_deg (at n_ref),
    t_3_7_deg and the chain's rebound there (rebound_chain_mm); under both stress readings
    speed_stress_<reading>_rpm and t_3_7_stress_<reading>_deg; stress_scale_lift = sqrt(ca_law /
    ca_own). Diagnostics: the limiting cycle and constraint of both plans, the bound that sets the
    lift's t(3,7) (lift_bound), with a box the lever and speed the lift's bound binds on
    (box_binding). SOLVED when the chain keeps the limit at t(3,7) on the nominal lever and, given
    a box, on its grid; INACCURATE otherwise (the message says where).
    """
    check_settings(codesign_machine_speed, lift_stress=lift_stress)
    if task.lever is None or task.amplitude_limit_mm is None or task.speed_rpm is None:
        raise ModelError("codesign: needs the lever's table [structure.lever], amplitude_limit_mm and speed_rpm",
                         key="lever")
    if band_low_rpm >= task.speed_rpm:
        raise SettingError(f"band_low_rpm={band_low_rpm} must be below speed_rpm={task.speed_rpm} (the band's top)",
                           key="band_low_rpm")
    box = box or LeverBox()
    clock = Clock()
    speed_settings = dict(scan_to_deg=scan_to_deg, scan_step_deg=scan_step_deg, box=box)
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
    scale, peaks = _stress_scale(task, law)
    machines = {reading: _with_lift_stress(dataclasses.replace(task, lever={**task.lever, "law": law}),
                                           scale if reading == "law_shape" else 1.0) for reading in READINGS}
    plans = {reading: max_machine_speed(machine, **speed_settings) for reading, machine in machines.items()}
    took["replan_s"] = replan.elapsed()
    for reading, each in plans.items():
        if each.status is not Status.SOLVED:
            return clock.result(each.status, values, message=f"the re-planned machine ({reading} stress): "
                                f"{each.message}", violated=each.violated)
        values[f"speed_stress_{reading}_rpm"] = each.values["max_speed_rpm"]
        values[f"t_3_7_stress_{reading}_deg"] = each.values["t_3_7_deg"]
    values |= {"stress_scale_lift": scale} | peaks
    plan, designed = plans[lift_stress], machines[lift_stress]
    n, t37 = plan.values["max_speed_rpm"], plan.values["t_3_7_deg"]
    chain = float(rebound_amplitude_mm(designed.lever_model, n, t37))     # the loop closed by the chain
    values |= {"speed_rpm": n, "gain_percent": 100.0 * (n / values["speed_baseline_rpm"] - 1.0), "t_3_7_deg": t37,
               "t_3_7_baseline_deg": baseline.values["t_3_7_deg"], "rebound_chain_mm": chain}
    values |= {k: v for k, v in plan.values.items()
               if (k.startswith(("p_", "t_", "sigma_", "amplitude_")) or k == "span_deg") and k not in values}
    diagnostics, held = {}, chain <= task.amplitude_limit_mm * (1 + 1e-6)
    if not box.trivial:     # the machine as re-planned, on every lever of the box's grid
        diagnostics = box_values(designed.lever_model, law, t37, (band_low_rpm, n), box, BOX_STEP_RPM,
                                 linear_lever(coefficients, 2), values, "")
        diagnostics["box_binding"] = _box_binding(plan, n)
        held = held and values["rebound_worst_box_mm"] <= task.amplitude_limit_mm * (1 + 1e-6)
    status = Status.SOLVED if held else Status.INACCURATE
    limiting = plan.diagnostics.get("limiting_constraint", "-")
    lift = _lift_bound(plan) or "no speed bound (its angle floor)"
    if lift.startswith("amplitude") and "roller_left" in str(plan.diagnostics.get("amplitude_bounds_at_reference")):
        lift += " (its edge: below it the roller leaves its cam, the closure force short)"
    other = next(r for r in READINGS if r != lift_stress)
    message = (f"{n:.6g} rpm with the synthesised lift law against {values['speed_baseline_rpm']:.6g} rpm with "
               f"{task.lever_model.law} ({values['gain_percent']:+.2f} %); the lift's t(3,7) now set by {lift} "
               f"(baseline: {_lift_bound(baseline) or '-'}); limiting: {limiting} "
               f"(baseline {baseline.diagnostics.get('limiting_constraint', '-')}); the chain at t(3,7) = {t37:.4g} deg: "
               f"{chain:.4g} mm; the lift's stress read from the {lift_stress} (x{scale:.4f} on the given; "
               f"read {other}: {values[f'speed_stress_{other}_rpm']:.6g} rpm)")
    if not box.trivial:
        message += (f"; on the box the lift's bound binds at {diagnostics['box_binding']}; the chain's worst there "
                    f"{values['rebound_worst_box_mm']:.4g} mm at {diagnostics.get('rebound_worst_box_at')}")
    diagnostics |= {"limiting_constraint": limiting, "limiting_group": plan.diagnostics.get("limiting_group"),
                    "critical_chain": plan.diagnostics.get("critical_chain"),
                    "critical_ops": plan.diagnostics.get("critical_ops", []),
                    "float_deg": plan.diagnostics.get("float_deg", {}),
                    "baseline_limiting_constraint": baseline.diagnostics.get("limiting_constraint"),
                    "lift_bound": lift, "timing": took, "baseline_lift_bound": _lift_bound(baseline),
                    "lift_bound_by_reading": {r: _lift_bound(p) for r, p in plans.items()},
                    "lift_amplitude_bound": plan.diagnostics.get("amplitude_bounds_at_reference"),
                    "windows_given_up": law_run.diagnostics.get("windows_given_up", 0),
                    "limiting": plan.diagnostics.get("limiting"),
                    "law": str(law), "law_knots": list(law.knots), "law_coefficients": list(law.coefficients)}
    arrays = dict(law_run.arrays) | plan.arrays
    return clock.result(status, values, message=message, diagnostics=diagnostics, arrays=arrays,
                        warnings=plan.warnings)


def _stress_scale(task, law):
    """sqrt(Ca_law / Ca_own): the lift cam's Hertz stress for the synthesised law against the law its
    stress model was calibrated on (module docstring, 5.), and both Ca (max |S''| of a unit rise)."""
    ca_law, ca_own = _peak_acceleration(law), _peak_acceleration(task.lever_model.law)
    return math.sqrt(ca_law / ca_own), {"ca_law": ca_law, "ca_own": ca_own}


def _peak_acceleration(law) -> float:
    """Ca = max |S''| over the rise: a library law's `peaks`, a spline's on a dense grid with its knots
    (a cubic's S'' is piecewise linear: its peak sits on a knot)."""
    if isinstance(law, str):
        return float(library_law(law).peaks["Ca"])
    xi = np.union1d(np.linspace(0.0, 1.0, PEAK_GRID), np.clip(law.knots, 0.0, 1.0))
    return float(np.abs(law.values(xi)[2]).max())


def _with_lift_stress(task, scale):
    """The task with the lift arc's stress model's sigma_ref times `scale`; refused where another
    arc shares that model (it would scale a cam the law does not move)."""
    names = {task.arc_data(k)["stress"] for k in task.amplitude_arcs()} - {None}
    if scale == 1.0 or not names:
        return task
    shared = [task.arcs[k] for k in task.stress_arcs()
              if k not in task.amplitude_arcs() and task.arc_data(k)["stress"] in names]
    if shared:
        x, y = shared[0]
        raise ModelError(f"stress_models: the lift's cam pair {sorted(names)} is shared with operation {x}->{y}; "
                         f"give the lift its own stress model (or lift_stress='given')", key="stress_models")
    models = {name: {**model, "sigma_ref_MPa": float(model["sigma_ref_MPa"]) * scale} if name in names else model
              for name, model in task.stress_models.items()}
    return dataclasses.replace(task, stress_models=models)


def _box_binding(plan, n_rpm):
    """The box's lever and speed the lift's bound binds on in the plan (its amplitude_box)."""
    for bound in (plan.diagnostics.get("amplitude_box") or {}).values():
        return {"frequency_factor": bound["frequency_factor"], "zeta": bound["zeta"],
                "speed_rpm": n_rpm * bound["speed_factor"]}
    return None


def _lift_bound(plan):
    """Which speed bound sets the lift's operation (3,7) on the plan's critical chain, if one does."""
    for row in plan.diagnostics.get("limiting") or ():
        if row["constraint"].endswith("[3->7]"):
            return row["constraint"]
    return None
