"""The cam itself, for the shop: pitch curve, profile flanks, pressure angle,
radius of curvature and undercut of a disc cam with a roller follower, from ANY motion law.

A law is a callable ``law(xi) -> (S, S', S'')`` over the rise's fraction xi in [0, 1] (S(0) = 0,
S(1) = 1): `library_law` wraps a law of the library (models/cam_laws.py, `mechopt.laws`) as
`models/cam_follower.py` evaluates it; `tabulated_law` takes
S, S', S'' on a grid (a synthesised law) and interpolates them by quintic Hermite pieces, exact at
the nodes and C2 between them. The cam turns through rise, upper dwell, return (1 - S), lower
dwell over 360 deg (`CamShape`'s angles), giving the normalised lift u(theta) in [0, 1].

Followers (the roller centre R(theta) in the fixed frame, the cam centre O at the origin):

* translating: R = (e, s0 + h u), s0 = sqrt(Rp^2 - e^2), Rp = base + roller radius (prime circle);
* oscillating (paper 004's lift lever): pivot A = (d, 0), roller at `a_mm` from A on an arm at
  psi from the line A -> O, R = A + a (-cos psi, sin psi), psi = psi0 + Psi u, with the lever's
  swing Psi = H / (a + b) (H the stroke of its end C, read as the arc C runs: the small-angle
  reading of paper 004's "travel of C") and psi0 from |R| = Rp at u = 0.

What is this module's own: the lift cam's layout (`CamShape`), the law over the turn (`lift`)
and the follower's roller centre R, R', R'' (`roller_centre`). The geometry from R on (pitch
curve P = Rot(-theta) R, its normal, radius of curvature, profile P - r n) is
`models/cam_geometry.roller_cam`'s, the one implementation every roller cam of the package
takes (the cam turning counter-clockwise, CCW: its pitch curve runs clockwise); the groove's
outer wall P + r n is `cam_geometry.groove_outer_wall`. Pressure angle here: the unsigned angle
between the roller centre's direction of motion and the pitch normal (the line of force). These
are the standard relations of Norton, *Design of Machinery* (McGraw-Hill),
ch. 8 "Cam design" (pressure angle, radius of curvature, undercutting), and Rothbart (ed.), *Cam
Design Handbook* (McGraw-Hill, 2004), ch. on cam profile determination; for a translating roller
follower they reduce to the hand formulas tan phi = (s' - e) / (s0 + s) and, for e = 0,
rho = ((Rp + s)^2 + s'^2)^(3/2) / ((Rp + s)^2 + 2 s'^2 - (Rp + s) s'') (tests pin both).

Undercut: the inner flank P - r n_out (the cam's surface under a spring-closed roller, and the
inner wall of a groove) has radius rho - r where the pitch curve is convex: r >= rho there cuts
the profile back (a cusp, a roller that cannot follow it). A groove's outer wall P + r n_out
fails the same way where the pitch curve is concave and r >= |rho|. Lengths in mm, angles in rad.
"""
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
from annotated_types import Ge, Gt, Interval, doc

from mechopt.kit.errors import ModelError, require
from mechopt.kit.settings import check_fields
from mechopt.models.cam_follower import law_values
from mechopt.models.cam_geometry import groove_outer_wall, roller_cam, seen_from_cam
from mechopt.models.cam_laws import law as find_law

Law = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
CHORD_SAMPLES = 64            # points inside a chord where its distance to the curve is measured
CHORD_SHARE = 0.9             # of the chord a circle of the local radius allows: a margin for the
                              # radius changing along it (the chords that still stray are halved)
MAX_TABLE_POINTS = 200_000    # a tolerance finer than any shop needs stops here
CCW = 1                       # the lift cam's sense of rotation (models/cam_geometry.py's sigma)
ORIENTATION = -CCW            # so its pitch curve runs clockwise as the cam angle grows


