"""The machine's speed co-designed with the lift cam's law: the readings planned here, the report
(values, message, the shop's cam) in solvers/loom/codesign_report.py.

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
6. The lift cam's closure (`lift_closure`, models/stop_impact.py): "force" (the roller held on its
   flank by the lever's closure_force_N; N < 0 is lift-off, past which the chain refuses: an edge
   below which no t(3,7) is planned) or "groove" (the paper's Fig. 3: a grooved cam; N < 0 is a
   crossover across `lift_backlash_mm`, no edge; where one comes before the plate the chain's
   approach is the hybrid model's with the backlash, solvers/stop_impact/groove.py). The synthesis
   keeps the roller on its driving wall (N >= 5 % of the closure) under both: against lift-off, or
   against a crossover whose flight the LP's linear lever does not hold (without those rows the
   chain with the backlash missed the LP's prediction by 0.33 of the limit); so one law serves
   both. Given a backlash (and `beside`), both readings are planned, each with its own cycloid
   baseline (speed_closure_<reading>_rpm, t_3_7_closure_<reading>_deg,
   gain_closure_<reading>_percent); speed_rpm is the chosen one's. Under the groove the crossovers
   at the re-planned t(3,7) are reported (count, angle, largest impact), with the approach and
   rebound of walls without play beside the backlash's.
"""
import dataclasses
import math
from typing import Literal

import numpy as np

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, check_settings
from mechopt.models.cam_laws import law as library_law
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram.speed import max_machine_speed
from mechopt.solvers.loom.codesign_report import READINGS, report
from mechopt.solvers.stop_impact.lever_box import LeverBox, takes_box
from mechopt.solvers.stop_impact.synthesis import law_of, synthesise_law

__all__ = ["codesign_machine_speed"]

