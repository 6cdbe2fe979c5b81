"""Torch-guiding linkage for cardioid cams (paper 000: Podchasov 2021, Secs. III-IV).

The torch centre should run on the ideal path: the cardioid (1), or its parallel curve at the
kerf offset h (2)-(3), shifted so that t = 0 sits at the origin (9). The linkage moves it on a
limaçon (Pascal's snail) (7), shifted the same way (10); its link lengths H, L are the unknowns.

Lengths are in mm (the names say so: the geometry is scale-free and the paper states mm), angles
in rad. Every function takes ``m=np`` or ``m=casadi`` so the same line serves numbers and symbols.

Effects a scene may call for:

============  ==========================================================  ==========
effect        adds                                                        paper
============  ==========================================================  ==========
torch_offset  kerf offset h: the path is the parallel curve at distance   eqs. (2)-(3)
              h outside the cam profile; without it, the plain cardioid
============  ==========================================================  ==========
"""
from dataclasses import dataclass
from functools import cached_property
from typing import Annotated, ClassVar, Literal

import numpy as np
from annotated_types import Ge, Gt, Interval, Le, doc
from scipy.optimize import brentq

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError, require
from mechopt.kit.settings import check_fields, range_fault
from mechopt.models.effects import Effect


def ideal_point(t, a, h=0.0, m=np):
    """Torch centre on the ideal path, eq. (9) [mm]: cardioid of size `a` plus offset `h` (3)."""
    x = a * (2 * m.cos(t) + m.cos(2 * t) - 3) + h * (m.cos(1.5 * t) - 1)
    y = a * (2 * m.sin(t) + m.sin(2 * t)) + h * m.sin(1.5 * t)
    return x, y


def ideal_normal(t, m=np):
    """Outward unit normal of the ideal path at t in [0, pi) (the same for every offset h).

    From eq. (2): the cardioid's y', -x' over its speed 4a cos(t/2) reduce, with
    cos t + cos 2t = 2 cos(3t/2) cos(t/2), to (cos 3t/2, sin 3t/2); that is how (3) arises.
    """
    return m.cos(1.5 * t), m.sin(1.5 * t)


def real_point(s, H, L, m=np):
    """Torch centre moved by the linkage (H, L) at crank parameter s, eq. (10) [mm]."""
    return L * (m.cos(s) - 1) + 0.5 * H * (m.cos(2 * s) - 1), L * m.sin(s) + 0.5 * H * m.sin(2 * s)


def real_velocity(s, H, L, m=np):
    """d/ds of `real_point` [mm/rad]."""
    return -L * m.sin(s) - H * m.sin(2 * s), L * m.cos(s) + H * m.cos(2 * s)


def real_acceleration(s, H, L, m=np):
    """d2/ds2 of `real_point` [mm/rad2]."""
    return -L * m.cos(s) - 2 * H * m.cos(2 * s), -L * m.sin(s) - 2 * H * m.sin(2 * s)


def limacon_implicit(x, y, H, L):
    """Implicit form of the closed real path [mm^4]: negative inside, zero on it, positive outside.

    About its pole (-(L+H), 0) the limaçon r = L + H cos s satisfies (r^2 - H u)^2 = L^2 r^2 with
    u the abscissa from the pole. "Inside" is the region between the loops (winding number one);
    the inner loop, when L < H, counts as outside, as an even-odd point-in-curve test would say.
    """
    u = x + L + H
    r2 = u * u + y * y
    return (r2 - H * u) ** 2 - (L * L) * r2


@memoised(maxsize=64)       # pure in (a, h); a task asks twice (its end, its matched linkage)
def finish_angle(a, h=0.0):
    """Exact t on (0, pi] where the ideal path meets the x axis (Y of eq. (9) = 0) [rad]."""
    def y(t):
        return ideal_point(t, a, h)[1]
    if y(np.pi) >= -1e-12 * a:      # plain cardioid: it meets the axis only at its cusp, t = pi
        return float(np.pi)
    t = np.linspace(0.0, np.pi, 721)[1:]
    below = np.flatnonzero(y(t) <= 0.0)[0]      # first sample on or under the axis
    return float(brentq(y, t[below - 1], t[below], xtol=1e-15))


