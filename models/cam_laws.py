"""The cam law library: motion laws S(xi) for a unit rise over a unit interval, 0 <= xi <= 1,
S(0) = 0, S(1) = 1, each with S', S'', S''' (d/dxi) in closed form and its peak coefficients
Cv = max |S'|, Ca = max |S''|, Cj = max |S'''| (the dimensionless factors a designer compares
laws by: a rise of h [mm] over beta [rad] has peak velocity Cv h / beta [mm/rad], acceleration
Ca h / beta^2, jerk Cj h / beta^3).

Each closed form is written ONCE as a function `forms(x, m)` -> (S, S', S'', S''') of `m`, a
module: numpy for numbers (`Law.values`), casadi for the expressions the package's integrators
take (`Law.expression`, as models/cam_profile.py's `parse_expression` serves both). Piecewise
laws select their piece with `m.where` (numpy) or `m.if_else` (casadi).

Laws (Rothbart (ed.), *Cam Design Handbook*, McGraw-Hill 2004, ch. 2 "Basic curves" and ch. 3;
Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., Industrial Press 2009, ch. 3; Chen,
*Mechanics and Design of Cam Mechanisms*, Pergamon 1982):

* cycloidal, harmonic (simple harmonic), double_harmonic, polynomial_345, polynomial_4567,
  cubic (Rothbart's "cubic no. 2", 3 xi^2 - 2 xi^3): one closed form each;
* modified_sine (Kloomok and Muffley's, pieces at 1/8 and 7/8);
* the sine-constant-cosine-acceleration (SCCA) family, `scca(b, c, cv)` (Norton, *Design of
  Machinery*, ch. 8, "the SCCA family", with b + c + d = 1; a constant-velocity part cv as the
  MechDesigner manual's SCCA law has): over the first half, a quarter sine rising over b/2, a
  constant over d/2, a quarter cosine falling over c/2 and zero over cv/2; the second half
  mirrors it negatively. Named members: modified_trapezoid (b = c = 1/4), constant_acceleration
  (b = c = 0); the family also holds cycloidal (b = c = 1/2), harmonic (b = 0, c = 1) and
  modified_sine (b = 1/4, c = 3/4), which the tests use as independent checks of those laws' own
  forms. `law("scca(b, c[, cv])")` names a member;
* trapezoid: trapezoidal acceleration, linear ramps over 1/8 (the jerk a square wave);
* `polynomial(conditions)`: the polynomial of least degree meeting given values of S and its
  derivatives at given xi (both ends, for a rise: S, S', S'' (, S''')), from the linear system.

`Law.end_order` is the derivative order that first jumps against a dwell at either end (a rise
between dwells): 2 for harmonic (an acceleration jump, infinite jerk there), 3 for cycloidal.
Cj is the largest |S'''| inside 0 <= xi <= 1, infinite where S'' steps at a join inside (the
constant-acceleration law at 1/2); a law whose acceleration jumps at an end against a dwell has
an infinite jerk THERE as well, which `end_order` states.
"""
import functools
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from mechopt.kit.errors import ModelError, quote, require

PEAK_GRID = 20_001          # samples of 0..1 where the peaks are looked for before polishing
PEAK_XTOL = 1e-12           # the polishing search's tolerance in xi
JUMP_TOL = 1e-9             # a step across a piece join larger than this (relative): a discontinuity


def _where(m, condition, yes, no):
    """`yes` where `condition`, else `no`: numpy's where or casadi's if_else, by `m`."""
    return np.where(condition, yes, no) if m is np else m.if_else(condition, yes, no)


def _select(m, x, breaks, pieces):
    """Piece k of `pieces` (each a value) on breaks[k-1] <= x < breaks[k]: nested selections,
    the last piece the outermost default."""
    out = pieces[-1]
    for brk, piece in zip(reversed(breaks), reversed(pieces[:-1])):
        out = _where(m, x < brk, piece, out)
    return out


