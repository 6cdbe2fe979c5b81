"""The lift cam's motion law synthesised under the lever's dynamic limits, and
checked by the chain that did not design it.

By job: the linear model and its window LP (solvers/stop_impact/window_lp.py: the law a spline,
the lever's response linear in its coefficients, the arrival window that makes the contact
linear, the rebound's envelope as rows), the search (synthesis_search.py: the windows scanned at
one phase angle, the dense check, the least phase), the cam's geometry (synthesis_geometry.py),
the lever's box (synthesis_box.py) and the library laws beside it (synthesis_compare.py). This
module is the solver a scene names.

Objectives (`objective`):
* "least_rebound"      min over c of the largest rebound at the sampled speeds, at t = t_deg;
* "least_acceleration" min of the peak |S''| with the rebound <= amplitude_limit_mm, at t_deg;
* "least_phase"        the least t with the least rebound <= amplitude_limit_mm over the band:
                       regula falsi (Illinois) on r*(t) - limit in [phase_from_deg, phase_to_deg]
                       to `phase_tol_deg` or r* within 1e-4 of the limit, r*(t) the least-rebound
                       LP's value, assumed to fall as t grows (more time, slower arrival: stated,
                       not proven); a t below the kinematic minimum is a bisection step.

Not modelled: the Hertz stress of the law; the cam's pressure angle and radius of curvature only
when `geometry` (sequential LPs, solvers/stop_impact/cam_rows.py).

Robust over the speed band [band_low_rpm, band_high_rpm]: constraints at `sample_speeds` speeds,
then the linear model is checked densely (every `dense_step_rpm`) between them; a speed that
breaks the limit (or the LP's bound) is added to the samples and the LP solved again.

Verification: the law found runs through follow_cam (CVODES, the contact located) and the closed
form of eq. (2) at every sampled speed and at the dense check's worst; the linear prediction must
agree within `agreement_rel` (else INACCURATE). The four library laws are run at the same t and
speeds beside it: rebound, dynamic error, peak acceleration.
"""
import dataclasses
import math
from typing import Literal

import numpy as np

from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, NonNegative
from mechopt.models.cam_follower import LAWS
from mechopt.models.cam_law import SplineLaw
from mechopt.models.cam_shape import CamShape
from mechopt.models.stop_impact import LeverStop, speed_tag
from mechopt.solvers.stop_impact.cam_rows import CamGeometry
from mechopt.solvers.stop_impact.cam_shape import law_cam
from mechopt.solvers.stop_impact.law import RollerLeftCam, rebound_amplitude_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox, takes_box
from mechopt.solvers.stop_impact.synthesis_box import beside, box_values, box_worst_point
from mechopt.solvers.stop_impact.synthesis_compare import analogues, compare_laws, library_least_phase
from mechopt.solvers.stop_impact.synthesis_geometry import geometry_values, least_angle
from mechopt.solvers.stop_impact.synthesis_search import ROBUST_ROUNDS, design_law, least_phase, points_text
from mechopt.solvers.stop_impact.window_lp import band_speeds, linear_lever, predicted_rebounds_mm

__all__ = ["law_of", "synthesise_law"]


def law_of(result: Result) -> SplineLaw:
    """The synthesised law of a `synthesise_law` Result (its diagnostics law_knots, law_coefficients):
    `law_of(run.result).values(xi)` gives S and its first three derivatives on any xi grid (the shop's input)."""
    knots, coeffs = np.asarray(result.diagnostics["law_knots"]), np.asarray(result.diagnostics["law_coefficients"])
    return SplineLaw(tuple(map(float, knots)), tuple(map(float, coeffs)), knots.size - coeffs.size - 1)