def decimal_reading(f, root, tol):
    """The paper's iterative reading of a root of f: the lattice step shrinks tenfold until both
    ends of the bracket give |f| <= tol; the lower end is the reading (the paper's t_FINISH: cases/cam-cutter/paper-grid)."""
    for k in range(1, 16):
        lo = np.floor(root * 10**k) / 10**k
        if max(abs(f(lo)), abs(f(lo + 10.0**-k))) <= tol:
            return round(float(lo), k)
    return float(root)


def matched_linkage(a, h=0.0):
    """(H, L) [mm] of the limaçon whose double point -(L+H) and vertex radius of curvature
    (L+H)^2 / (L+2H) equal the ideal path's axis crossing and its radius 8a/3 + h at t = 0.
    Exact (H = L = 2a) for the plain cardioid; within 0.2 mm of the optimum for the paper's case."""
    span = -float(ideal_point(finish_angle(a, h), a, h)[0])
    H = span**2 / (8 * a / 3 + h) - span
    return H, span - H


PAPER_A_MM = 25.0              # the paper's cam (Sec. IV): the size the solvers' tolerances were tuned on
A_RANGE_MM = (1e-6, 1e6)       # cam sizes accepted
LINK_MAX_PER_A = 100.0         # links and box bounds accepted up to this many cam sizes
# ranges that depend on another input, as describe shows them (checked in __post_init__)
BOX_RANGE = f"> 0 ... {LINK_MAX_PER_A:g} a_mm"
CENTRE_RANGE = "-10 (H_mm + L_mm) ... 10 (H_mm + L_mm)"
MIN_LINK_PER_A = 0.01          # a derived lower bound never below this many cam sizes


class _OnIdealPath:
    """What every task on the ideal path (`a_mm`, `h_mm`, `y_tol_mm`) knows of its end."""

    @cached_property
    def t_finish_rad(self) -> float:
        """Exact end of the ideal path in the upper half-plane [rad]."""
        return finish_angle(self.a_mm, self.h_mm)

    # the path protocol the minimax shares with models.cam_profile.ProfileFit (any curve)
    @property
    def size_mm(self) -> float:
        """The cam's size, the unit the solvers measure lengths in [mm]."""
        return self.a_mm

    @property
    def t_start_rad(self) -> float:
        return 0.0

    @property
    def t_end_rad(self) -> float:
        return self.t_finish_rad

    def path_point(self, t):
        """The ideal path (9) at t [mm]."""
        return ideal_point(t, self.a_mm, self.h_mm)

    def path_values(self) -> dict:
        """What a fit reports of the path itself: t_FINISH as the paper reads it."""
        return {"t_finish_rad": self.t_finish_read_rad}

    @cached_property
    def t_finish_read_rad(self) -> float:
        """t_FINISH as the paper reads it, to `y_tol_mm` in Y (see `decimal_reading`) [rad]."""
        return decimal_reading(lambda t: ideal_point(t, self.a_mm, self.h_mm)[1],
                               self.t_finish_rad, self.y_tol_mm)


