"""Ideal torch paths of any shape: a parametric curve or a table of points,
offset by the kerf h, placed in the linkage's frame.

* `parse_expression`: x(t), y(t) as text, parsed SAFELY by walking Python's `ast` with a
  whitelist (+ - * / **, unary minus, numbers, t, named constants, sin cos tan exp log sqrt abs
  pi); no eval. One parse serves numbers (`m=np`) and CasADi symbols (`m=casadi`), so the
  derivatives are CasADi's AD of the very expression the user typed.
* `ExpressionCurve`, `TableCurve`: the cam-side curve c(t) and its derivatives; a table is a
  cubic spline in chord length (periodic when the table closes on itself).
* `offset_point`: eq. (2) generalised, c(t) + h n(t) with n the unit right-hand normal
  (y', -x') / |c'| (outward for a counter-clockwise curve, as the paper's cardioid runs).
  Where |c'| vanishes (a cusp) the normal is undefined: `find_cusps` says where, and an offset
  h > 0 through one is refused (ModelError), never a NaN.

Placement (the paper's eq. (9) generalised): the paper shifts the cardioid so that its path
starts at the origin, at t = 0, where the limaçon (10) has s = 0, both symmetric about the x axis.
`PLACEMENTS` names the two readings for a general curve: "start_at_origin" (taken by default:
the offset path's first point moved to the origin, no rotation, exactly eq. (9) for the
cardioid; the user orients the curve so it starts on its axis of symmetry heading +y) and
"as_given" (the user's coordinates are the linkage frame's).
"""
import ast
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Annotated, ClassVar

import casadi as ca
import numpy as np
from annotated_types import Ge, Gt, Interval, doc
from scipy.interpolate import CubicSpline

from mechopt.kit.errors import ModelError, quote, require
from mechopt.kit.settings import check_fields, range_fault
from mechopt.models.cam_cutter import LinkageFit, real_point

FUNCTIONS = ("sin", "cos", "tan", "exp", "log", "sqrt", "abs")
_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
           ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a ** b}
PLACEMENTS = ("start_at_origin", "as_given")
EXPRESSION_MAX_CHARS = 2000
EXPRESSION_MAX_DEPTH = 100  # nested operators; building and evaluating the expression recurse once per level
CUSP_SPEED_REL = 1e-6       # |c'| below this fraction of its largest value on the range: a cusp


def _function(name, m):
    return getattr(m, "fabs" if name == "abs" and m is ca else name)


def parse_expression(text, constants=(), *, key="x_expr"):
    """A function f(t, values, m) for the expression `text` in t and the named `constants`.

    Only the whitelist of the module docstring is accepted; anything else (a call of another
    name, an attribute, a string, a comparison) is a ModelError naming `key` and what was found.
    `values` maps each constant to a number; `m` is numpy or casadi."""
    if not isinstance(text, str) or not text.strip():
        raise ModelError(f"{key}={quote(text, 80)}: expected an expression in t, e.g. '50*cos(t)'", key=key)
    if len(text) > EXPRESSION_MAX_CHARS:
        raise ModelError(f"{key}: {len(text)} characters; at most {EXPRESSION_MAX_CHARS}", key=key)
    try:
        tree = ast.parse(text.strip(), mode="eval").body
    except SyntaxError as exc:
        raise ModelError(f"{key}={quote(text, 80)}: not an expression ({exc.msg})", key=key) from None
    except (RecursionError, MemoryError):
        raise ModelError(f"{key}: operators nested too deeply; at most {EXPRESSION_MAX_DEPTH} levels",
                         key=key) from None
    if _nesting(tree) > EXPRESSION_MAX_DEPTH:
        raise ModelError(f"{key}: operators nested more than {EXPRESSION_MAX_DEPTH} levels deep; at most "
                         f"{EXPRESSION_MAX_DEPTH}", key=key)
    allowed_names = {"t", "pi", *constants}

    def build(node):
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            if not abs(node.value) <= 1.7976931348623157e308:     # an integer of hundreds of digits: no float holds it
                digits = f" of {len(str(abs(node.value))):,} digits" if isinstance(node.value, int) else ""
                raise ModelError(f"{key}: a number{digits} beyond a float's range (at most 1.8e308)", key=key)
            value = float(node.value)
            return lambda t, v, m: value
        if isinstance(node, ast.Name):
            if node.id not in allowed_names:
                raise ModelError(f"{key}={quote(text, 80)}: unknown name {node.id!r}; allowed: t, pi"
                                 + "".join(f", {c}" for c in constants) + " (constants are given in 'constants')",
                                 key=key)
            if node.id == "t":
                return lambda t, v, m: t
            if node.id == "pi":
                return lambda t, v, m: math.pi
            name = node.id
            return lambda t, v, m: v[name]
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = build(node.operand)
            return (lambda t, v, m: -inner(t, v, m)) if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            op, left, right = _BINARY[type(node.op)], build(node.left), build(node.right)
            return lambda t, v, m: op(left(t, v, m), right(t, v, m))
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS
                and len(node.args) == 1 and not node.keywords):
            name, inner = node.func.id, build(node.args[0])
            return lambda t, v, m: _function(name, m)(inner(t, v, m))
        what = ast.get_source_segment(text.strip(), node) or type(node).__name__
        raise ModelError(f"{key}={quote(text, 80)}: {what!r} is not allowed; use numbers, t, constants, + - * / **, "
                         f"unary minus and {', '.join(FUNCTIONS)}, pi", key=key)

    return build(tree)