@takes_box
def synthesise_law(task: LeverStop, *, objective: Literal["least_phase", "least_rebound", "least_acceleration"]
                   = "least_phase",
                   coefficients: Annotated[int, Interval(ge=2, le=2000)] = 100,
                   continuity: Literal[2, 3] = 2,
                   band_low_rpm: Annotated[float, Interval(gt=0, le=1e5)] = 280.0,
                   band_high_rpm: Annotated[float, Interval(gt=0, le=1e5)] = 420.0,
                   sample_speeds: Annotated[int, Interval(ge=1, le=50)] = 5,
                   dense_step_rpm: Annotated[float, Interval(gt=0, le=1e4)] = 5.0,
                   max_velocity_mm_per_rad: NonNegative = 0.0,
                   max_acceleration_mm_per_rad2: NonNegative = 0.0,
                   max_jerk_mm_per_rad3: NonNegative = 0.0,
                   phase_from_deg: Annotated[float, Interval(gt=0, lt=360)] = 10.0,
                   phase_to_deg: Annotated[float, Interval(gt=0, lt=360)] = 60.0,
                   phase_tol_deg: Annotated[float, Interval(gt=0, le=1)] = 0.01,
                   verify: bool = True,
                   agreement_rel: Annotated[float, Interval(gt=0, le=0.5)] = 2e-3,
                   compare: bool = True,
                   box: LeverBox | None = None,
                   robust: bool = False,
                   geometry: bool = False,
                   max_pressure_angle_deg: Annotated[float, Interval(gt=0, lt=90)] = 45.0,
                   min_curvature_margin_mm: NonNegative = 0.0,
                   cam_base_radius_mm: Annotated[float, Interval(gt=0, le=1e4)] = 60.0,
                   cam_roller_radius_mm: Annotated[float, Interval(gt=0, le=1e4)] = 15.0,
                   cam_centre_distance_mm: Annotated[float, Interval(gt=0, le=1e4)] = 120.0,
                   cam_dwell_deg: Annotated[float, Interval(ge=0, lt=360)] = 60.0,
                   geometry_steps: Annotated[int, Interval(ge=1, le=50)] = 8,
                   shop_cam: bool = True) -> Result:
    """Synthesise the lift cam's law (module docstring) and check it by the chain.

    Parameters
    ----------
    task : the lever (effects cam_drive and the impact's), `stroke_mm`, `amplitude_limit_mm` the
        rebound limit [mm], `t_deg` the phase angle for the fixed-angle objectives [deg].
    objective : "least_phase" | "least_rebound" | "least_acceleration".
    coefficients, continuity : free spline coefficients; C2 (cubic) or C3 (quartic) at the dwells.
    band_low_rpm, band_high_rpm, sample_speeds, dense_step_rpm : the speed band, the speeds the LP
        holds and the step of the dense check between them [rpm].
    max_velocity_mm_per_rad, max_acceleration_mm_per_rad2, max_jerk_mm_per_rad3 : kinematic bounds
        on the analogues of C's travel (0: none).
    phase_from_deg, phase_to_deg, phase_tol_deg : the search's bracket and tolerance on t [deg].
    verify, agreement_rel : run the law through follow_cam (CVODES) and eq. (2) and require the
        linear prediction to agree within agreement_rel (else INACCURATE).
    compare : the four library laws at the same t and speeds (values `<law>_rebound_mm_<rpm>` ...), and
        with least_phase the cycloid's least angle (`t_min_cycloidal_deg`, `phase_gain_percent`).
    box : the lever's uncertain inputs on a box (solvers/stop_impact/lever_box.py; a scene's settings
        box_frequency_low, box_frequency_high, box_zeta_low, box_zeta_high, box_speed_margin,
        box_grid: `takes_box`): a factor on both natural frequencies, the damping ratio (both 0: the
        task's own), the band's top raised by a fraction, the dense check's points per axis. Given,
        the result reports the chain's worst rebound over the box (`rebound_worst_box_mm`, its lever
        and speed in diagnostics).
    robust : the law must keep the limit on the whole box: its corners and nominal are LP rows, its
        grid the dense check, a failing point added (`design_law`); with compare, the nominal law's
        and the cycloid's (at its least angle) worst over the same box beside it.
    geometry : hold the lift cam's geometry too (solvers/stop_impact/cam_rows.py; off: nothing
        changes): the cam an oscillating roller follower in a groove, turning counter-clockwise, its
        lever arms and stroke the task's (a_mm, b_mm, stroke_mm), the rise and the mirrored return
        over t; `cam_base_radius_mm`, `cam_roller_radius_mm`, `cam_centre_distance_mm` (cam centre
        to the lever's pivot), `cam_dwell_deg` (upper dwell) [mm, deg]; the limits
        `max_pressure_angle_deg` (rise and return) and the pitch curve's radius of curvature >=
        roller radius + `min_curvature_margin_mm` on both walls of the groove; at most
        `geometry_steps` sequential LPs per phase angle (LIMIT naming them when the exact geometry
        still breaks a limit). Values: max_pressure_angle_{rise,return}_deg, min_radius_of_curvature_mm,
        min_concave_radius_mm, pressure_angle_binds, curvature_binds (1: within BINDS_WITHIN of its limit).

    Whatever `geometry`, the law's cam for the shop (`cam_shape.law_cam`: the lift cam of the cam_*
    settings, the lever's arms and stroke, rise and return over t): arrays `cam_pitch_x_mm` ...,
    diagnostics `cam` (its status, chordal errors, rise-start direction, geometry); the DXF writer
    draws from them. `shop_cam` false: not cut (for a caller that cuts its own, as the co-design at
    its re-planned t(3,7)); diagnostics `cam` then holds its geometry alone.
    """
    task.need("stroke_mm", "amplitude_limit_mm")
    task.need_effect("cam_drive")
    if band_low_rpm > band_high_rpm:
        raise SettingError(f"band_low_rpm={band_low_rpm} > band_high_rpm={band_high_rpm}: the band is empty",
                           key="band_low_rpm")
    if phase_from_deg >= phase_to_deg:
        raise SettingError(f"phase_from_deg={phase_from_deg} >= phase_to_deg={phase_to_deg}: empty bracket",
                           key="phase_from_deg")
    box = box or LeverBox()
    clock = Clock()
    bounds = {"max_velocity_mm_per_rad": max_velocity_mm_per_rad,
              "max_acceleration_mm_per_rad2": max_acceleration_mm_per_rad2, "max_jerk_mm_per_rad3": max_jerk_mm_per_rad3}
    band = (band_low_rpm, band_high_rpm)
    common = dict(coefficients=coefficients, continuity=continuity, sample_speeds=sample_speeds,
                  dense_step_rpm=dense_step_rpm, bounds=bounds)
    if robust and not box.trivial:
        common |= {"box": box, "rounds": ROBUST_ROUNDS}
    cam = None
    if geometry:
        try:        # the lever's arms and stroke, the rise and return over the bracket's top
            shape = CamShape(base_radius_mm=cam_base_radius_mm, roller_radius_mm=cam_roller_radius_mm,
                             stroke_mm=task.stroke_mm, rise_deg=phase_to_deg, return_deg=phase_to_deg,
                             dwell_deg=cam_dwell_deg, centre_distance_mm=cam_centre_distance_mm, a_mm=task.a_mm,
                             b_mm=task.b_mm, follower="oscillating", closure="groove")
        except ModelError as exc:       # named as the setting (or the task's parameter) at fault
            key = f"cam_{exc.key}" if exc.key in ("base_radius_mm", "roller_radius_mm", "centre_distance_mm",
                                                  "dwell_deg") else "phase_to_deg" if exc.key == "rise_deg" else exc.key
            raise SettingError(f"geometry: the lift cam cannot be made ({key}): {exc}", key=key) from None
        cam = CamGeometry(shape, max_pressure_angle_deg, min_curvature_margin_mm, geometry_steps)
        common["geometry"] = cam
    limit = task.amplitude_limit_mm
    build = Clock()
    linear_lever(coefficients, continuity)
    clock.build_s = build.elapsed()
    values, diagnostics = {}, {}
    if objective == "least_phase":
        design, t_deg, search = least_phase(task, band, phase_from_deg, phase_to_deg, phase_tol_deg, common)
        diagnostics |= {"bisection_steps": search["steps"], "windows_given_up": search["given_up"],
                        "windows_retried": search["retried"]}
        if design.status is not Status.SOLVED:
            if cam is not None and design.status is Status.INFEASIBLE:
                design = least_angle(design, cam, task, t_deg, bounds, coefficients, continuity, values)
            return _unsolved(design, values, diagnostics, clock, t_deg, limit, task, band, dense_step_rpm)
    else:
        task.need("t_deg")
        t_deg = task.t_deg
        design = design_law(task, t_deg, band, objective=objective, **common)
        diagnostics |= {"windows_given_up": design.given_up, "windows_retried": design.retried}
        if design.status is not Status.SOLVED:
            return _unsolved(design, values, diagnostics, clock, t_deg, limit, task, band, dense_step_rpm)
    law = design.law
    lever = linear_lever(coefficients, continuity)
    values |= {"t_deg": t_deg, "lp_value": design.value, "window_xi": design.window_xi, "lps": float(design.lps)}
    if cam is not None:
        values |= geometry_values(cam, design)
        diagnostics["geometry_binds"] = [k for k in ("pressure_angle", "curvature") if values[f"{k}_binds"]]
    if objective == "least_phase":
        values["t_min_synthesized_deg"] = t_deg
        if robust and not box.trivial:
            values["t_min_robust_deg"] = t_deg
        t_cyc = library_least_phase(task, "cycloidal", band, phase_from_deg, phase_to_deg, phase_tol_deg,
                                     dense_step_rpm) if compare else None
        if t_cyc is not None:
            values["t_min_cycloidal_deg"] = t_cyc
            values["phase_gain_percent"] = 100.0 * (1.0 - t_deg / t_cyc)
    dense = band_speeds(band, dense_step_rpm)
    pred = predicted_rebounds_mm(task, law, t_deg, dense, lever=lever)
    worst = int(np.argmax([p[0] for p in pred]))
    values |= {"rebound_max_predicted_mm": pred[worst][0], "rebound_max_speed_rpm": float(dense[worst])}
    xi = np.linspace(0, 1, 2001)
    S, dS, ddS, dddS = law.values(xi)
    t_rad = math.radians(t_deg)
    H_mm = task.stroke_mm
    values |= {"peak_velocity_mm_per_rad": float(np.abs(dS).max()) * H_mm / t_rad,
               "peak_acceleration_mm_per_rad2": float(np.abs(ddS).max()) * H_mm / t_rad**2,
               "peak_jerk_mm_per_rad3": float(np.abs(dddS).max()) * H_mm / t_rad**3}
    arrays = analogues(law, xi, H_mm, t_rad, "") | {"speed_rpm": dense.astype(float),
                                                     "rebound_predicted_mm": np.array([p[0] for p in pred])}
    if compare:          # the library laws' analogues at the same t, and the cycloid's rebound against speed
        for name in LAWS:
            arrays |= analogues(name, xi, H_mm, t_rad, f"{name}_")
        arrays["rebound_cycloidal_predicted_mm"] = np.array(
            [p[0] for p in predicted_rebounds_mm(task, "cycloidal", t_deg, dense, lever=lever)])
    status, message, warnings = Status.SOLVED, f"{objective}: {law} at t = {t_deg:.6g} deg", ()
    if verify:
        nominal = box.nominal(task)
        check_points = sorted(set(design.speeds) | {nominal + (float(dense[worst]),)})
        if robust and not box.trivial:      # and the box's worst (the robust LP's dense check was over it)
            check_points = sorted(set(check_points) | {box_worst_point(task, law, t_deg, band, box, dense_step_rpm,
                                                                       lever)[1]})
        worst_gap, chains = 0.0, []
        for point in check_points:
            n, each = point[2], dataclasses.replace(LeverBox.lever(task, point[:2]), law=law)
            try:
                chain = float(rebound_amplitude_mm(each, n, t_deg))
            except RollerLeftCam as exc:
                return clock.result(Status.INACCURATE, values, message=f"the chain at {points_text([point])}: {exc}",
                                    arrays=arrays, diagnostics=diagnostics)
            own = predicted_rebounds_mm(LeverBox.lever(task, point[:2]), law, t_deg, [n], lever=lever)[0][0]
            worst_gap = max(worst_gap, abs(chain - own) / max(limit, 1e-300))
            chains.append(chain)
            if point[:2] == nominal:
                values[f"rebound_chain_mm_{speed_tag(n)}"] = chain
                values[f"rebound_predicted_mm_{speed_tag(n)}"] = own
        values["chain_rel_diff"] = worst_gap
        values["rebound_max_chain_mm"] = max(chains)
        diagnostics["chain_points"] = [list(p) + [c] for p, c in zip(check_points, chains)]
        if worst_gap > agreement_rel:
            status = Status.INACCURATE
        over = values["rebound_max_chain_mm"] - limit
        if objective != "least_rebound" and over > agreement_rel * limit:
            status = Status.INACCURATE
            message += f"; the chain's rebound exceeds amplitude_limit_mm by {over:.3g} mm"
        message += (f"; the chain (CVODES + eq. (2)) agrees with the linear prediction to {worst_gap:.1e} of the "
                    f"limit at {len(check_points)} points (tolerance {agreement_rel:g})")
    if not box.trivial:
        diagnostics |= box_values(task, law, t_deg, band, box, dense_step_rpm, lever, values, "")
        if robust and compare and objective == "least_phase":
            beside(task, band, phase_from_deg, phase_to_deg, phase_tol_deg, common, box, values, diagnostics)
    if compare:
        compare_laws(task, law, t_deg, sorted({p[2] for p in design.speeds if p[:2] == box.nominal(task)}), values)
    sampled = [p[2] if box.trivial else list(p) for p in design.speeds]
    shape = {"base_radius_mm": cam_base_radius_mm, "roller_radius_mm": cam_roller_radius_mm,
             "centre_distance_mm": cam_centre_distance_mm, "dwell_deg": cam_dwell_deg}
    shop, said = law_cam(task, law, t_deg, shape) if shop_cam else ({}, {"cam": {"geometry": shape}})
    return clock.result(status, values, message=message,
                        arrays=arrays | shop, diagnostics=diagnostics | said | {"sampled_speeds_rpm": sampled,
                                                                  "law_knots": list(law.knots),
                                                                  "law_coefficients": list(law.coefficients)},
                        warnings=warnings)


def _unsolved(design, values, diagnostics, clock, t_deg, limit, task=None, band=None, step=5.0):
    """No law: the status and what binds; with a best law (the limit missed), the best achievable
    rebound over the band and the speed where it is set."""
    values = values | {"t_deg": t_deg}
    if design.law is not None and task is not None:
        dense = band_speeds(band, step)
        pred = [p[0] for p in predicted_rebounds_mm(task, design.law, t_deg, dense)]
        worst = int(np.argmax(pred))
        values |= {"rebound_best_mm": pred[worst], "rebound_best_speed_rpm": float(dense[worst])}
    return clock.result(design.status, values, message=design.message, violated=design.violated,
                        diagnostics=diagnostics)