@dataclass(frozen=True)
class LinkageFit(_OnIdealPath):
    """Link lengths H, L so that the limaçon (10) stays within `err_width_mm` of the ideal path (9).

    Parameters [mm]: `a_mm` cardioid size (1); `err_width_mm` allowed deviation either side of
    the path (the paper's ERRSHIFT, Δd); `step_mm` manufacturing precision of H and L (STEP);
    `h_mm` kerf offset (effect torch_offset); `y_tol_mm` accuracy in Y of t_FINISH; `H_min_mm` ...
    `L_max_mm` the search box (LOW_H ... HIGH_L); a bound not given is the matched linkage
    (`matched_linkage`, exact for h = 0) +- a/2. `step_mm` and `y_tol_mm` not given keep the
    paper's ratios to its cam (0.01 mm and 0.001 mm at a = 25 mm, `scaled_default`); the value
    filled in is stored, so `dataclasses.replace` of `a_mm` alone keeps it.
    """
    a_mm: Annotated[float, Interval(ge=A_RANGE_MM[0], le=A_RANGE_MM[1])]
    err_width_mm: Annotated[float, Gt(0)]
    step_mm: Annotated[float | None, Gt(0)] = None
    h_mm: Annotated[float, Ge(0)] = 0.0
    y_tol_mm: Annotated[float | None, Gt(0)] = None
    H_min_mm: Annotated[float | None, doc(BOX_RANGE)] = None
    H_max_mm: Annotated[float | None, doc(BOX_RANGE)] = None
    L_min_mm: Annotated[float | None, doc(BOX_RANGE)] = None
    L_max_mm: Annotated[float | None, doc(BOX_RANGE)] = None

    EFFECTS: ClassVar[dict[str, Effect]] = {
        "torch_offset": Effect(adds="kerf offset h: the torch runs on the parallel curve at distance h",
                               equation="(2)-(3)", params=("h_mm",)),
    }

    def __post_init__(self):
        _check_path(self)
        _fill_scaled_default(self, "step_mm")
        require(self.step_mm <= self.a_mm, range_fault("step_mm", self.step_mm, f"allowed <= a_mm={self.a_mm} (the "
                                                       "lattice must be finer than the cam)"), key="step_mm")
        for key in ("H_min_mm", "H_max_mm", "L_min_mm", "L_max_mm"):
            if getattr(self, key) is not None:
                _check_link(self, key)
        box = self.bounds()
        for k, (lo, hi) in enumerate((("H_min_mm", "H_max_mm"), ("L_min_mm", "L_max_mm"))):
            if box[2 * k] > box[2 * k + 1]:
                given = getattr(self, lo) is not None and getattr(self, hi) is not None
                raise ModelError(f"bounds reversed: {lo}={box[2 * k]} > {hi}={box[2 * k + 1]}"
                                 + ("" if given else " (the one not given is the matched linkage +- a/2: give both)"),
                                 key=lo if getattr(self, lo) is not None else hi)

    @cached_property
    def matched(self) -> tuple[float, float]:
        """`matched_linkage` of this cardioid (H, L) [mm]: the NLP's start and the default box's centre."""
        return matched_linkage(self.a_mm, self.h_mm)

    def bounds(self, pad_per_a: float = 0.5) -> tuple[float, float, float, float]:
        """(H_min, H_max, L_min, L_max) [mm]: the given box, gaps filled around the matched linkage
        +- pad_per_a * a (a solver widens a derived side its optimum lies on). A derived lower end
        never drops below MIN_LINK_PER_A * a: at the default pad it is >= 1.24 a for every h < a."""
        H0, L0 = self.matched
        pad = pad_per_a * self.a_mm
        floor = MIN_LINK_PER_A * self.a_mm
        derived = (max(H0 - pad, floor), H0 + pad, max(L0 - pad, floor), L0 + pad)
        return tuple(float(g) if g is not None else d for g, d in zip(self.given_bounds(), derived))

    def given_bounds(self) -> tuple[float | None, ...]:
        """(H_min_mm, H_max_mm, L_min_mm, L_max_mm) as given, None where the task derives it."""
        return (self.H_min_mm, self.H_max_mm, self.L_min_mm, self.L_max_mm)


@dataclass(frozen=True)
class LinkageCheck(_OnIdealPath):
    """A given linkage (H, L) against the ideal path: is its limaçon within `err_width_mm`?

    The what-if counterpart of `LinkageFit`: sweep `H_mm` and `L_mm` (and `err_width_mm`) to map
    where a linkage meets the band. Parameters [mm] as in `LinkageFit`; `H_mm`, `L_mm` the links.
    """
    a_mm: Annotated[float, Interval(ge=A_RANGE_MM[0], le=A_RANGE_MM[1])]
    err_width_mm: Annotated[float, Gt(0)]
    H_mm: Annotated[float, Gt(0)]
    L_mm: Annotated[float, Gt(0)]
    h_mm: Annotated[float, Ge(0)] = 0.0
    y_tol_mm: Annotated[float | None, Gt(0)] = None

    EFFECTS: ClassVar[dict[str, Effect]] = LinkageFit.EFFECTS

    def __post_init__(self):
        _check_path(self)
        for key in ("H_mm", "L_mm"):
            _check_link(self, key)


