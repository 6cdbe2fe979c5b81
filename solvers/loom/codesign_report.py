"""The co-design's report (solvers/loom/codesign.py): from the readings planned, the chosen
one's speed, gain and t(3,7), the chain at the re-planned t(3,7) (the loop closed), the box's
worst, each closure and stress reading beside it, the groove's crossovers, what binds, and the lift
cam for the shop cut to the law at t(3,7) with its phase on the shaft."""
import math

from mechopt.kit.result import Status
from mechopt.solvers.stop_impact.cam_follower import follow_cam
from mechopt.solvers.stop_impact.cam_shape import law_cam, without_cam
from mechopt.solvers.stop_impact.groove import rebound_with_backlash_mm
from mechopt.solvers.stop_impact.law import CHAIN_RELTOL, rebound_amplitude_mm
from mechopt.solvers.stop_impact.response import closed_form_amplitude_m
from mechopt.solvers.stop_impact.synthesis_box import box_values
from mechopt.solvers.stop_impact.window_lp import linear_lever

__all__ = ["READINGS", "report"]

BOX_STEP_RPM = 5.0          # the box's speeds at the re-planned t(3,7): every 5 rpm, as the synthesis' dense check
READINGS = ("law_shape", "given")
LIFT_START = "3"            # the event where the lift's rise begins: operation (3,7) starts there
GEOMETRY_VALUES = ("max_pressure_angle_rise_deg", "max_pressure_angle_return_deg", "min_radius_of_curvature_mm",
                   "min_concave_radius_mm", "pressure_angle_binds", "curvature_binds", "geometry_steps_taken")


def report(task, done, clock, *, lift_closure, lift_stress, lift_backlash_mm, beside, geometry, box, band_low_rpm,
           coefficients):
    """The Result of `codesign_machine_speed` (its docstring) from `done`: {closure reading: its
    planned steps (`codesign._plan_reading`)}, the chosen `lift_closure` among them."""
    chosen = done[lift_closure]
    baseline, law_run, law, plans, machines = (chosen[k] for k in ("baseline", "law_run", "law", "plans", "machines"))
    scale, peaks, took = chosen["scale"], chosen["peaks"], chosen["took"]
    values = {"speed_baseline_rpm": baseline.values["max_speed_rpm"],
              "t_min_synthesized_deg": law_run.values["t_min_synthesized_deg"]}
    for reading, each in plans.items():
        values[f"speed_stress_{reading}_rpm"] = each.values["max_speed_rpm"]
        values[f"t_3_7_stress_{reading}_deg"] = each.values["t_3_7_deg"]
    values |= {"stress_scale_lift": scale} | peaks
    if geometry:                             # the cam's geometry of the law at t_min (n_ref): the synthesis'
        values |= {k: law_run.values[k] for k in GEOMETRY_VALUES if k in law_run.values}
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
    lift = _lift_text(plan)
    by_closure = {}
    for closure, one in done.items():        # each closure reading: its speed, t(3,7), gain and what binds
        each, base = one["plans"][lift_stress], one["baseline"].values["max_speed_rpm"]
        values |= {f"speed_closure_{closure}_rpm": each.values["max_speed_rpm"],
                   f"t_3_7_closure_{closure}_deg": each.values["t_3_7_deg"],
                   f"speed_baseline_closure_{closure}_rpm": base,
                   f"gain_closure_{closure}_percent": 100.0 * (each.values["max_speed_rpm"] / base - 1.0)}
        by_closure[closure] = {"lift_bound": _lift_text(each), "baseline_lift_bound": _lift_text(one["baseline"])}
    if "groove" in done:                     # the crossovers at the groove's design point, the backlash's effect
        groove = done["groove"]
        values |= _groove_values(groove["machines"][lift_stress].lever_model,
                                 groove["plans"][lift_stress].values["max_speed_rpm"],
                                 groove["plans"][lift_stress].values["t_3_7_deg"])
    other = next(r for r in READINGS if r != lift_stress)
    message = (f"{n:.6g} rpm with the synthesised lift law against {values['speed_baseline_rpm']:.6g} rpm with "
               f"{task.lever_model.law} ({values['gain_percent']:+.2f} %); the lift's t(3,7) now set by {lift} "
               f"(baseline: {_lift_bound(baseline) or '-'}); limiting: {limiting} "
               f"(baseline {baseline.diagnostics.get('limiting_constraint', '-')}); the chain at t(3,7) = {t37:.4g} deg: "
               f"{chain:.4g} mm; the lift's stress read from the {lift_stress} (x{scale:.4f} on the given"
               + (f"; read {other}: {values[f'speed_stress_{other}_rpm']:.6g} rpm)" if beside else ")"))
    for closure in done:
        if closure != lift_closure:
            message += (f"; read as {closure}-closed: {values[f'speed_closure_{closure}_rpm']:.6g} rpm, t(3,7) = "
                        f"{values[f't_3_7_closure_{closure}_deg']:.5g} deg set by {by_closure[closure]['lift_bound']} "
                        f"({values[f'gain_closure_{closure}_percent']:+.2f} % over its cycloid)")
    if "crossovers_3_7" in values:
        message += (f"; in the groove at its t(3,7): {values['crossovers_3_7']:g} crossover(s) in the rise; with "
                    f"the backlash {lift_backlash_mm:g} mm the approach is "
                    f"{values.get('approach_velocity_backlash_m_s', math.nan):.4g} m/s, the rebound "
                    f"{values.get('rebound_backlash_mm', math.nan):.4g} mm (walls without play: "
                    f"{values['approach_velocity_no_backlash_m_s']:.4g} m/s, {values['rebound_no_backlash_mm']:.4g} mm)")
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
                    "lift_bound_by_closure": by_closure, "lift_closure": lift_closure,
                    "lift_amplitude_bound": plan.diagnostics.get("amplitude_bounds_at_reference"),
                    "windows_given_up": law_run.diagnostics.get("windows_given_up", 0),
                    "limiting": plan.diagnostics.get("limiting"),
                    "law": str(law), "law_knots": list(law.knots), "law_coefficients": list(law.coefficients)}
    # the lift cam cut to the law at the re-planned t(3,7) (the synthesis' own was cut at its t_min),
    # its phase on the shaft the re-planned cyclogram's event where the rise begins
    shop, said = law_cam(task.lever_model, law, t37, law_run.diagnostics["cam"]["geometry"])
    said["cam"] |= {"rise_start_shaft_deg": values[f"p_{LIFT_START}_deg"], "phase_event": LIFT_START,
                    "phase_event_what": task.events.get(LIFT_START, {}).get("what", "the start of operation (3,7)")}
    arrays = without_cam(law_run.arrays) | plan.arrays | shop
    return clock.result(status, values, message=message, diagnostics=diagnostics | said, arrays=arrays,
                        warnings=plan.warnings)


