"""A posed cam's sizing figures (models/cam_followers.py, cam_geometry.py, cam_forces.py): what a
designer reads before cutting it."""
import math

import numpy as np

from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval
from mechopt.models.cam_followers import CamFollower
from mechopt.models.cam_forces import (
    contact_radius_mm,
    effective_modulus_MPa,
    follower_force_N,
    hertz_MPa,
    jump_speed,
    omega_rad_s,
    sign_changes,
)
from mechopt.models.cam_geometry import groove_outer_wall
from mechopt.models.cam_shape import point_table
from mechopt.solvers.cam.extremes import polished_min

__all__ = ["size_cam", "pressure_peaks", "convex_min"]

MOVING = 1e-9       # |s'| [mm/rad] above which the follower rises or returns (a dwell below)
Samples = Annotated[int, Interval(ge=360, le=1_000_000)]
SHOWN_ANGLES = 8    # crossover angles a message names
LOCKED = 1e-9       # n . g at or below this: the pressure angle is 90 deg, the follower cannot be driven


def pressure_peaks(task: CamFollower, theta, curves, ds, base_mm=None) -> dict[str, float]:
    """The largest |pressure angle| on the rise (s' > 0) and on the return (s' < 0) [deg], each
    with its signed value and cam angle [deg], polished between samples (`curves` at `theta`)."""
    phi = curves.pressure_rad
    out = {}
    for name, moving in (("rise", ds > MOVING), ("return", ds < -MOVING)):
        def minus_abs(t, moving_sign=1 if name == "rise" else -1):
            c = task.curves(t, base_mm)
            rate = task.lift(t)[1] * moving_sign
            return np.where(rate > MOVING, -np.abs(c.pressure_rad), np.inf)
        value, at = polished_min(minus_abs, theta, -np.abs(phi), moving)
        if math.isfinite(value):
            signed = float(task.curves(np.array([at]), base_mm).pressure_rad[0])
            out |= {f"max_pressure_angle_{name}_deg": -math.degrees(value),
                    f"pressure_angle_{name}_signed_deg": math.degrees(signed),
                    f"max_pressure_{name}_at_deg": math.degrees(at)}
    return out


def convex_min(task: CamFollower, theta, radius, which: str, base_mm=None) -> tuple[float, float]:
    """(least convex radius of curvature [mm], cam angle [rad]) of the pitch curve (`which` =
    "pitch") or the profile ("profile"), polished; a flat face's profile may go <= 0 (a cusp)
    and is searched whole."""
    attr = f"{which}_radius_mm"
    flat = task.face == "flat"

    def f(t):
        r = getattr(task.curves(t, base_mm), attr)
        return r if flat else np.where(r > 0, r, np.inf)
    return polished_min(f, theta, radius if flat else np.where(radius > 0, radius, np.inf))