def library_law(name: str) -> Law:
    """A law of the library (`mechopt.laws.names()`) as a vectorised callable xi -> (S, S', S'')
    (`models/cam_follower.law_values`: the law's S, derivatives by CasADi's AD)."""
    find_law(name)                      # an unknown name: the library's ModelError, listing its laws
    return lambda xi: law_values(name, xi)


def tabulated_law(xi, S, dS, ddS) -> Law:
    """A law given on a grid (S, S', S'' at increasing nodes xi from 0 to 1), interpolated by
    quintic Hermite pieces: exact at the nodes, C2 between them (as a synthesised spline law is)."""
    xi, S, dS, ddS = (np.asarray(v, dtype=float).ravel() for v in (xi, S, dS, ddS))
    require(xi.size >= 2 and xi.size == S.size == dS.size == ddS.size,
            f"a tabulated law needs >= 2 nodes and S, S', S'' at each; got {xi.size} nodes, "
            f"{S.size}, {dS.size}, {ddS.size} values", key="law")
    require(bool(np.all(np.diff(xi) > 0)) and abs(xi[0]) < 1e-12 and abs(xi[-1] - 1) < 1e-12,
            "a tabulated law's nodes must increase from 0 to 1", key="law")
    require(bool(np.all(np.isfinite(np.r_[S, dS, ddS]))), "a tabulated law has non-finite values", key="law")

    def law(x):
        x = np.clip(np.atleast_1d(np.asarray(x, dtype=float)), 0.0, 1.0)
        i = np.clip(np.searchsorted(xi, x, side="right") - 1, 0, xi.size - 2)
        h = xi[i + 1] - xi[i]
        t = (x - xi[i]) / h
        return _quintic(t, h, S[i], dS[i], ddS[i], S[i + 1], dS[i + 1], ddS[i + 1])
    return law


def _quintic(t, h, p0, v0, a0, p1, v1, a1):
    """Value and first two x-derivatives of the quintic Hermite piece on [0, 1] of width h."""
    v0, v1, a0, a1 = v0 * h, v1 * h, a0 * h * h, a1 * h * h
    t2, t3, t4, t5 = t * t, t**3, t**4, t**5
    basis = ((1 - 10 * t3 + 15 * t4 - 6 * t5, t - 6 * t3 + 8 * t4 - 3 * t5, 0.5 * (t2 - 3 * t3 + 3 * t4 - t5),
              10 * t3 - 15 * t4 + 6 * t5, -4 * t3 + 7 * t4 - 3 * t5, 0.5 * (t3 - 2 * t4 + t5)),
             (-30 * t2 + 60 * t3 - 30 * t4, 1 - 18 * t2 + 32 * t3 - 15 * t4, 0.5 * (2 * t - 9 * t2 + 12 * t3 - 5 * t4),
              30 * t2 - 60 * t3 + 30 * t4, -12 * t2 + 28 * t3 - 15 * t4, 0.5 * (3 * t2 - 8 * t3 + 5 * t4)),
             (-60 * t + 180 * t2 - 120 * t3, -36 * t + 96 * t2 - 60 * t3, 0.5 * (2 - 18 * t + 36 * t2 - 20 * t3),
              60 * t - 180 * t2 + 120 * t3, -24 * t + 84 * t2 - 60 * t3, 0.5 * (6 * t - 24 * t2 + 20 * t3)))
    coeffs = (p0, v0, a0, p1, v1, a1)
    return tuple(sum(c * b for c, b in zip(coeffs, row)) / h**k for k, row in enumerate(basis))


