"""A disc cam with a follower of any of the four usual kinds, posed from a file: translating
(stem offset e) or oscillating (pivot distance, arm); roller or flat face; spring- or
form-closed (a groove with its backlash); the cam's sense of rotation. The follower's motion
s(theta) [mm] comes from the cam's segments (`models/cam_motion.py`) or any object with
`at(theta_rad) -> (s, s', s'', s''')`; its geometry is `models/cam_geometry.py`'s, its forces
`models/cam_forces.py`'s.

Layouts (fixed frame, cam centre O at the origin, the follower above it):

* translating roller: the roller centre R = (e, s0 + s), s0 = sqrt(Rp^2 - e^2), Rp = base +
  roller radius (prime circle);
* translating flat face: the face m . X = Rb + s with m = (0, 1), perpendicular to the stem
  (the stem's offset moves the face's middle, not its line);
* oscillating: pivot A = (d, 0), the arm at psi from the line A -> O, psi = psi0 + s / L: the
  follower's motion s is read as the arc run by the point at L = `arm_mm` from the pivot (the
  roller centre for a roller; a stated reading: a segment's `lift_mm` is an arc there). Roller:
  R = A + L (-cos psi, sin psi), psi0 from |R| = Rp. Flat face: the face parallel to the arm at
  `face_offset_mm` f from the pivot on the cam's side, normal m = (sin psi, cos psi), distance
  p = d sin psi - f from O, psi0 from p = Rb.

Contact coordinates along a flat face (the face width it needs) are measured from the stem's axis
(translating, positive +x) or from the foot of the perpendicular from the pivot (oscillating,
positive towards the cam's side of the pivot along the arm). Lengths in mm, angles in rad.
"""
import math
from dataclasses import dataclass
from typing import Annotated, ClassVar, Literal

import numpy as np
from annotated_types import Ge, Gt, Interval, Le, doc

from mechopt.kit.errors import require
from mechopt.kit.settings import check_fields
from mechopt.models.cam_geometry import CamCurves, flat_cam, quarter, roller_cam
from mechopt.models.cam_motion import CamMotion

SENSE = {"ccw": 1, "cw": -1}
Length = Annotated[float, Ge(0), Le(100_000)]