def _nesting(tree) -> int:
    """How deeply an expression's nodes nest, counted without recursion (a recursive count would
    fail on the very input it guards against)."""
    deepest, stack = 0, [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        stack += [(child, depth + 1) for child in ast.iter_child_nodes(node) if isinstance(child, ast.expr)]
    return deepest


def constant_values(constants, key="constants"):
    """{name: number} from the constants table: each a number, or {value, mark, why} where mark
    is given / assumed (with why), as a scene's parameters are."""
    if not isinstance(constants, dict):
        raise ModelError(f"{key}={constants!r}: expected a table of named numbers", key=key)
    out = {}
    for name, entry in constants.items():
        if not name.isidentifier() or name in ("t", "pi", *FUNCTIONS):
            raise ModelError(f"{key}.{name}: not a usable name (a Python identifier other than t, pi and the functions)",
                             key=f"{key}.{name}")
        if isinstance(entry, dict):
            unknown = set(entry) - {"value", "mark", "why", "where"}
            if unknown or "value" not in entry:
                raise ModelError(f"{key}.{name}: expected {{value, mark, why}}, got keys {sorted(entry)}", key=f"{key}.{name}")
            if entry.get("mark", "given") not in ("given", "assumed") or (entry.get("mark") == "assumed"
                                                                          and not str(entry.get("why", "")).strip()):
                raise ModelError(f"{key}.{name}: mark must be given or assumed, and an assumed value needs a 'why'",
                                 key=f"{key}.{name}")
            entry = entry["value"]
        if isinstance(entry, bool) or not isinstance(entry, (int, float)) or not math.isfinite(entry):
            raise ModelError(f"{key}.{name}={entry!r}: expected a finite number", key=f"{key}.{name}")
        out[name] = float(entry)
    return out


class _Curve:
    """What every cam-side curve offers: c(t) and c'(t) on [t0, t1] [mm, mm/rad]."""
    t0: float
    t1: float

    def speed(self, t):
        """|c'(t)| [mm/rad]."""
        return np.hypot(*self.derivative(t))

    def find_cusps(self, samples=4001):
        """Parameters t in [t0, t1] where |c'| vanishes (to CUSP_SPEED_REL of its largest value):
        local minima of the speed on a fine grid, refined by golden section. Returns a list of t."""
        t = np.linspace(self.t0, self.t1, samples)
        speed = self.speed(t)
        top = float(np.max(speed))
        if not np.isfinite(top):
            bad = t[~np.isfinite(speed)][0]
            raise ModelError(f"the curve's derivative is not finite at t = {bad:.6g} (outside the functions' domain?)",
                             key="x_expr")
        found = []
        for i in np.flatnonzero(np.r_[True, speed[1:] <= speed[:-1]] & np.r_[speed[:-1] <= speed[1:], True]):
            lo, hi = t[max(i - 1, 0)], t[min(i + 1, samples - 1)]
            for _ in range(60):           # golden section on the speed
                m1, m2 = hi - 0.618 * (hi - lo), lo + 0.618 * (hi - lo)
                lo, hi = (lo, m2) if self.speed(np.array([m1]))[0] <= self.speed(np.array([m2]))[0] else (m1, hi)
            tc = 0.5 * (lo + hi)
            if self.speed(np.array([tc]))[0] <= CUSP_SPEED_REL * top:
                found.append(float(tc))
        return sorted(set(round(x, 9) for x in found))


@dataclass(frozen=True)
class ExpressionCurve(_Curve):
    """c(t) = (x(t), y(t)) from two safely parsed expressions, t in [t0, t1] [rad]; constants by name."""
    x_expr: str
    y_expr: str
    t0: float
    t1: float
    constants: dict = field(default_factory=dict)

    def __post_init__(self):
        values = constant_values(self.constants)
        object.__setattr__(self, "_values", values)
        object.__setattr__(self, "_x", parse_expression(self.x_expr, values, key="x_expr"))
        object.__setattr__(self, "_y", parse_expression(self.y_expr, values, key="y_expr"))
        _check_range(self.t0, self.t1)

    def point(self, t, m=np):
        """c(t) [mm]; `m=casadi` for symbols."""
        x, y = self._x(t, self._values, m), self._y(t, self._values, m)
        if m is np:
            t = np.asarray(t, dtype=float)
            x, y = np.broadcast_to(x, t.shape).astype(float), np.broadcast_to(y, t.shape).astype(float)
        return x, y

    @cached_property
    def _derivatives(self):
        t = ca.SX.sym("t")
        x, y = self.point(t, m=ca)
        x, y = ca.SX(x), ca.SX(y)
        dx, dy = ca.jacobian(x, t), ca.jacobian(y, t)
        return ca.Function("curve_d", [t], [dx, dy])

    def _evaluate(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = self._derivatives(ca.DM(t.reshape(1, -1)))        # one column per t: CasADi maps it
        return [np.asarray(o).reshape(t.shape) for o in out]

    def derivative(self, t):
        """c'(t) by CasADi's AD [mm/rad]."""
        return tuple(self._evaluate(t))


@dataclass(frozen=True)
class TableCurve(_Curve):
    """A cubic spline through a table of points (x_mm, y_mm), in chord length t [mm] from the first
    point; periodic when the last point repeats the first (a closed table).

    Points must be in path order with no repeats: a repeated point (zero chord) or a reversal
    (two consecutive chords at more than 150 degrees: the table turns back on itself, which an
    unordered table does) is a ModelError naming `name` and the rows (1-based, after the header)."""
    x_mm: tuple
    y_mm: tuple
    name: str = "table"
    t0: float = field(init=False)
    t1: float = field(init=False)

    REVERSAL_DEG: ClassVar[float] = 150.0

    def __post_init__(self):
        x, y = np.asarray(self.x_mm, dtype=float), np.asarray(self.y_mm, dtype=float)
        if x.ndim != 1 or x.shape != y.shape or x.size < 4:
            raise ModelError(f"{self.name}: expected two columns x_mm, y_mm of at least 4 rows, got {x.size}",
                             key="points")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            rows = np.flatnonzero(~(np.isfinite(x) & np.isfinite(y))) + 1
            raise ModelError(f"{self.name}: rows {_rows(rows)}: not finite numbers", key="points")
        chord = np.hypot(np.diff(x), np.diff(y))
        scale = float(np.max(chord))
        closed = bool(chord.size and np.hypot(x[-1] - x[0], y[-1] - y[0]) <= 1e-9 * scale)
        repeats = np.flatnonzero(chord <= 1e-9 * scale)
        if repeats.size:
            raise ModelError(f"{self.name}: rows {_rows(np.c_[repeats + 1, repeats + 2].ravel())}: repeated point "
                             f"(zero chord); remove the duplicates", key="points")
        dx, dy = np.diff(x) / chord, np.diff(y) / chord
        turn = np.degrees(np.arccos(np.clip(dx[1:] * dx[:-1] + dy[1:] * dy[:-1], -1.0, 1.0)))
        back = np.flatnonzero(turn > self.REVERSAL_DEG)
        if back.size:
            raise ModelError(f"{self.name}: rows {_rows(np.c_[back + 1, back + 2, back + 3].ravel())}: the path "
                             f"turns back by {turn[back[0]]:.0f} degrees; the points are not in path order "
                             f"(sort them along the curve)", key="points")
        t = np.r_[0.0, np.cumsum(chord)]
        if closed:              # the closing point repeats the first to within 1e-9: make it exact
            x[-1], y[-1] = x[0], y[0]
        spline = CubicSpline(t, np.c_[x, y], bc_type="periodic" if closed else "not-a-knot")
        object.__setattr__(self, "_spline", spline)
        object.__setattr__(self, "closed", closed)
        object.__setattr__(self, "t0", 0.0)
        object.__setattr__(self, "t1", float(t[-1]))

    def point(self, t):
        xy = self._spline(np.asarray(t, dtype=float))
        return xy[..., 0], xy[..., 1]

    def derivative(self, t):
        xy = self._spline(np.asarray(t, dtype=float), 1)
        return xy[..., 0], xy[..., 1]


def _rows(rows):
    return ", ".join(str(int(r)) for r in dict.fromkeys(np.ravel(rows)))


def _check_range(t0, t1):
    for key, v in (("t0_rad", t0), ("t1_rad", t1)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ModelError(f"{key}={v!r}: expected a finite number", key=key)
    require(t1 > t0, range_fault("t1_rad", t1, f"allowed > t0_rad={t0}"), key="t1_rad")


def unit_normal(curve, t):
    """The right-hand unit normal (y', -x') / |c'| of `curve` at t: outward for a curve run
    counter-clockwise (the cardioid (1) from t = 0). Refused (ModelError) where |c'| vanishes."""
    dx, dy = curve.derivative(t)
    speed = np.hypot(dx, dy)
    floor = CUSP_SPEED_REL * float(np.max(curve.speed(np.linspace(curve.t0, curve.t1, 257))))
    if np.any(speed <= floor):
        at = np.atleast_1d(t)[np.atleast_1d(speed <= floor)][0]
        x, y = curve.point(np.array([at]))
        raise ModelError(f"the curve has a cusp at t = {at:.6g} ((x, y) = ({x[0]:.6g}, {y[0]:.6g}) mm): its normal "
                         "is undefined there, so the kerf offset cannot be taken; end the range before it or set h_mm = 0",
                         key="h_mm")
    return dy / speed, -dx / speed


def offset_point(curve, t, h):
    """The torch path c(t) + h n(t) [mm], eq. (2) generalised (h = 0: the curve itself)."""
    x, y = curve.point(t)
    if h == 0:
        return x, y
    nx, ny = unit_normal(curve, t)
    return x + h * nx, y + h * ny


@dataclass(frozen=True)
class PlacedPath:
    """The torch's ideal path in the linkage's frame: `curve` offset by `h_mm`, shifted by `shift_mm`."""
    curve: object
    h_mm: float
    shift_mm: tuple

    def point(self, t):
        """The placed torch path at t [mm] (vectorised)."""
        x, y = offset_point(self.curve, np.asarray(t, dtype=float), self.h_mm)
        return x + self.shift_mm[0], y + self.shift_mm[1]


def place(curve, h_mm, placement="start_at_origin"):
    """The curve's torch path (offset by h_mm) placed in the linkage's frame by `placement`
    (see PLACEMENTS). A cusp inside the range with h_mm > 0 is refused, naming where it is."""
    if placement not in PLACEMENTS:
        raise ModelError(f"placement={placement!r}: allowed {', '.join(PLACEMENTS)}", key="placement")
    if h_mm:
        cusps = curve.find_cusps()
        if cusps:
            x, y = curve.point(np.array(cusps[:1]))
            raise ModelError(f"the curve has a cusp at t = {cusps[0]:.6g} ((x, y) = ({x[0]:.6g}, {y[0]:.6g}) mm): "
                             "its normal is undefined there, so the kerf offset h_mm cannot be taken; end the range "
                             "before it or set h_mm = 0", key="h_mm")
    shift = (0.0, 0.0)
    if placement == "start_at_origin":
        x0, y0 = offset_point(curve, np.array([curve.t0]), h_mm)
        shift = (-float(x0[0]), -float(y0[0]))
    return PlacedPath(curve, float(h_mm), shift)


def coarse_start(point, t0, t1, span, *, side=24, nodes=48, vertices=128):
    """The best (H, L) [mm] of a side x side lattice over 0.05 .. 1.2 span (span: the path's reach
    along -x) by brute force: largest node-to-polyline distance, minimised. A start for the NLP
    where no closed form matches the limaçon to the curve (it is one for the cardioid)."""
    x, y = point(np.linspace(t0, t1, nodes))
    grid = np.linspace(0.05, 1.2, side) * span
    best = (np.inf, grid[0], grid[0])
    for H in grid:
        rx, ry = real_point(np.linspace(0.0, 2 * np.pi, vertices, endpoint=False), H, grid[:, None])  # (side, vertices)
        dist = np.hypot(rx[:, None, :] - x[None, :, None], ry[:, None, :] - y[None, :, None]).min(axis=2)
        worst = dist.max(axis=1)
        k = int(np.argmin(worst))
        if worst[k] < best[0]:
            best = (float(worst[k]), float(H), float(grid[k]))
    return best[1], best[2]


MIN_LINK_PER_SIZE = 0.01
LINK_MAX_PER_SIZE = 100.0
# the box's ranges as describe shows them, relative to the path's size (checked in ProfileFit.__post_init__)
CRANK_RANGE = f"-{LINK_MAX_PER_SIZE:g} ... {LINK_MAX_PER_SIZE:g} path sizes"
LINK_RANGE = f"> 0 ... {LINK_MAX_PER_SIZE:g} path sizes"


@dataclass(frozen=True)
class ProfileFit:
    """Link lengths H, L so that the limaçon (10) stays within `err_width_mm` of a cam of any shape.

    The cam side is a parametric curve (`x_expr`, `y_expr` in t over `t0_rad` .. `t1_rad`, with
    named `constants` [mm]) or a table of points `points_mm` ([[x, y], ...] in path order, its
    parameter the chord length [mm] over the whole table: t0_rad, t1_rad are then unused); the
    torch path is its offset by the kerf `h_mm` (effect torch_offset, eq. (2) generalised),
    placed by `placement` (PLACEMENTS). `H_min_mm` ... `L_max_mm` the search box, searched whole
    (`cam_cutter.minimax` is global over it); a side not given is the default box's: H within
    +- the path's reach (both cranks, see below), L from a hundredth of size to the reach, with
    size = the path's reach / 4 (the cardioid's a, for h = 0).

    The mirrored crank, H < 0 (reading taken). Eq. (5) puts the crank's pivot O1 at (H/2, 0) and
    its pin P on the circle of radius H/2 about it; eq. (7) is then the limaçon r = L + H cos t
    about the block's pivot O. With H < 0 the pivot O1 lies on the other side of O, the crank is
    |H|/2 long and P still runs on a circle through O, at twice the link's speed: the same
    slotted-link mechanism, its triangle O O1 P isosceles as before. Along the link the block
    sits at -H cos t from the pin for either sign, so the link must reach |H| behind the pin and
    L ahead of it whatever the sign: H < 0 is realisable wherever H > 0 is. Its limaçon is the
    H > 0 one mirrored across the y axis through O, and eq. (10)'s shift -(L + H) still puts its
    s = 0 point (now the vertex nearer the pole) at the origin. H = 0 (no crank: a circle about a
    fixed pivot) is no mechanism; `minimax` names an answer there. The other reading, H > 0 only
    (eq. (5)'s R = H/2 read as a length), excludes the mirrored crank; it is a box H_min_mm > 0.
    """
    err_width_mm: Annotated[float, Gt(0)]
    x_expr: str = ""
    y_expr: str = ""
    t0_rad: Annotated[float, Interval()] = 0.0
    t1_rad: Annotated[float, Interval()] = math.pi
    constants: dict = field(default_factory=dict)
    points_mm: tuple = ()
    h_mm: Annotated[float, Ge(0)] = 0.0
    placement: str = "start_at_origin"
    H_min_mm: Annotated[float | None, doc(CRANK_RANGE)] = None     # H < 0: the mirrored crank
    H_max_mm: Annotated[float | None, doc(CRANK_RANGE)] = None
    L_min_mm: Annotated[float | None, doc(LINK_RANGE)] = None
    L_max_mm: Annotated[float | None, doc(LINK_RANGE)] = None

    EFFECTS: ClassVar[dict] = LinkageFit.EFFECTS        # torch_offset: the same kerf h, eq. (2) generalised

    def __post_init__(self):
        if bool(self.points_mm) == bool(self.x_expr or self.y_expr):
            raise ModelError("give either x_expr and y_expr (a parametric curve) or points_mm (a table), not "
                             f"{'both' if self.points_mm else 'neither'}", key="x_expr" if not self.points_mm else "points_mm")
        if self.points_mm:
            rows = np.asarray(self.points_mm, dtype=float) if _is_table(self.points_mm) else None
            if rows is None:
                raise ModelError("points_mm: expected rows [x_mm, y_mm]", key="points_mm")
            curve = TableCurve(tuple(rows[:, 0]), tuple(rows[:, 1]), name="points_mm")
        else:
            curve = ExpressionCurve(self.x_expr, self.y_expr, self.t0_rad, self.t1_rad, dict(self.constants))
        check_fields(self)      # after the curve: its parser says what an expression is better than "expected text"
        try:
            with np.errstate(all="raise"):
                sample = curve.point(np.linspace(curve.t0, curve.t1, 257))
        except (FloatingPointError, OverflowError, ZeroDivisionError, ValueError) as exc:
            raise ModelError(f"the curve cannot be evaluated on t0_rad .. t1_rad ({exc})", key="x_expr") from None
        if not np.all(np.isfinite(sample)):
            raise ModelError("the curve is not finite on t0_rad .. t1_rad", key="x_expr")
        path = place(curve, self.h_mm, self.placement)
        object.__setattr__(self, "curve", curve)
        object.__setattr__(self, "path", path)
        x = path.point(np.linspace(curve.t0, curve.t1, 1025))[0]
        reach = float(max(-x.min(), x.max() - x.min()))
        if not reach > 0:
            raise ModelError("the placed path has no extent along x: the limaçon's axis is x; rotate the curve",
                             key="x_expr")
        object.__setattr__(self, "size_mm", reach / 4)
        require(self.h_mm <= self.size_mm, range_fault("h_mm", self.h_mm, f"allowed <= {self.size_mm:.6g} (a quarter "
                                                       "of the path's reach)"), key="h_mm")
        top = LINK_MAX_PER_SIZE * self.size_mm
        require(self.err_width_mm <= top, range_fault("err_width_mm", self.err_width_mm, f"allowed <= {top:.6g}"),
                key="err_width_mm")
        for key, v in zip(("H_min_mm", "H_max_mm", "L_min_mm", "L_max_mm"), self.given_bounds()):
            crank = key.startswith("H")             # H < 0: the mirrored crank (the class docstring)
            require(v is None or ((-top <= v if crank else 0 < v) and v <= top),
                    range_fault(key, v, f"allowed {f'{-top:.6g}' if crank else '> 0'} ... {top:.6g}"), key=key)
        box = self.bounds()
        for lo, hi, k in (("H_min_mm", "H_max_mm", 0), ("L_min_mm", "L_max_mm", 2)):
            if box[k] > box[k + 1]:
                raise ModelError(f"bounds reversed: {lo}={box[k]:.6g} > {hi}={box[k + 1]:.6g}"
                                 " (a side not given is the default box's: give both)", key=lo)

    @property
    def t_start_rad(self) -> float:
        return self.curve.t0

    @property
    def t_end_rad(self) -> float:
        return self.curve.t1

    def path_point(self, t):
        """The torch path in the linkage's frame at t [mm]."""
        return self.path.point(t)

    def path_values(self) -> dict:
        return {}

    @cached_property
    def matched(self) -> tuple[float, float]:
        """(H, L) [mm]: the NLP's start and the default box's centre (`coarse_start`)."""
        return coarse_start(self.path_point, self.t_start_rad, self.t_end_rad, 4 * self.size_mm)

    def bounds(self) -> tuple[float, float, float, float]:
        """(H_min, H_max, L_min, L_max) [mm]: the given sides; a side not given is the path's reach
        (4 sizes) either side for H (both cranks), MIN_LINK_PER_SIZE sizes .. the reach for L."""
        reach, floor = 4 * self.size_mm, MIN_LINK_PER_SIZE * self.size_mm
        derived = (-reach, reach, floor, reach)
        return tuple(float(g) if g is not None else d for g, d in zip(self.given_bounds(), derived))

    def given_bounds(self) -> tuple[float | None, ...]:
        """(H_min_mm, H_max_mm, L_min_mm, L_max_mm) as given, None where the task derives it."""
        return (self.H_min_mm, self.H_max_mm, self.L_min_mm, self.L_max_mm)


def _is_table(rows):
    try:
        array = np.asarray(rows, dtype=float)
    except (TypeError, ValueError):
        return False
    return array.ndim == 2 and array.shape[1] == 2
