"""The lift cam for the shop: the cam's shape from its law and follower
(models/cam_shape.py), its checks (least radius of curvature, largest pressure angle, undercut
margin) and the point tables a DXF or a CNC takes, each with its measured chordal error. A law
solver (the synthesis, the co-design) returns its law's cam as point tables too (`law_cam`), so the
shop's drawing reads that Result's arrays (`mechopt.cam_sheet.sheet_of`)."""

import math

import numpy as np

from mechopt.kit.errors import ModelError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval
from mechopt.models.cam_shape import FLANKS, CamShape, Law, check_undercut, flank, pitch, point_table, summarise

__all__ = ["SHOP_PREFIX", "cam_profile", "law_cam", "shape_cam", "without_cam"]

FLANK_ARRAYS = {"inner": "profile", "outer": "groove_outer"}     # the arrays' names per flank


def cam_profile(task: CamShape, *, samples: Annotated[int, Interval(ge=360, le=1_000_000)] = 7200) -> Result:
    """The cam's pitch curve and profile flank(s) as point tables within `task.chord_tol_mm`, and
    its checks: `min_radius_of_curvature_mm` (the pitch curve's least convex radius), the least
    concave one for a groove, `max_pressure_angle_deg`, `undercut_margin_mm` (least |rho| - r over
    the flanks made), `chord_error_mm` (the largest measured over the tables). Checks are taken on
    `samples` cam angles, each extreme polished between its neighbours.

    INFEASIBLE, violated `undercut` (no flank is made; the message names the
    cam angle) or `pressure_angle` (above `max_pressure_angle_deg`; the tables are still made).

    Example: `cam_profile(CamShape(base_radius_mm=40, roller_radius_mm=10, stroke_mm=20,
    rise_deg=90, return_deg=90))`.
    """
    return shape_cam(task, None, samples=samples)


def shape_cam(task: CamShape, law: Law | None, *, samples: int = 7200) -> Result:
    """`cam_profile` with any law in place of the task's library law (`law` None): a synthesised
    law enters as `models.cam_shape.tabulated_law(xi, S, dS, ddS)`."""
    clock = Clock()
    s = summarise(task, law, samples=samples)
    values = {"min_radius_of_curvature_mm": s.min_convex_radius_mm, "min_radius_deg": s.min_convex_deg,
              "max_pressure_angle_deg": s.max_pressure_angle_deg, "max_pressure_at_deg": s.max_pressure_deg,
              "undercut_margin_mm": s.undercut_margin_mm}
    if np.isfinite(s.min_concave_radius_mm):
        values |= {"min_concave_radius_mm": s.min_concave_radius_mm, "min_concave_deg": s.min_concave_deg}
    breaks = task.phase_ends_rad()
    tables = {"pitch": point_table(lambda t: pitch(task, t, law).P, task.chord_tol_mm, breaks=breaks)}
    violated, said = [], []
    try:
        check_undercut(task, s)
    except ModelError as exc:           # the model's words, naming the cam angle: a status here, not a raise
        violated.append("undercut")
        said.append(f"{exc}; no profile is made")
    if not violated:
        for side in FLANKS[task.closure]:
            tables[FLANK_ARRAYS[side]] = point_table(lambda t, side=side: flank(task, t, side, law),
                                                     task.chord_tol_mm, breaks=breaks)
    if s.max_pressure_angle_deg > task.max_pressure_angle_deg:
        violated.append("pressure_angle")
        said.append(f"pressure angle {s.max_pressure_angle_deg:.3f} deg at cam angle {s.max_pressure_deg:.3f} deg "
                    f"exceeds max_pressure_angle_deg={task.max_pressure_angle_deg:g}")
    values["chord_error_mm"] = max(t.chord_error_mm for t in tables.values())
    values["profile_points"] = float(sum(t.t.size for name, t in tables.items() if name != "pitch"))
    arrays = _dense(task, law, samples)
    for name, table in tables.items():
        arrays |= {f"{name}_x_mm": table.xy[:, 0], f"{name}_y_mm": table.xy[:, 1],
                   f"{name}_cam_angle_deg": np.degrees(table.t)}
    status = Status.INFEASIBLE if violated else Status.SOLVED
    message = "; ".join(said) if said else (f"{len(tables) - 1} flank(s) and the pitch curve within "
                                            f"{values['chord_error_mm']:.4g} mm of their chords")
    return clock.result(status, values, message=message, violated=tuple(violated), arrays=arrays,
                        diagnostics={"undercut_flank": s.undercut_flank, "closure": task.closure,
                                     "follower": task.follower, "roller_radius_mm": task.roller_radius_mm,
                                     "chord_error_mm": {name: t.chord_error_mm for name, t in tables.items()}})