PEAK_GRID = 200001          # xi points for a spline's max |S''|: its error ~ h^2 max|S''''| / 8, below 1e-8 here
CLOSURES = ("force", "groove")


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
                           lift_stress: Literal["law_shape", "given"] = "law_shape",
                           lift_closure: Literal["force", "groove"] = "force",
                           lift_backlash_mm: Annotated[float, Interval(ge=0.0, le=10.0)] = 0.0,
                           beside: bool = True,
                           geometry: bool = False,
                           max_pressure_angle_deg: Annotated[float, Interval(gt=0, lt=90)] = 45.0,
                           min_curvature_margin_mm: Annotated[float, Interval(ge=0)] = 0.0,
                           cam_base_radius_mm: Annotated[float, Interval(gt=0, le=1e4)] = 60.0,
                           cam_roller_radius_mm: Annotated[float, Interval(gt=0, le=1e4)] = 15.0,
                           cam_centre_distance_mm: Annotated[float, Interval(gt=0, le=1e4)] = 120.0,
                           cam_dwell_deg: Annotated[float, Interval(ge=0, lt=360)] = 60.0,
                           geometry_steps: Annotated[int, Interval(ge=1, le=50)] = 8) -> Result:
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
    lift_closure, lift_backlash_mm : the lift cam's closure reading (module docstring, 6.) and the
        groove's backlash reduced to C [mm] (0: not given; "groove" needs it; given, and with
        `beside`, the other closure reading is planned beside the chosen one).
    beside : plan the other readings (stress, and closure given a backlash) beside the chosen ones;
        false: the chosen readings alone (one plan: the command's CPU roughly halved).
    geometry, max_pressure_angle_deg ... geometry_steps : the law synthesised with its cam's
        geometry bounds (`synthesise_law`'s, stop-impact/law-synthesis-geometry): pressure angle and
        radius of curvature held at t_min at n_ref; the re-planned t(3,7) >= t_min, where a law of
        fixed shape only gets gentler (its s' and s'' scale as 1 / t and 1 / t^2).

    Values: speed_rpm, speed_baseline_rpm, gain_percent, t_min_synthesized_deg (at n_ref),
    t_3_7_deg and the chain's rebound there (rebound_chain_mm); under both stress readings
    speed_stress_<reading>_rpm and t_3_7_stress_<reading>_deg; stress_scale_lift = sqrt(ca_law /
    ca_own). Diagnostics: the limiting cycle and constraint of both plans, the bound that sets the
    lift's t(3,7) (lift_bound), with a box the lever and speed the lift's bound binds on
    (box_binding); the lift cam for the shop cut to the law at t(3,7) (`cam_shape.law_cam`, the
    synthesis' cam geometry: arrays cam_pitch_x_mm ..., diagnostics cam with the shaft's angle at
    event 3 where the rise begins). SOLVED when the chain keeps the limit at t(3,7) on the nominal lever and, given
    a box, on its grid; INACCURATE otherwise (the message says where).
    """
    check_settings(codesign_machine_speed, lift_stress=lift_stress, lift_closure=lift_closure,
                   lift_backlash_mm=lift_backlash_mm)
    if task.lever is None or task.amplitude_limit_mm is None or task.speed_rpm is None:
        raise ModelError("codesign: needs the lever's table [structure.lever], amplitude_limit_mm and speed_rpm",
                         key="lever")
    if band_low_rpm >= task.speed_rpm:
        raise SettingError(f"band_low_rpm={band_low_rpm} must be below speed_rpm={task.speed_rpm} (the band's top)",
                           key="band_low_rpm")
    if lift_closure == "groove" and lift_backlash_mm <= 0:
        raise SettingError(f"lift_backlash_mm={lift_backlash_mm}: allowed > 0 with lift_closure='groove' (the "
                           "groove's play reduced to C, mm)", key="lift_backlash_mm")
    box = box or LeverBox()
    clock = Clock()
    speed_settings = dict(scan_to_deg=scan_to_deg, scan_step_deg=scan_step_deg, box=box)
    synthesis_settings = dict(objective="least_phase", coefficients=coefficients, band_low_rpm=band_low_rpm,
                              band_high_rpm=task.speed_rpm, sample_speeds=sample_speeds,
                              max_acceleration_mm_per_rad2=max_acceleration_mm_per_rad2,
                              phase_from_deg=phase_from_deg, phase_to_deg=phase_to_deg,
                              phase_tol_deg=phase_tol_deg, compare=False, robust=robust, box=box,
                              shop_cam=False)                  # the report cuts its own at t(3,7)
    if geometry:
        synthesis_settings |= dict(geometry=True, max_pressure_angle_deg=max_pressure_angle_deg,
                                   min_curvature_margin_mm=min_curvature_margin_mm,
                                   cam_base_radius_mm=cam_base_radius_mm, cam_roller_radius_mm=cam_roller_radius_mm,
                                   cam_centre_distance_mm=cam_centre_distance_mm, cam_dwell_deg=cam_dwell_deg,
                                   geometry_steps=geometry_steps)
    closures = [lift_closure] + [c for c in CLOSURES if c != lift_closure and lift_backlash_mm > 0 and beside]
    done = _plan_readings(task, closures, lift_stress, lift_backlash_mm, beside, synthesis_settings, speed_settings)
    if isinstance(done, tuple):             # (closure, status, message, violated, values): a step failed
        closure, status, message, violated, partial = done
        return clock.result(status, partial, message=f"closure {closure}: {message}", violated=violated)
    return report(task, done, clock, lift_closure=lift_closure, lift_stress=lift_stress,
                  lift_backlash_mm=lift_backlash_mm, beside=beside, geometry=geometry, box=box,
                  band_low_rpm=band_low_rpm, coefficients=coefficients)


def _plan_readings(task, closures, lift_stress, backlash_mm, beside, synthesis_settings, speed_settings):
    """Each closure reading of `closures` planned (`_plan_reading`), the chosen one (the first)
    under both stress readings when `beside`: {closure: its steps}, or (closure, status, message,
    violated, values so far) where a step is not SOLVED."""
    done = {}
    for closure in closures:                # the chosen reading first, under both stress readings
        stresses = READINGS if closure == closures[0] and beside else (lift_stress,)
        # one law for both: the LP keeps the roller on its driving wall either way (no lift-off / no crossover)
        law_run = done[closures[0]]["law_run"] if done else None
        one = _plan_reading(_with_closure(task, closure, backlash_mm), stresses, synthesis_settings,
                            speed_settings, law_run)
        if isinstance(one, tuple):
            return (closure,) + one
        done[closure] = one
    return done


def _with_closure(task, closure, backlash_mm):
    """The machine with its lift lever's closure reading (module docstring, 6.)."""
    lever = {k: v for k, v in task.lever.items() if k != "backlash_mm"} | {"closure": closure}
    if closure == "groove":
        lever["backlash_mm"] = backlash_mm
    return dataclasses.replace(task, lever=lever)


def _plan_reading(task, stresses, synthesis_settings, speed_settings, law_run=None):
    """One closure reading: the cycloid's machine (the baseline), the law synthesised for its lever
    (or `law_run`'s, another reading's: the LP is the same under both closures, its rows named
    apart), the machine re-planned with it under each stress reading of `stresses`. A dict of the
    steps, or (status, message, violated, values so far) where a step is not SOLVED."""
    baseline = max_machine_speed(task, **speed_settings)
    if baseline.status is not Status.SOLVED:
        return baseline.status, f"the baseline machine: {baseline.message}", baseline.violated, {}
    lever = dataclasses.replace(task.lever_model, amplitude_limit_mm=task.amplitude_limit_mm,
                                speed_nominal_rpm=task.speed_rpm)
    synthesis = Clock()
    law_run = law_run or synthesise_law(lever, **synthesis_settings)
    took = {"synthesis_s": synthesis.elapsed()}                     # timings go to diagnostics: values are results
    if law_run.status is not Status.SOLVED:
        return (law_run.status, f"the lift's law: {law_run.message}", law_run.violated,
                {"speed_baseline_rpm": baseline.values["max_speed_rpm"]})
    law = law_of(law_run)
    replan = Clock()
    scale, peaks = _stress_scale(task, law)
    machines = {reading: _with_lift_stress(dataclasses.replace(task, lever={**task.lever, "law": law}),
                                           scale if reading == "law_shape" else 1.0) for reading in stresses}
    plans = {reading: max_machine_speed(machine, **speed_settings) for reading, machine in machines.items()}
    took["replan_s"] = replan.elapsed()
    for reading, each in plans.items():
        if each.status is not Status.SOLVED:
            return (each.status, f"the re-planned machine ({reading} stress): {each.message}", each.violated,
                    {"speed_baseline_rpm": baseline.values["max_speed_rpm"]})
    return {"baseline": baseline, "law_run": law_run, "law": law, "plans": plans, "machines": machines,
            "scale": scale, "peaks": peaks, "took": took}


def _stress_scale(task, law):
    """sqrt(Ca_law / Ca_own): the lift cam's Hertz stress for the synthesised law against the law its
    stress model was calibrated on (module docstring, 5.), and both Ca (max |S''| of a unit rise)."""
    ca_law, ca_own = _peak_acceleration(law), _peak_acceleration(task.lever_model.law)
    return math.sqrt(ca_law / ca_own), {"ca_law": ca_law, "ca_own": ca_own}


@memoised(maxsize=16)      # one law, both closure readings
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
