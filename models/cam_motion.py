"""A cam's follower motion as a sequence of segments over one turn: rise, dwell, return (a rise
that stops short of the top, or a return short of the bottom, is a partial one: any lift).

Each segment has a law of the library (models/cam_laws.py), an angle beta [deg] and a lift h
[mm] (> 0 a rise, < 0 a return, 0 a dwell). Over segment k, starting at cam angle theta_k with
the follower at s_k, x = (theta - theta_k) / beta_k and

    s = s_k + h S(x),   s' = h S'(x) / beta,   s'' = h S''(x) / beta^2,   s''' = h S'''(x) / beta^3

(' = d/dtheta, theta in rad; Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., ch. 3: the
normalised law scaled to the segment). The angles must add to 360 deg and the lifts to 0 (the
follower returns to its start); the cam starts at theta = 0 with s = 0 at the first segment.

Joins: where one segment ends and the next begins (the last's end is the first's start) s' or
s'' may step. A step of s' is an infinite acceleration, a step of s'' an infinite jerk (Norton's
"fundamental law of cam design": s, s', s'' continuous over the whole turn). Each step is a
`Join`, named by its segments, angle and size; `joins = "warn"` (default) reports them as the
model's warnings, `joins = "refuse"` makes them a ModelError. Steps of s''' (every law with a
finite jerk at a dwell) are allowed and not reported.

Read from a scene's ``[structure]``: `segments` a list of tables {segment, law, angle_deg,
lift_mm} (TOML ``[[structure.segments]]``) or a CSV beside the scene with those columns
(`CSV_TABLES`). A dwell needs no law.
"""
import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, Literal

import numpy as np

from mechopt.kit.errors import ModelError, quote, require, some_of
from mechopt.kit.settings import check_fields
from mechopt.models.cam_laws import Law
from mechopt.models.cam_laws import law as library_law

KINDS = ("rise", "dwell", "return")
SEGMENT_COLUMNS = {"segment": str, "law": str, "angle_deg": float, "lift_mm": float,
                   "mark": str, "why": str, "where": str, "what": str}      # the last four: notes, not physics
SEGMENT_REQUIRED = ("segment", "angle_deg", "lift_mm")
FULL_TURN_DEG = 360.0
ANGLE_TOL_DEG = 1e-9        # the angles' sum may miss 360 deg by this (rounding of a designer's table)
LIFT_TOL_MM = 1e-9          # the lifts' sum may miss 0 by this
JOIN_TOL = 1e-9             # a step smaller than this, relative to the cam's peak of that order, is rounding
MAX_SEGMENTS = 10_000
_DERIVATIVE = {1: ("velocity", "mm/rad", "an infinite acceleration"),
               2: ("acceleration", "mm/rad^2", "an infinite jerk")}