@dataclass(frozen=True)
class Law:
    """A motion law for a unit rise over 0 <= xi <= 1: `forms(x, m)` -> (S, S', S'', S''') for
    `m` numpy or casadi; `breaks` the xi where its pieces join (the peaks' search keeps them);
    `end_order` the first derivative order that jumps at an end against a dwell; `source` where
    the form is printed."""
    name: str
    forms: Callable = field(repr=False)
    breaks: tuple = ()
    end_order: int = 3
    source: str = ""

    def values(self, xi):
        """(S, S', S'', S''') as float arrays at `xi` (0 <= xi <= 1; outside, the closed form
        continued: a caller with dwells clips first)."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        return tuple(np.broadcast_to(np.asarray(v, dtype=float), xi.shape).copy() for v in self.forms(xi, np))

    def expression(self, xi):
        """(S, S', S'', S''') as CasADi expressions of the CasADi symbol `xi`."""
        import casadi as ca  # here, not at the top: a loom plan reaches the library and needs none
        return self.forms(xi, ca)

    @cached_property
    def peaks(self) -> dict:
        """{"Cv": max |S'|, "Ca": max |S''|, "Cj": max |S'''|} over 0 <= xi <= 1: a dense grid
        (the piece joins among its points), each largest polished by a bounded search between its
        grid neighbours."""
        from scipy.optimize import minimize_scalar
        xi = np.unique(np.r_[np.linspace(0.0, 1.0, PEAK_GRID), self.breaks])
        out = {}
        for key, k in (("Cv", 1), ("Ca", 2), ("Cj", 3)):
            size = np.abs(self.values(xi)[k])
            i = int(np.argmax(size))
            lo, hi = xi[max(i - 1, 0)], xi[min(i + 1, xi.size - 1)]
            best = minimize_scalar(lambda x: -abs(float(self.values(x)[k][0])), bounds=(lo, hi), method="bounded",
                                   options={"xatol": PEAK_XTOL})
            out[key] = max(float(size[i]), float(-best.fun))
        if any(order <= 2 for _, order, _ in self.interior_jumps()):
            out["Cj"] = math.inf            # an acceleration (or velocity) step inside: infinite jerk there
        return out

    def interior_jumps(self) -> list[tuple[float, int, float]]:
        """(xi, order, jump) where S' or S'' steps at a piece join inside the interval (the
        constant-acceleration law's S'' at 1/2): a step of S'' is an infinite jerk."""
        out = []
        for brk in self.breaks:
            left, right = self.values(np.nextafter(brk, -np.inf)), self.values(brk)
            for order in (1, 2):
                jump = float(right[order][0] - left[order][0])
                if abs(jump) > JUMP_TOL * (1 + abs(float(right[order][0]))):
                    out.append((float(brk), order, jump))
        return out

    def continuity(self) -> dict:
        """The values at the ends: {"start": (S, S', S'', S'''), "end": (...)} at xi = 0 and 1."""
        start, end = (tuple(float(v[0]) for v in self.values(x)) for x in (0.0, 1.0))
        return {"start": start, "end": end}


# ---------------------------------------------------------------- one closed form each
# The four laws the lift's integrators used before the library (cycloidal, harmonic, modified_sine,
# polynomial_345) keep S in the arithmetic of their old copies: CasADi's AD of it is the same to the bit.

TWO_PI = 2 * math.pi


def _cycloidal(x, m):
    return (x - m.sin(2 * math.pi * x) / (2 * math.pi), 1 - m.cos(TWO_PI * x),
            TWO_PI * m.sin(TWO_PI * x), TWO_PI**2 * m.cos(TWO_PI * x))


def _harmonic(x, m):
    pi = math.pi
    return ((1 - m.cos(math.pi * x)) / 2, pi / 2 * m.sin(pi * x), pi**2 / 2 * m.cos(pi * x),
            -pi**3 / 2 * m.sin(pi * x))


def _double_harmonic(x, m):
    """Norton's double harmonic: S = [(1 - cos pi x) - (1 - cos 2 pi x) / 4] / 2 (a rise with no
    dwell after it: its acceleration is 0 at the start, -pi^2 at the end)."""
    pi = math.pi
    return (((1 - m.cos(pi * x)) - (1 - m.cos(2 * pi * x)) / 4) / 2,
            pi / 2 * (m.sin(pi * x) - m.sin(2 * pi * x) / 2),
            pi**2 / 2 * (m.cos(pi * x) - m.cos(2 * pi * x)),
            pi**3 / 2 * (2 * m.sin(2 * pi * x) - m.sin(pi * x)))


def _polynomial_345(x, m):
    return (x**3 * (10 - 15 * x + 6 * x**2), 30 * x**2 * (1 - x)**2, 60 * x * (1 - x) * (1 - 2 * x),
            60 * (1 - 6 * x + 6 * x**2))


def _polynomial_4567(x, m):
    return (x**4 * (35 - 84 * x + 70 * x**2 - 20 * x**3), 140 * x**3 * (1 - x)**3,
            420 * x**2 * (1 - x)**2 * (1 - 2 * x), 840 * x * (1 - x) * (1 - 5 * x + 5 * x**2))


def _cubic(x, m):
    return x**2 * (3 - 2 * x), 6 * x * (1 - x), 6 - 12 * x, -12 + 0 * x