@dataclass(frozen=True)
class CamShape:
    """A disc cam with a roller follower: its layout over one turn and its follower.

    Parameters: `base_radius_mm` least radius of the cam's (inner) surface; `roller_radius_mm`;
    `stroke_mm` the follower's lift (translating) or the travel of the lever's end C (oscillating);
    `rise_deg`, `dwell_deg` (upper), `return_deg` (the lower dwell is what is left of 360);
    `offset_mm` the translating follower's offset e; `centre_distance_mm` cam centre O to pivot A,
    `a_mm` pivot to roller, `b_mm` roller to C (oscillating); `chord_tol_mm` the point table's
    chordal error; `max_pressure_angle_deg` the limit a design must keep; for the shop's drawing
    (`mechopt.cam_sheet`): `bore_diameter_mm` the shaft's bore (0: not stated, no drawing) and
    `rise_start_shaft_deg` the machine shaft's angle at which the rise begins (a cyclogram's event;
    the cam itself turns counter-clockwise, ORIENTATION). Structure: `law` (one
    of the library's; a synthesised law is passed as a `Law` to `pitch`, `flank`, `summarise` or
    the solver `solvers.stop_impact.cam_shape.shape_cam`), `follower`, `closure` ("spring": one
    flank; "groove": both walls of a grooved cam).
    """
    base_radius_mm: Annotated[float, Gt(0)]
    roller_radius_mm: Annotated[float, Gt(0)]
    stroke_mm: Annotated[float, Gt(0)]
    rise_deg: Annotated[float, Interval(gt=0, lt=360)]
    return_deg: Annotated[float, Interval(gt=0, lt=360)]
    dwell_deg: Annotated[float, Ge(0)] = 0.0
    offset_mm: Annotated[float, doc("|offset| < base_radius_mm + roller_radius_mm")] = 0.0
    centre_distance_mm: Annotated[float, Ge(0)] = 0.0
    a_mm: Annotated[float, Ge(0)] = 0.0
    b_mm: Annotated[float, Ge(0)] = 0.0
    chord_tol_mm: Annotated[float, Interval(gt=0, le=1)] = 0.01
    max_pressure_angle_deg: Annotated[float, Interval(gt=0, lt=90)] = 45.0
    bore_diameter_mm: Annotated[float, Ge(0), doc("0: not stated; below 2 x base_radius_mm")] = 0.0
    rise_start_shaft_deg: Annotated[float, Interval(ge=0, lt=360)] = 0.0
    law: str = "cycloidal"
    follower: Literal["translating", "oscillating"] = "translating"
    closure: Literal["spring", "groove"] = "spring"

    def __post_init__(self):
        check_fields(self)      # each input's range and kind (follower, closure: their Literal) on its field
        find_law(self.law)              # an unknown name: the library's ModelError, listing its laws
        require(self.bore_diameter_mm < 2 * self.base_radius_mm, f"bore_diameter_mm={self.bore_diameter_mm:g}: "
                f"allowed: below the base circle's diameter {2 * self.base_radius_mm:g} mm", key="bore_diameter_mm")
        total = self.rise_deg + self.dwell_deg + self.return_deg
        require(total <= 360.0, f"rise_deg + dwell_deg + return_deg = {total:g} deg: more than a turn (<= 360)",
                key="rise_deg")
        rp = self.prime_radius_mm
        if self.follower == "translating":
            require(abs(self.offset_mm) < rp, f"offset_mm={self.offset_mm:g}: must be below the prime radius "
                    f"(base + roller = {rp:g} mm)", key="offset_mm")
            return
        for key in ("centre_distance_mm", "a_mm", "b_mm"):
            require(getattr(self, key) > 0, f"{key}={getattr(self, key):g}: an oscillating follower needs it > 0",
                    key=key)
        d, a = self.centre_distance_mm, self.a_mm
        require(abs(d - a) < rp < d + a, f"the roller at a_mm={a:g} from the pivot cannot reach the prime circle "
                f"(base + roller = {rp:g} mm) from centre_distance_mm={d:g}: need |d - a| < {rp:g} < d + a",
                key="centre_distance_mm")
        psi_end = self.psi0_rad + self.swing_rad
        require(psi_end < math.pi, f"stroke_mm={self.stroke_mm:g} swings the lever past the line through O "
                f"({math.degrees(psi_end):.4g} deg from it)", key="stroke_mm")

    @property
    def prime_radius_mm(self) -> float:
        """Rp = base + roller radius: the pitch curve's least radius."""
        return self.base_radius_mm + self.roller_radius_mm

    @property
    def swing_rad(self) -> float:
        """The lever's angular stroke Psi = H / (a + b) (C's travel read as its arc)."""
        return self.stroke_mm / (self.a_mm + self.b_mm)

    @property
    def psi0_rad(self) -> float:
        """The arm's angle from the line A -> O at rest, |R| = Rp (law of cosines)."""
        d, a, rp = self.centre_distance_mm, self.a_mm, self.prime_radius_mm
        return math.acos((d * d + a * a - rp * rp) / (2 * a * d))

    def phase_ends_rad(self) -> tuple[float, ...]:
        """Cam angles where the layout changes phase (rise start ... return end) [rad]."""
        ends = np.cumsum([0.0, self.rise_deg, self.dwell_deg, self.return_deg])
        return tuple(float(math.radians(e)) for e in dict.fromkeys(ends) if e < 360.0)