def size_cam(task: CamFollower, *, samples: Samples = 7200,
             chord_tol_mm: Annotated[float, Interval(gt=0, le=1)] = 0.01) -> Result:
    """The cam's sizing figures over `samples` cam angles (extremes polished between samples):

    * pressure angle: `max_pressure_angle_rise_deg` and `_return_deg` (|phi|, with the signed
      value and cam angle; the sense of rotation is the task's `sense`);
    * radius of curvature: `min_pitch_radius_mm` and `min_profile_radius_mm` (convex, with cam
      angles); a roller with the pitch curve's convex radius at or below its own is undercut
      (violated `undercut`, at its cam angle); a flat face's profile radius Rb + s + s''-like
      at or below `min_profile_radius_mm` is a cusp (violated `cusp`);
    * flat face: the contact point's travel along the face (`face_contact_min_mm`, `_max_mm`,
      `face_travel_mm`) and the width a face centred at `face_centre_mm` needs; a narrower
      `face_width_mm` is violated `face_width`;
    * forces, when `speed_rpm`, `mass_kg` or a spring is given: the follower force Q and contact
      force N over the cycle, `min_follower_force_N`; spring-closed: `jump_speed_rpm` and its cam
      angle (Q < 0 at the task's speed: violated `jump`, status `on_jump`); groove: the
      crossovers (sign changes of N, each an impact across `backlash_mm`) and their angles;
    * at `report_angle_deg` (if given): s and the follower and contact forces;
    * Hertz stress (`roller_width_mm` > 0): `max_contact_stress_MPa` and its cam angle;
    * `pressure_angle` violated when above `max_pressure_angle_deg`.

    Arrays: the cam angle, s, the pressure angle, radii, forces and stress over `samples` angles;
    the cam as the shop takes it in the cam frame (the cam at cam angle 0), point tables within
    `chord_tol_mm` of the curves: `pitch_x_mm`/`_y_mm` (a flat face: the profile), `profile_...`
    and a groove's `groove_outer_...` (none where the profile is undercut or cusped), their
    measured chordal errors in diagnostics `chord_error_mm`. Diagnostics `rise_start_deg`: the
    direction (cam frame, from +x) of the roller centre (a flat face: its foot) where the first
    rise begins; `sense`.
    """
    clock = Clock()
    theta = np.linspace(0.0, 2 * math.pi, samples, endpoint=False)
    lift = task.lift(theta)
    s, ds, dds = lift
    c = task.curves(theta, lift=lift)
    values = pressure_peaks(task, theta, c, ds)
    values["max_pressure_angle_deg"] = max((values.get(f"max_pressure_angle_{k}_deg", 0.0)
                                            for k in ("rise", "return")), default=0.0)
    violated, said, arrays = [], [], {}
    if values["max_pressure_angle_deg"] > task.max_pressure_angle_deg:
        violated.append("pressure_angle")
        worst = max(("rise", "return"), key=lambda k: values.get(f"max_pressure_angle_{k}_deg", -1.0))
        said.append(f"pressure angle {values['max_pressure_angle_deg']:.3f} deg on the {worst} (cam angle "
                    f"{values[f'max_pressure_{worst}_at_deg']:.2f} deg, {task.sense}) exceeds "
                    f"max_pressure_angle_deg={task.max_pressure_angle_deg:g}")
    _curvature(task, theta, c, values, violated, said)
    if task.face == "flat":
        _face_width(task, c, values, violated, said, arrays)
    if task.speed_rpm > 0 or task.spring_rate_N_per_mm > 0 or task.preload_N > 0:
        _forces(task, theta, s, dds, c, values, violated, said, arrays)
    arrays |= {"cam_angle_deg": np.degrees(theta), "s_mm": s, "ds_mm_per_rad": ds, "dds_mm_per_rad2": dds,
               "pressure_angle_deg": np.degrees(c.pressure_rad),
               "pitch_radius_mm": np.clip(c.pitch_radius_mm, -1e6, 1e6),
               "profile_radius_mm": np.clip(c.profile_radius_mm, -1e6, 1e6)}
    errors = _shop_tables(task, chord_tol_mm, shapeless=bool({"undercut", "cusp"} & set(violated)), arrays=arrays)
    only_jump = violated == ["jump"]
    status = (Status.SOLVED if not violated else Status.LIMIT if only_jump and task.on_jump == "LIMIT"
              else Status.INFEASIBLE)
    message = "; ".join(said) if said else (f"{task.follower} {task.face} follower, {task.sense} cam: "
                                            f"pressure angle {values['max_pressure_angle_deg']:.3f} deg at most")
    return clock.result(status, values, message=message, violated=tuple(violated), arrays=arrays,
                        diagnostics={"follower": task.follower, "face": task.face, "sense": task.sense,
                                     "closure": task.closure, "samples": samples, "chord_error_mm": errors,
                                     "rise_start_deg": _rise_start_deg(task)})