def _dense(task, law, samples):
    """The pitch curve's radius of curvature and pressure angle against the cam angle (figures)."""
    theta = np.linspace(0.0, 2 * np.pi, min(samples, 3600), endpoint=False)
    p = pitch(task, theta, law)
    return {"cam_angle_deg": np.degrees(theta), "radius_of_curvature_mm": np.clip(p.radius_mm, -1e6, 1e6),
            "pressure_angle_deg": np.degrees(p.pressure_rad)}


# ---------------------------------------------------------------- a synthesised law's cam, for the shop

SHOP_PREFIX = "cam_"        # a law solver's arrays of its cam: cam_pitch_x_mm ... (`law_cam`)
SHOP_TABLES = ("pitch", *FLANK_ARRAYS.values())


def law_cam(lever, law, t_deg: float, geometry: dict, *, samples: int = 7200) -> tuple[dict, dict]:
    """(arrays, diagnostics) a law solver adds to its Result for the shop: the lift cam cut to
    `law` (a spline law: `law.values(xi)` -> S, S', S'', ...) at phase angle `t_deg` [deg], an
    oscillating roller follower in a groove turning counter-clockwise, the lever's arms and stroke
    (`lever.a_mm`, `b_mm`, `stroke_mm`), the rise and the return with the same law over t (as
    stop-impact/lift-cam-profile reads its return), and `geometry`: base_radius_mm,
    roller_radius_mm, centre_distance_mm, dwell_deg (upper) [mm, deg], and any other `CamShape`
    parameter (max_pressure_angle_deg, chord_tol_mm: CamShape's defaults where not given).

    Arrays: its point tables (`shape_cam`: the cam frame at cam angle 0, where the rise begins)
    as `cam_<table>_x_mm`, `_y_mm`, `_cam_angle_deg` for the pitch curve, the profile (the groove's
    inner wall) and the groove's outer wall. Diagnostics `cam`: status and message, `geometry`,
    `t_deg`, each table's measured chordal error, `rise_start_deg` (the roller centre's direction
    as the rise begins, from +x counter-clockwise) and `sense`, the largest pressure angle and the
    least radius of curvature. A cam that cannot be made or is not SOLVED has no tables (its
    message says why: the shop's drawing refuses it)."""
    said = {"geometry": dict(geometry), "t_deg": float(t_deg), "sense": "ccw"}
    try:
        shape = CamShape(stroke_mm=lever.stroke_mm, rise_deg=t_deg, return_deg=t_deg, a_mm=lever.a_mm,
                         b_mm=lever.b_mm, follower="oscillating", closure="groove", **geometry)
    except ModelError as exc:
        return {}, {"cam": said | {"status": Status.INFEASIBLE.value, "message": f"the cam cannot be made: {exc}"}}
    cam = shape_cam(shape, lambda xi: tuple(law.values(xi)[:3]), samples=samples)
    said |= {"status": cam.status.value, "message": cam.message}
    said |= {k: cam.values[k] for k in ("max_pressure_angle_deg", "min_radius_of_curvature_mm") if k in cam.values}
    if cam.status is not Status.SOLVED:
        return {}, {"cam": said}
    a = cam.arrays
    arrays = {f"{SHOP_PREFIX}{name}_{axis}": a[f"{name}_{axis}"] for name in SHOP_TABLES if f"{name}_x_mm" in a
              for axis in ("x_mm", "y_mm", "cam_angle_deg")}
    said |= {"chord_error_mm": cam.diagnostics["chord_error_mm"],
             "rise_start_deg": math.degrees(math.atan2(a["pitch_y_mm"][0], a["pitch_x_mm"][0]))}
    return arrays, {"cam": said}


def without_cam(arrays: dict) -> dict:
    """`arrays` less a law solver's cam tables (`law_cam`): for a caller that cuts its own cam."""
    return {k: v for k, v in arrays.items() if not k.startswith(SHOP_PREFIX)}