def lift(shape: CamShape, theta, law: Law | None = None):
    """Normalised lift u(theta) in [0, 1] and its theta-derivatives u', u'' [1/rad, 1/rad^2]
    over rise, upper dwell, return (1 - S) and lower dwell."""
    law = law or library_law(shape.law)
    theta = np.mod(np.atleast_1d(np.asarray(theta, dtype=float)), 2 * math.pi)
    b1, dw, b2 = (math.radians(v) for v in (shape.rise_deg, shape.dwell_deg, shape.return_deg))
    u, du, ddu = np.zeros_like(theta), np.zeros_like(theta), np.zeros_like(theta)
    rise = theta <= b1
    if rise.any():
        S, dS, ddS = law(theta[rise] / b1)
        u[rise], du[rise], ddu[rise] = S, dS / b1, ddS / b1**2
    top = (theta > b1) & (theta <= b1 + dw)
    u[top] = 1.0
    back = (theta > b1 + dw) & (theta <= b1 + dw + b2)
    if back.any():
        S, dS, ddS = law((theta[back] - b1 - dw) / b2)
        u[back], du[back], ddu[back] = 1.0 - S, -dS / b2, -ddS / b2**2
    return u, du, ddu


def roller_centre(shape: CamShape, theta, law: Law | None = None):
    """R, R', R'' (each 2 x n, fixed frame [mm, mm/rad, mm/rad^2]) and the unit direction in
    which the roller centre moves, all at the cam angles `theta`."""
    u, du, ddu = lift(shape, theta, law)
    if shape.follower == "translating":
        s0 = math.sqrt(shape.prime_radius_mm**2 - shape.offset_mm**2)
        h = shape.stroke_mm
        zero = np.zeros_like(u)
        R = np.array([np.full_like(u, shape.offset_mm), s0 + h * u])
        return R, np.array([zero, h * du]), np.array([zero, h * ddu]), np.array([zero, np.ones_like(u)])
    a, swing = shape.a_mm, shape.swing_rad
    psi, dpsi, ddpsi = shape.psi0_rad + swing * u, swing * du, swing * ddu
    along = np.array([np.sin(psi), np.cos(psi)])          # d/dpsi of (-cos psi, sin psi)
    inward = np.array([np.cos(psi), -np.sin(psi)])        # d/dpsi of `along`
    R = np.array([shape.centre_distance_mm - a * np.cos(psi), a * np.sin(psi)])
    return R, a * dpsi * along, a * (ddpsi * along + dpsi**2 * inward), along


@dataclass(frozen=True)
class Pitch:
    """The pitch curve at cam angles `theta` [rad]: points P (2 x n, cam frame) [mm], unit
    outward normal, signed radius of curvature (> 0 convex, < 0 concave) [mm], pressure angle
    [rad]. P runs clockwise as theta grows (ORIENTATION)."""
    theta: np.ndarray
    P: np.ndarray
    normal: np.ndarray
    radius_mm: np.ndarray
    pressure_rad: np.ndarray