@dataclass(frozen=True)
class Segment:
    """One segment: `kind` (rise, dwell, return), `law` (None for a dwell), `angle_deg` beta,
    `lift_mm` h, and where it starts: `start_deg` theta_k, `start_mm` s_k."""
    kind: str
    law: Law | None
    angle_deg: float
    lift_mm: float
    start_deg: float = 0.0
    start_mm: float = 0.0

    @property
    def beta_rad(self) -> float:
        return math.radians(self.angle_deg)

    def label(self, number: int) -> str:
        return f"segment {number} ({self.kind}" + (f", {self.law.name})" if self.law else ")")

    def values(self, x):
        """(s, s', s'', s''') at the fractions x in [0, 1] of the segment [mm, mm/rad^k]."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        if self.law is None:
            zero = np.zeros_like(x)
            return zero + self.start_mm, zero, zero.copy(), zero.copy()
        S = self.law.values(x)
        h, b = self.lift_mm, self.beta_rad
        return self.start_mm + h * S[0], h * S[1] / b, h * S[2] / b**2, h * S[3] / b**3

    def peaks(self) -> dict:
        """The segment's largest |s'|, |s''|, |s'''| [mm/rad, mm/rad^2, mm/rad^3]: |h| C / beta^k."""
        if self.law is None:
            return {"velocity_mm_per_rad": 0.0, "acceleration_mm_per_rad2": 0.0, "jerk_mm_per_rad3": 0.0}
        c, h, b = self.law.peaks, abs(self.lift_mm), self.beta_rad
        return {"velocity_mm_per_rad": h * c["Cv"] / b, "acceleration_mm_per_rad2": h * c["Ca"] / b**2,
                "jerk_mm_per_rad3": h * c["Cj"] / b**3}


@dataclass(frozen=True)
class Join:
    """A step of s' (order 1) or s'' (order 2) where segment `before` ends and `after` begins
    (1-based numbers), at cam angle `angle_deg`: `jump` = after's value - before's [mm/rad^order]."""
    before: int
    after: int
    angle_deg: float
    order: int
    jump: float
    text: str

    def __str__(self):
        return self.text


@dataclass(frozen=True)
class CamMotion:
    """The follower's motion over one turn from its `segments` (module docstring): `at(theta_rad)`
    -> (s [mm], s' [mm/rad], s'' [mm/rad^2], s''' [mm/rad^3]). `joins`: "warn" reports each step
    of s' or s'' at a join among the warnings, "refuse" raises a ModelError naming them."""
    segments: tuple = ()
    joins: Literal["warn", "refuse"] = "warn"

    # a scene may read the segments from a CSV beside it (columns segment, law, angle_deg, lift_mm)
    CSV_TABLES: ClassVar[dict] = {"segments": (SEGMENT_REQUIRED, SEGMENT_COLUMNS)}

    def __post_init__(self):
        check_fields(self)
        object.__setattr__(self, "segments", _segments(self.segments))
        steps = self.steps()
        if self.joins == "refuse" and steps:
            raise ModelError(f"joins='refuse': {'; '.join(map(str, steps))} ('warn' reports them instead)",
                             key="joins")

    @property
    def starts_rad(self) -> np.ndarray:
        return np.radians([seg.start_deg for seg in self.segments])

    def at(self, theta_rad):
        """(s, s', s'', s''') at the cam angles `theta_rad` (any real: taken modulo a turn) [mm,
        mm/rad, mm/rad^2, mm/rad^3], float arrays of theta's shape (at least 1-d). At a join the
        segment that begins there gives the values."""
        theta = np.mod(np.atleast_1d(np.asarray(theta_rad, dtype=float)), 2 * math.pi)
        which = np.clip(np.searchsorted(self.starts_rad, theta, side="right") - 1, 0, len(self.segments) - 1)
        out = tuple(np.empty_like(theta) for _ in range(4))
        for k, seg in enumerate(self.segments):
            here = which == k
            if here.any():
                x = np.clip((theta[here] - math.radians(seg.start_deg)) / seg.beta_rad, 0.0, 1.0)
                for target, value in zip(out, seg.values(x)):
                    target[here] = value
        return out

    def steps(self) -> list[Join]:
        """Every step of s' or s'' at a join (the last segment's end joins the first's start)."""
        return list(self._steps)

    @cached_property
    def _steps(self) -> tuple[Join, ...]:
        each = [seg.peaks() for seg in self.segments]
        scale = {1: max(p["velocity_mm_per_rad"] for p in each), 2: max(p["acceleration_mm_per_rad2"] for p in each)}
        out, n = [], len(self.segments)
        for k in range(n):
            before, after = self.segments[k - 1], self.segments[k]
            end, start = before.values(1.0), after.values(0.0)
            for order in (1, 2):
                jump = float(start[order][0] - end[order][0])
                if abs(jump) > JOIN_TOL * max(scale[order], 1e-300):
                    what, unit, meaning = _DERIVATIVE[order]
                    text = (f"{what} jump of {jump:+.6g} {unit} at cam angle {after.start_deg:g} deg between "
                            f"{before.label((k - 1) % n + 1)} and {after.label(k + 1)}: {meaning} there")
                    out.append(Join((k - 1) % n + 1, k + 1, after.start_deg, order, jump, text))
        return tuple(out)

    def segment_peaks(self) -> list[dict]:
        """Per segment: its number, kind, law and largest |s'|, |s''|, |s'''| (`Segment.peaks`)."""
        return [{"segment": k + 1, "kind": seg.kind, "law": seg.law.name if seg.law else ""} | seg.peaks()
                for k, seg in enumerate(self.segments)]

    def peaks(self) -> dict:
        """The cam's largest |s'|, |s''|, |s'''| over the turn [mm/rad^k]; the jerk is infinite
        where s'' steps at a join (or inside a law, as the constant-acceleration law's)."""
        each = self.segment_peaks()
        out = {key: max(p[key] for p in each) for key in ("velocity_mm_per_rad", "acceleration_mm_per_rad2",
                                                           "jerk_mm_per_rad3")}
        if any(j.order == 1 for j in self._steps):
            out["acceleration_mm_per_rad2"] = math.inf
        if self._steps:
            out["jerk_mm_per_rad3"] = math.inf
        return out

    def in_time(self, theta_rad, speed_rpm: float):
        """(s [mm], v [mm/s], a [mm/s^2], j [mm/s^3]) at the cam angles `theta_rad` for a cam
        turning steadily at `speed_rpm`: the angle derivatives times omega^k, omega = 2 pi n / 60."""
        require(isinstance(speed_rpm, (int, float)) and math.isfinite(speed_rpm) and speed_rpm > 0,
                f"speed_rpm={quote(speed_rpm)}: allowed > 0", key="speed_rpm")
        omega = 2 * math.pi * speed_rpm / 60.0
        return tuple(v * omega**k for k, v in enumerate(self.at(theta_rad)))

    def warnings(self, values: dict) -> list[str]:
        """The steps at joins (an infinite acceleration or jerk), one line each."""
        return [str(j) for j in self.steps()]