def _check_path(task):
    """The ideal path's inputs, shared by every task on it: each in its declared range (on the
    field), then the ranges relative to the cam's size a, so no solver meets an absurd number."""
    check_fields(task)
    _fill_scaled_default(task, "y_tol_mm")
    a = task.a_mm
    for key, ok, allowed in (
            ("err_width_mm", task.err_width_mm <= LINK_MAX_PER_A * a,
             f"<= {LINK_MAX_PER_A:g} a_mm = {LINK_MAX_PER_A * a:g} (a band a hundred cams wide)"),
            ("y_tol_mm", task.y_tol_mm <= a, f"<= a_mm={a} (a reading must be finer than the cam)"),
            ("h_mm", task.h_mm < a, f"< a_mm={a} (a wider kerf than the cardioid has no cam left)")):
        require(ok, range_fault(key, getattr(task, key), f"allowed {allowed}"), key=key)


def _check_link(task, key):
    """A link length (or a bound on one): positive, and at most LINK_MAX_PER_A cam sizes."""
    value, top = getattr(task, key), LINK_MAX_PER_A * task.a_mm
    require(0 < value <= top, range_fault(key, value, f"allowed > 0 ... {LINK_MAX_PER_A:g} a_mm = {top:g} (the "
                                          "matched links are 1.7 a .. 4.6 a)"), key=key)


def scaled_default(key, a):
    """The default of `step_mm` or `y_tol_mm` for a cam of size a [mm]: the paper's value at its
    a = 25 mm, in proportion (a / 2500 and a / 25000: exactly 0.01 and 0.001 at a = 25)."""
    return a / {"step_mm": 2500, "y_tol_mm": 25000}[key]


def _fill_scaled_default(task, key):
    if getattr(task, key) is None:
        object.__setattr__(task, key, scaled_default(key, task.a_mm))     # frozen: set once, here


# --- Kinetostatics of the linkage (paper 000, Sec. V, re-derived) --------------------------
#
# Reading of Fig. 2 taken here (the figure is not in the text): a slotted-link ("wings" =
# kulisa) mechanism. Frame pivots O = (0, 0) and O1 = (H/2, 0) (frame of eq. (7)); the crank O1P,
# of length H/2, turns at phi = 2t, so P runs on the circle (5); the wing link is pinned to the
# crank at P, slides through a swivel block pivoted at O and carries the torch T at L from P
# along its axis (6), at angle t. The triangle O O1 P is isosceles (O O1 = O1 P = H/2), which is
# why the link turns at exactly half the crank speed and T runs on the limaçon (7). "H" is the
# diameter of the crank-pin circle, the longest distance between the pairs O and P. Another
# reading (a crank of length H, "H := AB" of Sec. V) does not give eq. (5) and is not taken.
#
# Bodies: 1 crank, 2 wing link, 3 swivel block. Unknowns (`LOAD_UNKNOWNS`): frame on crank at O1,
# crank on link at P, block on link (normal force N at O, couple Mp), frame on block at O, the
# driving torque M on the crank. Couples are solved as couple / H and moment rows divided by H,
# so that the matrix is dimensionless and its condition number says something about the mechanism.

LOAD_UNKNOWNS = ("R01x_N", "R01y_N", "R12x_N", "R12y_N", "N_N", "Mp_N_m", "R03x_N", "R03y_N", "M_N_m")