def _cam(shape: CamShape, theta, law: Law | None):
    """`models/cam_geometry.roller_cam` (the one implementation of a roller cam's pitch curve,
    normal, radii and profile) of this follower's roller centre, the cam turning counter-clockwise
    (CCW); and the roller centre's direction of motion (2 x n)."""
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    R, dR, ddR, moving = roller_centre(shape, theta, law)
    return roller_cam(theta, R, dR, ddR, moving, shape.roller_radius_mm, CCW), moving


def pitch(shape: CamShape, theta, law: Law | None = None) -> Pitch:
    """The pitch curve, its normal, radius of curvature and pressure angle (module docstring), from
    `roller_cam`; the pressure angle unsigned: the angle between the lines of motion and of force."""
    c, moving = _cam(shape, theta, law)
    n = c.normal
    # |sin| and |cos| of the signed angle from the motion to the normal (roller_cam's pressure_rad)
    pressure = np.arctan2(np.abs(moving[0] * n[1] - moving[1] * n[0]), np.abs(c.lever))
    return Pitch(c.theta, c.pitch, seen_from_cam(c.theta, n, CCW), c.pitch_radius_mm, pressure)


FLANKS = {"spring": ("inner",), "groove": ("inner", "outer")}


def flank(shape: CamShape, theta, side: Literal["inner", "outer"] = "inner", law: Law | None = None):
    """Points (2 x n, cam frame) [mm] of a profile flank: the envelope of the roller circles,
    `roller_cam`'s profile P - r n_out (inner: the cam's surface, a groove's inner wall) or
    `groove_outer_wall` P + r n_out (a groove's outer wall). Refused (ModelError naming the cam
    angle of the least radius among the angles given) where the flank is undercut."""
    c, _ = _cam(shape, theta, law)
    rho = c.pitch_radius_mm
    bad = undercut_at(rho, shape.roller_radius_mm, side)
    if bad.any():
        i = int(np.argmin(np.where(bad, np.abs(rho), np.inf)))
        raise ModelError(_undercut_message(shape, side, float(c.theta[i]), float(rho[i])), key="roller_radius_mm")
    return c.profile if side == "inner" else groove_outer_wall(c)


def undercut_at(rho, roller_mm: float, side: str) -> np.ndarray:
    """Where a flank is undercut: the roller radius reaches the pitch curve's signed radius `rho`
    [mm] on the side the flank is offset towards (convex for the inner flank, concave for the outer)."""
    return (rho > 0) & (rho <= roller_mm) if side == "inner" else (rho < 0) & (-rho <= roller_mm)


def _undercut_message(shape, side, theta, rho):
    kind = "convex" if side == "inner" else "concave"
    return (f"undercut: roller_radius_mm={shape.roller_radius_mm:g} >= the pitch curve's {kind} radius of "
            f"curvature {abs(rho):.4g} mm at cam angle {math.degrees(theta):.3f} deg ({side} flank); "
            f"use a roller below {abs(rho):.4g} mm, a larger base_radius_mm or a longer rise/return")


@dataclass(frozen=True)
class ShapeSummary:
    """What the shop and the designer ask of a cam: the least radii of curvature of the pitch
    curve (convex, and concave where a groove's outer wall needs it) with their cam angles, the
    largest pressure angle and where, and the undercut margin (least |rho| - r over the flanks
    made; <= 0: undercut, at `undercut_deg`)."""
    min_convex_radius_mm: float
    min_convex_deg: float
    min_concave_radius_mm: float        # inf when the pitch curve is nowhere concave
    min_concave_deg: float
    max_pressure_angle_deg: float
    max_pressure_deg: float
    undercut_margin_mm: float
    undercut_deg: float
    undercut_flank: str