def _modified_sine(x, m):
    """Kloomok and Muffley's modified sine: a cycloid's quarter (period 1/2) over 0..1/8 and
    7/8..1, a harmonic's (period 3/2) between."""
    pi, k = math.pi, 4 + math.pi
    inner = math.pi * (4 * x + 1) / 3
    s_first = (math.pi * x - m.sin(4 * math.pi * x) / 4) / k
    s_middle = (2 + math.pi * x - 9 * m.sin(inner) / 4) / k
    s_last = (4 + math.pi * x - m.sin(4 * math.pi * x) / 4) / k
    v_outer, v_middle = pi * (1 - m.cos(4 * pi * x)) / k, pi * (1 - 3 * m.cos(inner)) / k
    a_outer, a_middle = 4 * pi**2 * m.sin(4 * pi * x) / k, 4 * pi**2 * m.sin(inner) / k
    j_outer, j_middle = 16 * pi**3 * m.cos(4 * pi * x) / k, 16 * pi**3 / 3 * m.cos(inner) / k
    breaks = (0.125, 0.875)
    return (_select(m, x, breaks, (s_first, s_middle, s_last)),
            *(_select(m, x, breaks, (outer, middle, outer)) for outer, middle in
              ((v_outer, v_middle), (a_outer, a_middle), (j_outer, j_middle))))


# ---------------------------------------------------------------- laws built from acceleration pieces

@dataclass(frozen=True)
class _Piece:
    """S(u) = c0 + c1 u + c2 u^2 + c3 u^3 + B sin(w u + phi), u = x - x0, on [x0, next break)."""
    x0: float
    c: tuple
    B: float = 0.0
    w: float = 0.0
    phi: float = 0.0

    def forms(self, x, m):
        u = x - self.x0
        c0, c1, c2, c3 = self.c
        poly = (c0 + u * (c1 + u * (c2 + u * c3)), c1 + u * (2 * c2 + 3 * c3 * u), 2 * c2 + 6 * c3 * u, 6 * c3 + 0 * u)
        if self.B == 0.0:
            return poly
        sin, cos = m.sin(self.w * u + self.phi), m.cos(self.w * u + self.phi)
        B, w = self.B, self.w
        return (poly[0] + B * sin, poly[1] + B * w * cos, poly[2] - B * w**2 * sin, poly[3] - B * w**3 * cos)


def _integrated(accelerations):
    """Pieces of S from pieces of S'' given as (x0, x1, A, w, phi, k0, k1): S'' = A sin(w u + phi)
    + k0 + k1 u on [x0, x1], u = x - x0, integrated twice from S(0) = S'(0) = 0, continuous in S
    and S', then scaled to S(1) = 1."""
    pieces, s, v = [], 0.0, 0.0
    for x0, x1, A, w, phi, k0, k1 in accelerations:
        B = -A / w**2 if A else 0.0
        c = (s - B * math.sin(phi), v - B * w * math.cos(phi), k0 / 2, k1 / 6)
        piece = _Piece(x0, c, B, w, phi)
        pieces.append(piece)
        s, v = (float(f) for f in piece.forms(np.float64(x1), np)[:2])
    scale = 1.0 / s
    return tuple(_Piece(p.x0, tuple(scale * ci for ci in p.c), scale * p.B, p.w, p.phi) for p in pieces)


def _piecewise(pieces):
    breaks = tuple(float(p.x0) for p in pieces[1:])

    def forms(x, m):
        each = [p.forms(x, m) for p in pieces]
        return tuple(_select(m, x, breaks, [e[k] for e in each]) for k in range(4))
    return forms, breaks


def _mirrored(first_half):
    """Acceleration pieces over 0..1 from those over 0..1/2: S''(x) = -S''(1 - x) (a symmetric
    rise). A piece A sin(w u + phi) + k0 + k1 u on [x0, x1] (length L) mirrors to [1 - x1, 1 - x0]
    as A sin(w u - w L - phi) - k0 - k1 L + k1 u."""
    back = [(1 - x1, 1 - x0, A, w, -w * (x1 - x0) - phi, -k0 - k1 * (x1 - x0), k1)
            for x0, x1, A, w, phi, k0, k1 in reversed(first_half)]
    return list(first_half) + back


