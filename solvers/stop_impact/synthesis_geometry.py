"""The synthesis with its cam's geometry (solvers/stop_impact/synthesis.py, `geometry`): the
pressure angle and the radius of curvature held by sequential LPs around the law (the rows
linearised at the last law, solvers/stop_impact/cam_rows.py), what binds, and where no law of the
space meets the pressure-angle limit, the least angle it reaches."""
import dataclasses

import numpy as np

from mechopt.kit.result import Status
from mechopt.models.cam_follower import law_values
from mechopt.solvers.stop_impact.cam_rows import TRUST, least_pressure_angle
from mechopt.solvers.stop_impact.window_lp import kinematic_rows, linear_lever

__all__ = ["BINDS_WITHIN", "geometry_steps", "geometry_values", "least_angle"]

BINDS_WITHIN = (0.1, 0.1)       # a geometry limit binds when the exact value is this near it [deg, mm]


def geometry_steps(task, t_deg, band_rpm, geometry, settings, design):
    """The law without the cam's geometry, then while its exact geometry (`CamGeometry.check`)
    breaks a limit: the window LP again with the geometry rows linearised at the last law, its
    coefficients within TRUST of it, each family's limit lowered by the exact excess of the laws
    the linearised rows gave so far (their error; solvers/stop_impact/cam_rows.py); the speeds and
    window of the last law carried (`design`: the search's law at one t, synthesis_search). SOLVED
    when the exact geometry holds; the LP's own status when a step has no law; LIMIT after
    `geometry.steps` steps."""
    lever = linear_lever(settings.get("coefficients", 100), settings.get("continuity", 2))
    d, backoff, check = design(task, t_deg, band_rpm, **settings), {"pressure_angle": 0.0, "curvature_kappa": 0.0}, None
    for step in range(geometry.steps + 1):
        if d.status is not Status.SOLVED:
            said = f" (geometry step {step}: the rows linearised at the last law, its coefficients within {TRUST:g})"
            return dataclasses.replace(d, geometry_steps=step, message=d.message + (said if step else ""))
        check = geometry.check(d.law, t_deg)
        if check.holds():
            return dataclasses.replace(d, geometry=check, geometry_steps=step)
        if step == geometry.steps:
            break
        if step:        # a law of the linearised rows that breaks the exact limit: the rows' error, backed off
            backoff["pressure_angle"] += max(check.excess["pressure_angle"], 0.0)
            least = geometry.least_radius_mm
            if check.excess["curvature"] > 0:           # rho short by v: kappa over 1 / least by this
                backoff["curvature_kappa"] += 1.0 / max(least - check.excess["curvature"], 1e-3 * least) - 1.0 / least
        rows, c_k = geometry.linearised(lever, d.c, t_deg, backoff), d.c

        def extra(lp_rows, rows=rows, c_k=c_k):
            lp_rows.bound("c", c_k - TRUST, c_k + TRUST)
            for family, G, upper in rows:
                lp_rows.le(family, [("c", G)], upper)
        d = design(task, t_deg, band_rpm, **settings | {"samples": d.speeds, "around": d.window_xi, "extra": extra})
    return dataclasses.replace(
        d, status=Status.LIMIT, geometry=check, geometry_steps=geometry.steps,
        message=f"the cam's geometry at t = {t_deg:.6g} deg still breaks its limits after {geometry.steps} "
                f"sequential LPs (geometry_steps): pressure angle {check.pressure_deg:.4g} deg "
                f"(max_pressure_angle_deg={geometry.max_pressure_angle_deg:g}), least radius of curvature "
                f"{min(check.convex_mm, check.concave_mm):.4g} mm (bound {geometry.least_radius_mm:g} mm)")


def geometry_values(cam, design):
    """The synthesised law's cam: pressure angles, least radii, which geometry limit binds."""
    check = design.geometry
    return {"max_pressure_angle_rise_deg": check.pressure_rise_deg,
            "max_pressure_angle_return_deg": check.pressure_return_deg,
            "min_radius_of_curvature_mm": check.convex_mm, "min_concave_radius_mm": check.concave_mm,
            "pressure_angle_binds": float(check.excess["pressure_angle"] >= -BINDS_WITHIN[0]),
            "curvature_binds": float(check.excess["curvature"] >= -BINDS_WITHIN[1]),
            "geometry_steps_taken": float(design.geometry_steps)}


def least_angle(design, cam, task, t_deg, bounds, coefficients, continuity, values):
    """No law at the bracket's top: the least largest pressure angle the sequential steps reach
    there, the lever left out (`cam_rows.least_pressure_angle`, from the cycloid's fit), named in
    the message and `least_pressure_angle_deg`."""
    lever = linear_lever(coefficients, continuity)
    (s0, B), *_ = lever.kin
    rise = lever.rise
    c0 = np.linalg.lstsq(B[np.flatnonzero(rise)].toarray(), law_values("cycloidal", lever.xi[rise])[0] - s0[rise], rcond=None)[0]
    least, steps = least_pressure_angle(cam, lever, t_deg, c0,
                                        lambda rows: kinematic_rows(rows, lever, t_deg, task.stroke_mm, bounds))
    values["least_pressure_angle_deg"] = least
    if least <= cam.max_pressure_angle_deg:
        return design
    return dataclasses.replace(
        design, violated=tuple(dict.fromkeys(design.violated + ("pressure_angle",))),
        message=design.message + f"; the least largest pressure angle a law of the space reaches at t = {t_deg:g} deg "
                                 f"(the lever left out, {steps} sequential LPs) is {least:.4g} deg > "
                                 f"max_pressure_angle_deg={cam.max_pressure_angle_deg:g}")