def _curvature(task, theta, c, values, violated, said):
    """Least convex radii; an undercut roller or a cusped flat face named at its cam angle."""
    rho_pitch, at_pitch = convex_min(task, theta, c.pitch_radius_mm, "pitch")
    rho_prof, at_prof = convex_min(task, theta, c.profile_radius_mm, "profile")
    if math.isfinite(rho_pitch):
        values |= {"min_pitch_radius_mm": rho_pitch, "min_pitch_radius_at_deg": math.degrees(at_pitch)}
    if math.isfinite(rho_prof):
        values |= {"min_profile_radius_mm": rho_prof, "min_profile_radius_at_deg": math.degrees(at_prof)}
    if task.face == "roller":
        if math.isfinite(rho_pitch) and rho_pitch <= task.roller_radius_mm + task.min_profile_radius_mm:
            violated.append("undercut")
            said.append(f"undercut: the pitch curve's convex radius of curvature {rho_pitch:.4g} mm at cam angle "
                        f"{math.degrees(at_pitch):.3f} deg is at or below roller_radius_mm={task.roller_radius_mm:g}"
                        + (f" + min_profile_radius_mm={task.min_profile_radius_mm:g}" if task.min_profile_radius_mm
                           else "") + "; a smaller roller or a larger base_radius_mm")
    elif rho_prof <= task.min_profile_radius_mm:
        violated.append("cusp")
        said.append(f"cusp: the profile's radius of curvature {rho_prof:.4g} mm at cam angle {math.degrees(at_prof):.3f}"
                    f" deg is at or below min_profile_radius_mm={task.min_profile_radius_mm:g} (the flat face "
                    "cannot follow it); a larger base_radius_mm")


def _face_width(task, c, values, violated, said, arrays):
    """The contact point's travel along a flat face, and the face it needs."""
    x = task.face_coordinate_mm(c)
    lo, hi = float(x.min()), float(x.max())
    need = 2 * max(abs(lo - task.face_centre_mm), abs(hi - task.face_centre_mm))
    values |= {"face_contact_min_mm": lo, "face_contact_max_mm": hi, "face_travel_mm": hi - lo,
               "face_width_needed_mm": need}
    arrays["face_contact_mm"] = x
    if task.face_width_mm > 0 and task.face_width_mm < need:
        violated.append("face_width")
        said.append(f"face_width_mm={task.face_width_mm:g} is narrower than the face needed: the contact point runs "
                    f"from {lo:.3f} to {hi:.3f} mm along the face (travel {hi - lo:.3f} mm); a face centred at "
                    f"face_centre_mm={task.face_centre_mm:g} needs {need:.3f} mm")