def scca(b: float, c: float, cv: float = 0.0, name: str | None = None) -> Law:
    """The sine-constant-cosine-acceleration law: over the first half, a quarter sine rising
    over b/2, a constant over d/2, a quarter cosine falling over c/2 and zero acceleration
    (constant velocity) over cv/2, d = 1 - b - c - cv; the second half mirrors it negatively.
    b, c, cv >= 0, b + c + cv <= 1 (module docstring; cv = 0 is Norton's three-parameter family)."""
    parts = {"b": b, "c": c, "cv": cv}
    require(all(isinstance(v, (int, float)) and math.isfinite(v) and 0 <= v <= 1 for v in parts.values())
            and b + c + cv <= 1 + 1e-12 and cv < 1,
            f"law=scca(b={b!r}, c={c!r}, cv={cv!r}): allowed 0 <= b, c, cv and b + c + cv <= 1, cv < 1", key="law")
    d = max(1.0 - b - c - cv, 0.0)
    edges = np.cumsum([0.0, b / 2, d / 2, c / 2, cv / 2])
    shapes = ((1.0, math.pi / b if b else 0.0, 0.0, 0.0),            # (A, w, phi, k0): a quarter sine up
              (0.0, 0.0, 0.0, 1.0),                                  # the constant
              (1.0, math.pi / c if c else 0.0, math.pi / 2, 0.0),    # a quarter cosine down
              (0.0, 0.0, 0.0, 0.0))                                  # constant velocity
    half = [(x0, x1, A, w, phi, k0, 0.0) for x0, x1, (A, w, phi, k0) in zip(edges[:-1], edges[1:], shapes)
            if x1 - x0 > 0]
    forms, breaks = _piecewise(_integrated(_mirrored(half)))
    label = f"scca_b{b:g}_c{c:g}" + (f"_cv{cv:g}" if cv else "")
    return Law(name or label, forms, breaks, end_order=3 if b > 0 else 2,
               source="Norton, Design of Machinery, ch. 8 (the SCCA family); a constant-velocity part as in "
                      "the MechDesigner manual's SCCA law")


def _trapezoid() -> Law:
    """Trapezoidal acceleration: linear ramps over 1/8 (a square-wave jerk)."""
    e = 1 / 8
    half = [(0.0, e, 0.0, 0.0, 0.0, 0.0, 1 / e), (e, 3 * e, 0.0, 0.0, 0.0, 1.0, 0.0),
            (3 * e, 4 * e, 0.0, 0.0, 0.0, 1.0, -1 / e)]
    forms, breaks = _piecewise(_integrated(_mirrored(half)))
    return Law("trapezoid", forms, breaks, end_order=3, source="Norton, Cam Design and Manufacturing Handbook, "
               "2nd ed., ch. 3 (trapezoidal acceleration)")


# ---------------------------------------------------------------- polynomial from conditions

MAX_CONDITIONS = 12         # a polynomial law of degree 11 at most: beyond, its linear system is ill-conditioned


def polynomial(conditions: Sequence, name: str | None = None) -> Law:
    """The polynomial of least degree (number of conditions - 1) meeting `conditions`, each
    (xi, order, value): d^order S / dxi^order = value at xi (order 0..3), 2 to MAX_CONDITIONS of
    them. For a rise between dwells, S, S', S'' at both ends give the 3-4-5 polynomial, and
    S''' = 0 too the 4-5-6-7. Its name states its degree ("polynomial_deg5")."""
    rows = [tuple(c) if isinstance(c, (list, tuple)) else (c,) for c in conditions]
    said = f"law=polynomial({quote(rows, 80)})"
    require(2 <= len(rows) <= MAX_CONDITIONS and all(len(r) == 3 for r in rows),
            f"{said}: expected two or more (xi, order, value), at most {MAX_CONDITIONS}", key="law")
    require(all(all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in r)
                and int(r[1]) == r[1] and 0 <= r[1] <= 3 for r in rows),
            f"{said}: order allowed 0..3, xi and value finite numbers", key="law")
    degree = len(rows) - 1
    powers = np.arange(degree + 1)
    A = np.zeros((len(rows), degree + 1))
    for i, (xi, order, _) in enumerate(rows):
        order = int(order)
        falling = np.array([math.perm(int(p), order) for p in powers], dtype=float)
        A[i] = falling * np.where(powers >= order, float(xi) ** np.maximum(powers - order, 0), 0.0)
    rank = np.linalg.matrix_rank(A)
    require(rank == len(rows), f"{said}: the conditions are not independent (rank {rank} of {len(rows)}): "
            "a condition repeated or contradicting another", key="law")
    coef = np.linalg.solve(A, np.array([r[2] for r in rows], dtype=float))
    derivs = [coef]
    for _ in range(3):
        derivs.append(derivs[-1][1:] * np.arange(1, derivs[-1].size) if derivs[-1].size > 1 else np.zeros(1))

    def horner(cs, x):
        out = 0 * x + float(cs[-1])
        for ci in cs[-2::-1]:
            out = out * x + float(ci)
        return out

    def forms(x, m):
        return tuple(horner(cs, x) for cs in derivs)
    return Law(name or f"polynomial_deg{degree}", forms, end_order=_first_jump(rows),
               source="the linear system of its boundary conditions (Norton, ch. 3, polynomial functions)")