def _segments(rows) -> tuple[Segment, ...]:
    """The segments of `rows` (tables or `Segment`s), each checked, placed end to end from 0 deg
    and s = 0; the angles must add to a turn and the lifts to 0."""
    count = len(rows) if isinstance(rows, (list, tuple)) else None
    require(count is not None and 0 < count <= MAX_SEGMENTS,
            f"segments={quote(rows)}: expected a list of 1 to {MAX_SEGMENTS} tables {{segment, law, angle_deg, "
            "lift_mm}", key="segments")
    out, theta, s = [], 0.0, 0.0
    for k, row in enumerate(rows):
        if isinstance(row, Segment):            # held to the same rules as a table
            row = {"segment": row.kind, "law": row.law or "", "angle_deg": row.angle_deg, "lift_mm": row.lift_mm}
        seg = _segment(row, f"segments[{k}]")
        out.append(Segment(seg.kind, seg.law, seg.angle_deg, seg.lift_mm, theta, s))
        theta, s = theta + seg.angle_deg, s + seg.lift_mm
    angles = " + ".join(f"{seg.angle_deg:g}" for seg in out)
    require(abs(theta - FULL_TURN_DEG) <= ANGLE_TOL_DEG,
            f"segments={some_of(angles.split(' + '), sep=' + ')} deg: the angles add to {theta:.10g} deg; "
            f"allowed: a full turn, {FULL_TURN_DEG:g} deg", key="segments")
    require(abs(s) <= LIFT_TOL_MM,
            f"segments={some_of([f'({seg.lift_mm:+g})' for seg in out], sep=' + ')} mm: the lifts add to "
            f"{s:.10g} mm; allowed: 0 (the follower returns to its start)", key="segments")
    return tuple(out)


def _segment(row, where: str) -> Segment:
    """One table {segment, law, angle_deg, lift_mm} checked: its kind, its law, a finite angle in
    (0, 360] deg and a lift whose sign is its kind's. Errors name the row's key (segments[2].lift_mm)."""
    require(isinstance(row, dict), f"{where}={quote(row)}: expected a table {{segment, law, angle_deg, lift_mm}}",
            key=where)
    unknown = sorted(map(str, set(row) - set(SEGMENT_COLUMNS)))
    require(not unknown, f"{where}={quote(row)}: unknown key(s) {', '.join(unknown)}; allowed: "
            f"{', '.join(SEGMENT_COLUMNS)}", key=where)
    missing = [key for key in SEGMENT_REQUIRED if key not in row]
    require(not missing, f"{where}={quote(row)}: missing {', '.join(missing)}", key=where)
    kind, angle, lift = row["segment"], row["angle_deg"], row["lift_mm"]
    require(kind in KINDS, f"{where}.segment={quote(kind)}: allowed {', '.join(KINDS)}", key=f"{where}.segment")
    for key, value in (("angle_deg", angle), ("lift_mm", lift)):
        require(isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value),
                f"{where}.{key}={quote(value)}: expected a finite number", key=f"{where}.{key}")
    require(0 < angle <= FULL_TURN_DEG, f"{where}.angle_deg={angle!r}: allowed > 0 and <= {FULL_TURN_DEG:g}",
            key=f"{where}.angle_deg")
    rule = {"rise": ("> 0", lift > 0), "return": ("< 0 (a return falls)", lift < 0), "dwell": ("= 0", lift == 0)}
    require(rule[kind][1], f"{where}.lift_mm={lift!r}: allowed {rule[kind][0]} for a {kind}", key=f"{where}.lift_mm")
    name = row.get("law", "")
    if kind == "dwell":
        require(name in ("", "dwell"), f"{where}.law={quote(name)}: a dwell has no law (leave it out)",
                key=f"{where}.law")
        return Segment(kind, None, float(angle), 0.0)
    try:
        found = library_law(name)
    except ModelError as exc:
        raise ModelError(f"{where}.{exc}", key=f"{where}.law") from None
    return Segment(kind, found, float(angle), float(lift))