def summarise(shape: CamShape, law: Law | None = None, *, samples: int = 7200) -> ShapeSummary:
    """`ShapeSummary` on `samples` cam angles (the phase ends among them), each extreme polished
    by a bounded scalar search between its neighbours."""
    from scipy.optimize import minimize_scalar

    theta = np.unique(np.r_[np.linspace(0, 2 * math.pi, samples, endpoint=False), shape.phase_ends_rad()])
    p = pitch(shape, theta, law)

    def polish(values, f):
        i = int(np.argmin(values))
        lo, hi = theta[max(i - 1, 0)], theta[min(i + 1, theta.size - 1)]
        best = minimize_scalar(lambda t: f(pitch(shape, t, law))[0], bounds=(lo, hi), method="bounded",
                               options={"xatol": 1e-10})
        return (float(best.fun), float(best.x)) if best.fun < values[i] else (float(values[i]), float(theta[i]))

    def convex(q):
        return np.where(q.radius_mm > 0, q.radius_mm, np.inf)

    def concave(q):
        return np.where(q.radius_mm < 0, -q.radius_mm, np.inf)

    rho_vex, at_vex = polish(convex(p), convex) if np.isfinite(convex(p)).any() else (math.inf, 0.0)
    rho_cave, at_cave = polish(concave(p), concave) if np.isfinite(concave(p)).any() else (math.inf, 0.0)
    phi, at_phi = polish(-p.pressure_rad, lambda q: -q.pressure_rad)
    margins = {"inner": (rho_vex - shape.roller_radius_mm, at_vex)}
    if shape.closure == "groove":
        margins["outer"] = (rho_cave - shape.roller_radius_mm, at_cave)
    side = min(margins, key=lambda k: margins[k][0])
    return ShapeSummary(rho_vex, math.degrees(at_vex), rho_cave, math.degrees(at_cave), math.degrees(-phi),
                        math.degrees(at_phi), margins[side][0], math.degrees(margins[side][1]), side)


def check_undercut(shape: CamShape, summary: ShapeSummary) -> None:
    """ModelError naming the cam angle when a flank the cam needs is undercut."""
    if summary.undercut_margin_mm <= 0:
        rho = summary.min_convex_radius_mm if summary.undercut_flank == "inner" else summary.min_concave_radius_mm
        raise ModelError(_undercut_message(shape, summary.undercut_flank, math.radians(summary.undercut_deg), rho),
                         key="roller_radius_mm")


@dataclass(frozen=True)
class PointTable:
    """A curve as the shop takes it: parameters `t` and points `xy` (n x 2) [mm] whose chords
    stay within `chord_error_mm` (measured, <= the tolerance asked) of the curve; `closed`: the
    last point joins the first (else the last point is the curve's end)."""
    t: np.ndarray
    xy: np.ndarray
    chord_error_mm: float
    tolerance_mm: float
    closed: bool = True