def _first_jump(rows) -> int:
    """The lowest derivative order with no zero condition at both ends (what a dwell would break)."""
    for order in range(1, 4):
        ends = {r[0] for r in rows if r[1] == order and r[2] == 0}
        if not {0, 1} <= ends:
            return order
    return 4


# ---------------------------------------------------------------- a law known by its numbers

def numeric_law(source, name: str | None = None) -> Law:
    """A law known by numbers only: `source.values(xi)` -> (S, S', S'', S''') on 0 <= xi <= 1 (a
    synthesised spline law, models/cam_law.py `SplineLaw`). Its numpy form is those numbers (its
    knots inside the rise are the breaks the peaks' search keeps); it has no CasADi form."""
    def forms(x, m):
        if m is not np:
            raise ModelError(f"law={source}: known by its numbers only, it has no CasADi form", key="law")
        return tuple(source.values(x))
    breaks = tuple(float(k) for k in np.unique(getattr(source, "knots", ())) if 0 < k < 1)
    ends = [np.abs(np.asarray(v, dtype=float)).max() for v in source.values(np.array([0.0, 1.0]))[1:]]
    order = next((k for k, size in enumerate(ends, start=1) if size > JUMP_TOL), 4)
    return Law(name or str(source), forms, breaks, end_order=order, source="its numbers (a synthesised law)")


# ---------------------------------------------------------------- the library

_BOOK = "Rothbart (ed.), Cam Design Handbook, 2004, ch. 2-3; Norton, Cam Design and Manufacturing Handbook, 2nd ed., ch. 3"
_LAWS: dict[str, Law] = {}


def _add(law: Law):
    _LAWS[law.name] = law


_add(Law("cycloidal", _cycloidal, end_order=3, source=_BOOK))
_add(Law("harmonic", _harmonic, end_order=2, source=_BOOK))
_add(Law("modified_sine", _modified_sine, (0.125, 0.875), end_order=3, source=_BOOK))
_add(scca(0.25, 0.25, name="modified_trapezoid"))
_add(Law("polynomial_345", _polynomial_345, end_order=3, source=_BOOK))
_add(Law("polynomial_4567", _polynomial_4567, end_order=4, source=_BOOK))
_add(Law("double_harmonic", _double_harmonic, end_order=2, source=_BOOK))
_add(scca(0.0, 0.0, name="constant_acceleration"))
_add(_trapezoid())
_add(Law("cubic", _cubic, end_order=2, source=_BOOK))


def names() -> tuple[str, ...]:
    """The library's law names."""
    return tuple(_LAWS)


_NUMBER = r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*"
_SCCA_NAME = re.compile(rf"scca\({_NUMBER},{_NUMBER}(?:,{_NUMBER})?\)")
SCCA_FORM = "scca(b, c[, cv])"          # a family member by name, as a scene's law


def law(name) -> Law:
    """The library law `name`, or a member of the SCCA family named "scca(b, c)" or
    "scca(b, c, cv)"; a `Law` passes through, a synthesised law (anything with `values(xi)`
    giving S, S', S'', S''') becomes a `numeric_law`. An unknown name: ModelError listing them."""
    if isinstance(name, Law):
        return name
    if not isinstance(name, str) and callable(getattr(name, "values", None)):
        return _numeric_cached(name)                # a synthesised law: its numbers
    if isinstance(name, str) and name in _LAWS:
        return _LAWS[name]
    member = _SCCA_NAME.fullmatch(name.strip()) if isinstance(name, str) else None
    if member is None:
        raise ModelError(f"law={quote(name)}: unknown motion law; allowed: {', '.join(_LAWS)}, or {SCCA_FORM} "
                         "(fractions of the rise)", key="law")
    return _scca_named(*(float(g) for g in member.groups() if g is not None))


@functools.lru_cache(maxsize=16)
def _numeric_cached(source) -> Law:
    return numeric_law(source)


@functools.lru_cache(maxsize=64)
def _scca_named(b: float, c: float, cv: float = 0.0) -> Law:
    return scca(b, c, cv, name=f"scca({b:g}, {c:g}" + (f", {cv:g})" if cv else ")"))