@dataclass(frozen=True)
class LinkageLoads:
    """Joint reactions and driving torque of the torch-guiding linkage (H, L) over a cycle.

    Links [mm]; `force_N` the torch force, opposing the torch's velocity ("against_velocity", a
    resistance to the feed) or normal to the wing link ("normal_to_link", Sec. V's b rows 7-8);
    crank at constant `crank_speed_rad_s`; masses [kg], inertias about the centre of mass
    [kg m2]; centres: the crank's at `crank_centre_mm` from O1 towards P, the link's at
    `link_centre_mm` from P towards the torch (negative: behind P); the block's at O. Gravity
    `gravity_m_s2` acts along -y (0: the linkage lies in a horizontal plane).
    """
    H_mm: Annotated[float, Gt(0), Le(1e6)]
    L_mm: Annotated[float, Gt(0), Le(1e6)]
    force_N: Annotated[float, Ge(0), Le(1e6)]
    crank_speed_rad_s: Annotated[float, Gt(0), Le(1e6)]
    crank_mass_kg: Annotated[float, Ge(0), Le(1e6)]
    crank_centre_mm: Annotated[float, doc(CENTRE_RANGE)]
    crank_inertia_kgm2: Annotated[float, Ge(0), Le(1e6)]
    link_mass_kg: Annotated[float, Ge(0), Le(1e6)]
    link_centre_mm: Annotated[float, doc(CENTRE_RANGE)]
    link_inertia_kgm2: Annotated[float, Ge(0), Le(1e6)]
    block_mass_kg: Annotated[float, Ge(0), Le(1e6)] = 0.0
    block_inertia_kgm2: Annotated[float, Ge(0), Le(1e6)] = 0.0
    gravity_m_s2: Annotated[float, Ge(0), Le(1e6)] = 0.0
    force_direction: Literal["against_velocity", "normal_to_link"] = "against_velocity"

    def __post_init__(self):
        check_fields(self)
        span = 10 * (self.H_mm + self.L_mm)
        for key in ("crank_centre_mm", "link_centre_mm"):
            value = getattr(self, key)
            require(-span <= value <= span, range_fault(key, value, f"allowed {CENTRE_RANGE} = -{span:g} ... {span:g}"),
                    key=key)


def linkage_positions(phi, H, L, c1, c2, m=np):
    """Positions [m] at crank angle phi [rad] of the linkage (H, L) [m], eqs. (5)-(7) in the frame
    of (7): a dict of (x, y) pairs P (crank pin), C1 (crank centre, c1 from O1 towards P), C2 (link
    centre, c2 from P towards the torch), T (torch), and the angles "phi" and "theta" (the link's
    angle t = phi / 2). O = (0, 0) and O1 = (H/2, 0) are fixed."""
    theta = phi / 2
    ex, ey = m.cos(phi), m.sin(phi)
    ux, uy = m.cos(theta), m.sin(theta)
    P = (H / 2 + H / 2 * ex, H / 2 * ey)
    return {"P": P, "C1": (H / 2 + c1 * ex, c1 * ey), "C2": (P[0] + c2 * ux, P[1] + c2 * uy),
            "T": (P[0] + L * ux, P[1] + L * uy), "phi": phi, "theta": theta}


def linkage_energy(positions, velocities, task: LinkageLoads):
    """Kinetic plus potential energy [J] of the linkage, from `linkage_positions` [m] and their
    time derivatives [m/s, rad/s]; gravity along -y, the block's centre O does not move."""
    def sq(v):
        return v[0] * v[0] + v[1] * v[1]
    kinetic = 0.5 * (task.crank_mass_kg * sq(velocities["C1"]) + task.crank_inertia_kgm2 * velocities["phi"] ** 2
                     + task.link_mass_kg * sq(velocities["C2"])
                     + (task.link_inertia_kgm2 + task.block_inertia_kgm2) * velocities["theta"] ** 2)
    return kinetic + task.gravity_m_s2 * (task.crank_mass_kg * positions["C1"][1]
                                          + task.link_mass_kg * positions["C2"][1])


# --- Readjustable tool: one frame distance H for a family of cams ---------

FAMILY_MAX_MEMBERS = 400