def point_table(curve, tol_mm: float, *, period: float = 2 * math.pi, breaks=(), dense: int = 20_000,
                closed: bool = True) -> PointTable:
    """Points of the closed curve `curve(t) -> (2 x n)` over t in [0, period) (an open one, to its
    end at t = period, with `closed=False`), spaced by the curvature: a chord of length c on an
    arc of radius rho strays c^2 / (8 rho) from it, so the
    points are laid CHORD_SHARE * sqrt(8 rho tol) apart along the curve (rho from the circles
    through `dense` consecutive points: any curve, no derivatives asked); a chord still straying
    more than `tol_mm` is halved until none does. `breaks` (corners, phase ends) are always points.
    The error stated is the largest curve-to-chord distance measured at CHORD_SAMPLES points inside
    every chord (the arc's bump over a chord is smooth, so the sampled largest is within ~1e-4
    relative of the true one)."""
    require(tol_mm > 0, f"chord_tol_mm={tol_mm!r}: must be > 0", key="chord_tol_mm")
    ends = np.unique(np.r_[0.0, [b % period for b in breaks], period])
    td = np.unique(np.r_[np.linspace(0.0, period, dense, endpoint=False), ends[:-1]])
    Q = np.asarray(curve(np.r_[td, period]))                    # the last point: the first again if closed
    step = np.hypot(*np.diff(Q, axis=1))                        # from point k to k + 1
    before = np.c_[Q[:, -2:-1], Q[:, :-2]] if closed else np.c_[Q[:, 1:2], Q[:, :-2]]
    after = Q[:, 1:]
    here = Q[:, :-1]
    ab, bc, ca = np.hypot(*(here - before)), step, np.hypot(*(before - after))
    cross = np.abs((here - before)[0] * (after - before)[1] - (here - before)[1] * (after - before)[0])
    bend = 2 * cross / np.maximum(ab * bc * ca, 1e-300)        # 1 / circumradius at each point
    bend_next = np.r_[bend[1:], bend[0] if closed else bend[-1]]
    allowed = CHORD_SHARE * np.sqrt(8 * tol_mm / np.maximum(np.maximum(bend, bend_next), 1e-12))
    count = np.r_[0.0, np.cumsum(step / allowed)]              # chords needed from t = 0 up to each point
    t_all = np.r_[td, period]
    t = []
    for lo, hi in zip(ends[:-1], ends[1:]):                    # whole chords between breaks
        n_lo, n_hi = np.interp([lo, hi], t_all, count)
        m = max(1, int(math.ceil(n_hi - n_lo)))
        t.append(np.interp(n_lo + (n_hi - n_lo) * np.arange(m) / m, count, t_all))
    t = np.unique(np.concatenate(t))
    while True:
        bad = chord_errors(curve, np.r_[t, period], CHORD_SAMPLES) > tol_mm
        if not bad.any():
            break
        edges = np.r_[t, period]
        t = np.sort(np.r_[t, 0.5 * (edges[:-1] + edges[1:])[bad]])
        require(t.size <= MAX_TABLE_POINTS, f"chord_tol_mm={tol_mm:g} needs more than {MAX_TABLE_POINTS} points; "
                "a coarser tolerance", key="chord_tol_mm")
    achieved = float(chord_errors(curve, np.r_[t, period], CHORD_SAMPLES).max())
    t = t if closed else np.r_[t, period]
    return PointTable(t, np.asarray(curve(t)).T.copy(), achieved, float(tol_mm), closed)


def chord_errors(curve, ends, samples: int) -> np.ndarray:
    """Per chord between consecutive parameters `ends`: the largest distance from the curve to the
    chord, at `samples` points inside it [mm]."""
    ends = np.asarray(ends, dtype=float)
    frac = np.arange(1, samples + 1) / (samples + 1)
    inner = ends[:-1, None] + frac[None, :] * np.diff(ends)[:, None]
    A, B = (np.asarray(curve(x)) for x in (ends[:-1], ends[1:]))
    Q = np.asarray(curve(inner.ravel())).reshape(2, *inner.shape)
    return np.max(distance_to_segment(Q, A[:, :, None], B[:, :, None]), axis=1)


def distance_to_segment(Q, A, B):
    """Distance from points Q to the segments A-B (arrays with the coordinate first) [mm]."""
    AB, AQ = B - A, Q - A
    length2 = np.sum(AB * AB, axis=0)
    along = np.clip(np.sum(AQ * AB, axis=0) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    return np.hypot(*(AQ - along * AB))


def mirrored(curve, t_start: float, t_end: float):
    """A closed curve over [0, 2 (t_end - t_start)): `curve` from t_start to t_end, then its mirror
    in the x axis back to the start (a path symmetric about the x axis given by its upper half,
    as paper 000's torch paths are)."""
    span = t_end - t_start

    def closed(t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        back = t > span
        x, y = (np.asarray(v, dtype=float) for v in curve(t_start + np.where(back, 2 * span - t, t)))
        return np.array([x, np.where(back, -y, y)])
    return closed