def _groove_values(lever, n_rpm, t_deg):
    """At the groove reading's design point (n, t(3,7)): the crossovers of the chain's rise (count,
    the first's cam angle, the largest impact, each flight from the backlash-free path) and the
    approach with the backlash (the hybrid model, solvers/stop_impact/groove.py: the chain's own
    where a crossover comes before the plate) beside the backlash-free walls' approach and rebound."""
    rise = follow_cam(lever, n_rpm, t_deg, reltol=CHAIN_RELTOL)
    speeds = [c.impact_m_s for c in rise.crossovers if c.impact_m_s is not None]
    out = {"crossovers_3_7": float(len(rise.crossovers)),
           "approach_velocity_no_backlash_m_s": rise.approach_velocity_m_s,
           "rebound_no_backlash_mm": closed_form_amplitude_m(
               lever.impact(n_rpm, t_deg, v0_m_s=rise.approach_velocity_m_s))[0] * 1e3}
    if rise.crossovers:
        out["crossover_angle_3_7_deg"] = rise.crossovers[0].angle_deg(t_deg)
    if speeds:
        out["crossover_impact_max_m_s"] = max(speeds)
    rebound, real = rebound_with_backlash_mm(lever, n_rpm, t_deg)
    if real.status is Status.SOLVED and real.contact_xi is not None:
        out |= {"approach_velocity_backlash_m_s": real.approach_velocity_m_s, "rebound_backlash_mm": rebound}
    return out


def _lift_text(plan):
    """What sets the lift's t(3,7) in a plan, its edge named where the roller leaves its cam."""
    lift = _lift_bound(plan) or "no speed bound (its angle floor)"
    if lift.startswith("amplitude") and "roller_left" in str(plan.diagnostics.get("amplitude_bounds_at_reference")):
        lift += " (its edge: below it the roller leaves its cam, the closure force short)"
    return lift


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