@dataclass(frozen=True)
class ToolFamily:
    """A readjustable linkage: one frame distance H for a family of cardioid cams, the wing length
    L set per cam (paper 000, Sec. VII's "readjustable machine tool for a range of shapes and sizes").

    The family is every a in `a_count` equal steps over `a_min_mm` .. `a_max_mm` with every kerf h
    of `h_values_mm` (several nozzles); each member's path is eq. (9) up to its axis crossing.
    `err_width_mm` is the band every member must keep. `H_min_mm`, `H_max_mm` bound H (not given:
    the members' matched H +- a/2, widened by the solver when the optimum lies on a side).
    """
    a_min_mm: Annotated[float, Interval(ge=A_RANGE_MM[0], le=A_RANGE_MM[1])]
    a_max_mm: Annotated[float, Interval(ge=A_RANGE_MM[0], le=A_RANGE_MM[1])]
    err_width_mm: Annotated[float, Gt(0)]
    a_count: Annotated[int, Ge(1), Le(200)] = 5
    h_values_mm: tuple = (2.0,)
    H_min_mm: Annotated[float | None, doc(f"> 0 ... {LINK_MAX_PER_A:g} a_max_mm")] = None
    H_max_mm: Annotated[float | None, doc(f"> 0 ... {LINK_MAX_PER_A:g} a_max_mm")] = None

    EFFECTS: ClassVar[dict[str, Effect]] = {}

    def __post_init__(self):
        check_fields(self)
        object.__setattr__(self, "a_count", int(self.a_count))
        require(self.a_max_mm >= self.a_min_mm, range_fault("a_max_mm", self.a_max_mm, f"allowed >= a_min_mm="
                                                            f"{self.a_min_mm}"), key="a_max_mm")
        require(self.a_count == 1 or self.a_max_mm > self.a_min_mm,
                range_fault("a_count", self.a_count, "allowed 1 when a_min_mm = a_max_mm"), key="a_count")
        h = self.h_values_mm
        ok = isinstance(h, (list, tuple)) and len(h) >= 1 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in h)
        require(ok, f"h_values_mm={h!r}: expected a list of one or more numbers [mm]", key="h_values_mm")
        object.__setattr__(self, "h_values_mm", tuple(float(v) for v in h))
        require(len(set(self.h_values_mm)) == len(self.h_values_mm),
                f"h_values_mm={list(self.h_values_mm)}: must not repeat a value", key="h_values_mm")
        require(min(self.h_values_mm) >= 0 and max(self.h_values_mm) < self.a_min_mm,
                range_fault("h_values_mm", list(self.h_values_mm), f"allowed each >= 0 and < a_min_mm={self.a_min_mm} "
                            "(the torch runs outside the cam)"), key="h_values_mm")
        members = self.a_count * len(self.h_values_mm)
        require(members <= FAMILY_MAX_MEMBERS, f"a_count x len(h_values_mm) = {members} members; at most "
                f"{FAMILY_MAX_MEMBERS}", key="a_count")
        top = LINK_MAX_PER_A * self.a_min_mm
        require(self.err_width_mm <= top, range_fault("err_width_mm", self.err_width_mm, f"allowed <= "
                                                      f"{LINK_MAX_PER_A:g} a_min_mm = {top:g}"), key="err_width_mm")
        top = LINK_MAX_PER_A * self.a_max_mm
        for key in ("H_min_mm", "H_max_mm"):
            value = getattr(self, key)
            require(value is None or 0 < value <= top, range_fault(key, value, f"allowed > 0 ... "
                                                                   f"{LINK_MAX_PER_A:g} a_max_mm = {top:g}"), key=key)
        if self.H_min_mm is not None and self.H_max_mm is not None:
            require(self.H_min_mm <= self.H_max_mm, range_fault("H_min_mm", self.H_min_mm, f"allowed <= H_max_mm="
                                                                f"{self.H_max_mm}"), key="H_min_mm")

    @cached_property
    def members(self) -> tuple[tuple[float, float], ...]:
        """(a, h) of every cam of the family [mm], a ascending, then h in the given order."""
        a = np.linspace(self.a_min_mm, self.a_max_mm, self.a_count)
        return tuple((float(x), h) for x in a for h in self.h_values_mm)