@dataclass(frozen=True)
class CamFollower:
    """A disc cam and its follower (module docstring), with what sizes it.

    Geometry: `base_radius_mm` (least radius of the cam's surface), `roller_radius_mm` (roller),
    `offset_mm` e (translating), `pivot_distance_mm` d and `arm_mm` L (oscillating),
    `face_offset_mm` (oscillating flat face: pivot to face), `face_width_mm` with its middle at
    `face_centre_mm` along the face (flat; 0: width not checked), `sense` ("ccw" or "cw").
    Closure: "spring" (`spring_rate_N_per_mm`, `preload_N` at s = 0, pressing the follower on the
    cam) or "groove" (form-closed, `backlash_mm`); `mass_kg` the follower's (oscillating: its
    equivalent at L), `external_force_N` a constant load pressing it towards the cam,
    `speed_rpm` the cam's speed. Contact stress: `roller_width_mm` (face or roller width in
    contact; 0: not computed), Young's moduli and Poisson's ratios of cam and follower. Limits:
    `max_pressure_angle_deg`, `min_profile_radius_mm` (the profile's least convex radius allowed;
    0: only > 0, no cusp or undercut), `base_radius_min_mm`/`base_radius_max_mm` (the least base
    radius search's bounds), `on_jump` (the status when the spring cannot hold the follower at
    `speed_rpm`: INFEASIBLE or LIMIT, as the scene asks), `report_angle_deg` (a cam angle whose
    follower and contact forces are reported, as a textbook problem asks them). For the shop
    (`mechopt run --dxf`): `bore_diameter_mm` (0: not stated) and `rise_start_shaft_deg`, the
    machine shaft's angle at which the rise begins (the cam's phase, where the scene states it). Motion: `segments` (the cam's segments,
    read by `models/cam_motion.py`, with its `joins`: "warn" or "refuse" a step of s' or s''
    where segments meet) or `motion` (an object with `at`).
    """
    base_radius_mm: Annotated[float, Gt(0), Le(100_000)]
    follower: Literal["translating", "oscillating"] = "translating"
    face: Literal["roller", "flat"] = "roller"
    sense: Literal["ccw", "cw"] = "ccw"
    roller_radius_mm: Length = 0.0
    offset_mm: Annotated[float, doc("|offset| < base + roller radius"), Interval(ge=-100_000, le=100_000)] = 0.0
    pivot_distance_mm: Length = 0.0
    arm_mm: Length = 0.0
    face_offset_mm: Annotated[float, doc("base + face offset < pivot distance"),
                              Interval(ge=-100_000, le=100_000)] = 0.0
    face_width_mm: Length = 0.0
    face_centre_mm: Annotated[float, Interval(ge=-100_000, le=100_000)] = 0.0
    closure: Literal["spring", "groove"] = "spring"
    backlash_mm: Annotated[float, Ge(0), Le(10)] = 0.0
    mass_kg: Annotated[float, Ge(0), Le(100_000)] = 0.0
    spring_rate_N_per_mm: Annotated[float, Ge(0), Le(1e7)] = 0.0
    preload_N: Annotated[float, Ge(0), Le(1e8)] = 0.0
    external_force_N: Annotated[float, Interval(ge=-1e8, le=1e8)] = 0.0
    speed_rpm: Annotated[float, Ge(0), Le(100_000)] = 0.0
    roller_width_mm: Length = 0.0
    cam_E_MPa: Annotated[float, Gt(0), Le(1e7)] = 206_000.0
    cam_nu: Annotated[float, Interval(ge=0, lt=0.5)] = 0.3
    follower_E_MPa: Annotated[float, Gt(0), Le(1e7)] = 206_000.0
    follower_nu: Annotated[float, Interval(ge=0, lt=0.5)] = 0.3
    max_pressure_angle_deg: Annotated[float, Interval(gt=0, lt=90)] = 30.0
    min_profile_radius_mm: Length = 0.0
    base_radius_min_mm: Length = 0.0
    base_radius_max_mm: Length = 0.0
    on_jump: Literal["INFEASIBLE", "LIMIT"] = "INFEASIBLE"
    report_angle_deg: Annotated[float | None, Interval(ge=0, lt=360)] = None
    bore_diameter_mm: Annotated[float, Ge(0), Le(100_000), doc("0: not stated, no drawing for the shop")] = 0.0
    rise_start_shaft_deg: Annotated[float, Interval(ge=0, lt=360)] = 0.0
    joins: Literal["warn", "refuse"] = "warn"
    segments: object | None = None
    motion: object | None = None

    # the segments may come from a CSV beside the scene (columns segment, law, angle_deg, lift_mm)
    CSV_TABLES: ClassVar[dict] = CamMotion.CSV_TABLES

    def __post_init__(self):
        check_fields(self)
        if self.motion is None:
            require(self.segments is not None, "no motion: give the cam's `segments` (rise, dwell, return ...)",
                    key="segments")
            object.__setattr__(self, "motion", motion_of_segments(self.segments, self.joins))
        require(callable(getattr(self.motion, "at", None)), "motion: expected an object with at(theta_rad) -> "
                "(s, s', s'', s''')", key="motion")
        self.check_layout(self.base_radius_mm)
        if self.closure == "groove":
            require(self.face == "roller", "closure='groove' takes a roller follower (a groove has two walls "
                    "for one roller); a flat face is spring-closed", key="closure")
        lo, hi = self.base_radius_min_mm, self.base_radius_max_mm
        require(hi == 0 or 0 < lo < hi, f"base_radius_min_mm={lo:g}, base_radius_max_mm={hi:g}: allowed 0 < min < max "
                "(both 0: no least base radius search)", key="base_radius_min_mm")

    def check_layout(self, base_mm: float) -> None:
        """ModelError naming the key when the follower cannot reach a cam of base radius `base_mm`."""
        if self.face == "roller":
            require(self.roller_radius_mm > 0, "face='roller' needs roller_radius_mm > 0", key="roller_radius_mm")
        rp = base_mm + (self.roller_radius_mm if self.face == "roller" else 0.0)
        if self.follower == "translating":
            if self.face == "roller":
                require(abs(self.offset_mm) < rp, f"offset_mm={self.offset_mm:g}: allowed |offset| < base + roller "
                        f"radius = {rp:g} mm", key="offset_mm")
            return
        for key in ("pivot_distance_mm", "arm_mm"):
            require(getattr(self, key) > 0, f"{key}={getattr(self, key):g}: an oscillating follower needs it > 0",
                    key=key)
        d, a = self.pivot_distance_mm, self.arm_mm
        if self.face == "roller":
            require(abs(d - a) < rp < d + a, f"the roller at arm_mm={a:g} cannot reach the prime circle (base + roller "
                    f"= {rp:g} mm) from pivot_distance_mm={d:g}: need |d - a| < {rp:g} < d + a", key="pivot_distance_mm")
        else:
            require(0 < rp + self.face_offset_mm < d, f"base_radius_mm + face_offset_mm = {rp + self.face_offset_mm:g}: "
                    f"allowed 0 ... pivot_distance_mm={d:g} (excl.): the face cannot touch the base circle",
                    key="face_offset_mm")

    @property
    def sigma(self) -> int:
        """+1 for a counter-clockwise cam, -1 for a clockwise one."""
        return SENSE[self.sense]

    def lift(self, theta):
        """s, s', s'' [mm, mm/rad, mm/rad^2] at the cam angles `theta` [rad]."""
        values = self.motion.at(np.asarray(theta, dtype=float))
        s, ds, dds = (np.asarray(v, dtype=float) for v in values[:3])
        require(bool(np.all(np.isfinite(np.r_[s, ds, dds]))), "the motion has non-finite values", key="segments")
        return s, ds, dds

    def curves(self, theta, base_mm: float | None = None, lift=None) -> CamCurves:
        """The cam's geometry at `theta` [rad] for base radius `base_mm` (default the task's);
        `lift` = (s, s', s'') when already evaluated."""
        base = self.base_radius_mm if base_mm is None else float(base_mm)
        self.check_layout(base)
        theta = np.atleast_1d(np.asarray(theta, dtype=float))
        s, ds, dds = lift if lift is not None else self.lift(theta)
        if self.follower == "translating":
            return self._translating(theta, s, ds, dds, base)
        return self._oscillating(theta, s, ds, dds, base)

    def _translating(self, theta, s, ds, dds, base):
        up, zero = np.array([np.zeros_like(s), np.ones_like(s)]), np.zeros_like(s)
        if self.face == "roller":
            rp = base + self.roller_radius_mm
            R = np.array([np.full_like(s, self.offset_mm), math.sqrt(rp**2 - self.offset_mm**2) + s])
            return roller_cam(theta, R, np.array([zero, ds]), np.array([zero, dds]), up, self.roller_radius_mm,
                              self.sigma)
        return flat_cam(theta, np.full_like(s, math.pi / 2), zero, zero, base + s, ds, dds, lambda c: up, self.sigma)

    def _oscillating(self, theta, s, ds, dds, base):
        d, L = self.pivot_distance_mm, self.arm_mm
        psi0 = self.psi0_rad(base)
        psi, dpsi, ddpsi = psi0 + s / L, ds / L, dds / L
        require(bool(np.all((psi > 0) & (psi < math.pi))), f"the arm swings to {math.degrees(psi.max()):.4g} deg "
                "from the line pivot -> cam centre: past it (allowed 0 ... 180 deg); a shorter lift or longer arm_mm",
                key="arm_mm")
        sin, cos = np.sin(psi), np.cos(psi)
        if self.face == "roller":
            along = np.array([sin, cos])                   # dR/dpsi / L
            R = np.array([d - L * cos, L * sin])
            dR = L * dpsi * along
            ddR = L * (ddpsi * along + dpsi**2 * np.array([cos, -sin]))
            return roller_cam(theta, R, dR, ddR, along, self.roller_radius_mm, self.sigma)
        f = self.face_offset_mm
        pivot = np.array([[d], [0.0]])
        p = d * sin - f
        dp = d * cos * dpsi
        ddp = d * (cos * ddpsi - sin * dpsi**2)
        return flat_cam(theta, math.pi / 2 - psi, -dpsi, -ddpsi, p, dp, ddp,
                        lambda c: -quarter(c - pivot) / L, self.sigma)

    def psi0_rad(self, base_mm: float) -> float:
        """The oscillating arm's angle from the line pivot -> O at s = 0 [rad]."""
        d, L = self.pivot_distance_mm, self.arm_mm
        if self.face == "roller":
            rp = base_mm + self.roller_radius_mm
            return math.acos((d * d + L * L - rp * rp) / (2 * L * d))
        return math.asin((base_mm + self.face_offset_mm) / d)

    def face_coordinate_mm(self, curves: CamCurves, base_mm: float | None = None) -> np.ndarray:
        """The contact point's place along a flat face [mm] (module docstring: from the stem's
        axis, or from the pivot's foot)."""
        if self.follower == "translating":
            return curves.contact[0] - self.offset_mm
        s = self.lift(curves.theta)[0]
        psi = self.psi0_rad(self.base_radius_mm if base_mm is None else base_mm) + s / self.arm_mm
        along = np.array([-np.cos(psi), np.sin(psi)])
        return np.sum((curves.contact - np.array([[self.pivot_distance_mm], [0.0]])) * along, axis=0)

    def warnings(self, values: dict) -> list[str]:
        """The motion's: steps of s' or s'' where segments meet (an infinite acceleration or jerk)."""
        return list(getattr(self.motion, "warnings", lambda v: [])(values))


def motion_of_segments(segments, joins: str = "warn"):
    """The follower's motion from the cam's segments (`models/cam_motion.CamMotion`)."""
    return CamMotion(segments=segments, joins=joins)