def _forces(task, theta, s, dds, c, values, violated, said, arrays):
    """Follower and contact forces, the jump speed or the groove's crossovers, Hertz stress."""
    omega = omega_rad_s(task.speed_rpm)
    Q = follower_force_N(task, s, dds, omega)
    i = int(np.argmin(Q))
    values |= {"min_follower_force_N": float(Q[i]), "min_follower_force_at_deg": math.degrees(theta[i])}
    arrays["follower_force_N"] = Q
    locked = c.lever <= LOCKED
    if locked.any():                # the normal stands across the follower's motion: no force moves it
        j = int(np.argmax(locked))
        said.append(f"the pressure angle reaches 90 deg at cam angle {math.degrees(theta[j]):.2f} deg: the follower "
                    "locks there; no contact force or stress is computed")
        return
    N = Q / c.lever
    values["max_contact_force_N"] = float(np.abs(N).max())
    arrays["contact_force_N"] = N
    if task.closure == "spring":
        rpm, at = jump_speed(task, theta, s, dds)
        if math.isfinite(rpm):
            values |= {"jump_speed_rpm": rpm, "jump_at_deg": math.degrees(at)}
        if Q[i] < 0:
            violated.append("jump")
            off = np.degrees(sign_changes(theta, Q))      # the force falls through 0 (leaves) and rises (lands)
            arrays["lift_off_deg"] = off
            said.append(f"the spring cannot hold the follower at speed_rpm={task.speed_rpm:g}: the follower force "
                        f"falls to {Q[i]:.4g} N at cam angle {math.degrees(theta[i]):.2f} deg; it leaves the cam "
                        f"and lands again at cam angles {_angles(off)} deg; jump speed {rpm:.4g} rpm; a stiffer "
                        "spring or a larger preload_N")
    else:
        cross = np.degrees(sign_changes(theta, N))
        values["crossovers"] = float(cross.size)
        arrays["crossover_deg"] = cross
        if cross.size:
            said.append(f"groove: the contact force changes sign {cross.size} times per turn (cam angles "
                        f"{_angles(cross)} deg): the roller crosses to the other wall "
                        f"across backlash_mm={task.backlash_mm:g}, an impact each time (not lift-off)")
    if task.report_angle_deg is not None:
        at = np.array([math.radians(task.report_angle_deg)])
        s1, _, dds1 = task.lift(at)
        q = follower_force_N(task, s1, dds1, omega)
        values |= {"s_at_report_mm": float(s1[0]), "follower_force_at_report_N": float(q[0]),
                   "contact_force_at_report_N": float(q[0] / task.curves(at).lever[0])}
    if task.roller_width_mm > 0:
        R = contact_radius_mm(task, c, N)
        p = hertz_MPa(N, task.roller_width_mm, effective_modulus_MPa(task), R)
        if task.closure == "spring":
            p = np.where(N >= 0, p, 0.0)            # off the cam: no contact
        j = int(np.argmax(p))
        values |= {"max_contact_stress_MPa": float(p[j]), "max_contact_stress_at_deg": math.degrees(theta[j])}
        arrays["contact_stress_MPa"] = p


def _angles(degrees) -> str:
    """The first SHOWN_ANGLES cam angles, '...' for more."""
    return ", ".join(f"{a:.2f}" for a in degrees[:SHOWN_ANGLES]) + (" ..." if len(degrees) > SHOWN_ANGLES else "")


def _shop_tables(task, tol_mm, *, shapeless, arrays) -> dict[str, float]:
    """The cam's curves as point tables within `tol_mm` (models/cam_shape.point_table, the segment
    joins among the points) into `arrays`; their measured chordal errors. An undercut or cusped
    profile is not made (a roller's pitch curve still is; a flat face's is its profile)."""
    breaks = tuple(getattr(task.motion, "starts_rad", ()))
    curves = {"pitch": lambda t: task.curves(t).pitch} if task.face == "roller" or not shapeless else {}
    if not shapeless:
        curves["profile"] = lambda t: task.curves(t).profile
        if task.closure == "groove":
            curves["groove_outer"] = lambda t: groove_outer_wall(task.curves(t))      # P + r n
    errors = {}
    for name, curve in curves.items():
        table = point_table(curve, tol_mm, breaks=breaks)
        arrays |= {f"{name}_x_mm": table.xy[:, 0], f"{name}_y_mm": table.xy[:, 1],
                   f"{name}_cam_angle_deg": np.degrees(table.t)}
        errors[name] = table.chord_error_mm
    return errors


def _rise_start_deg(task) -> float:
    """Where the first rise begins: the direction of the roller centre (a flat face: the foot of
    its perpendicular) seen from the cam at cam angle 0 [deg] (cam angle 0 where the motion names
    no segments)."""
    segments = getattr(task.motion, "segments", ())
    start = next((math.radians(seg.start_deg) for seg in segments if getattr(seg, "kind", "") == "rise"), 0.0)
    p = task.curves(np.array([start])).pitch[:, 0]      # at the rise start s' = 0: a flat face's contact is its foot
    return math.degrees(math.atan2(p[1], p[0]))
