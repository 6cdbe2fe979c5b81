"""A motion per operation of a cyclogram, and clearances between two motions.

An operation may carry a cam law (`mechopt.laws`: a unit rise S(xi), xi = its fraction of the
operation's angle) and a stroke h: `stroke_mm` for a translating output, `stroke_deg` for an
oscillating one (a lever's swing; h in rad below, its limits `max_accel_rad_s2`,
`max_velocity_rad_s` and its peaks in rad/s^2, rad/s); its phase angle t is then the motion's duration. At a
main-shaft speed n [rpm] (omega = 2 pi n / 60 rad/s, the angle t deg lasting t / (6 n) s) its
peak velocity and acceleration are (Norton, Cam Design and Manufacturing Handbook, 2nd ed., ch. 3;
Rothbart (ed.), Cam Design Handbook, 2004, ch. 2)

    v = Cv h / T,    a = Ca h / T^2,      T = t / (6 n) s,   h [m] or [rad],

so a limit a <= a_max is T >= sqrt(Ca h / a_max) and v <= v_max is T >= Cv h / v_max: a least
duration, as an operation's `min_ms` (its angle 0.006 n T grows with the speed; the highest-speed
solvers take it as they take the stress bound). `least_ms` gives it; the network folds it into the
operation's time floor.

A displacement fraction c of the stroke is reached at the fraction x_c of the angle with
S(x_c) = c (`angle_fraction`, brentq on the law): the instant p(from) + x_c (p(to) - p(from)), a
fixed fraction for a fixed law, so a clearance between two motions is one linear row in the event
times (not a difference constraint unless both angles are fixed).
"""
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Annotated

from annotated_types import Ge, Gt, Le

from mechopt.kit.errors import MechoptError, ModelError
from mechopt.models.cam_laws import law as cam_law

MAX_STROKE_MM = 1e5
MAX_STROKE_DEG = 360.0         # an oscillating output swings less than a turn
MAX_ACCEL_M_S2 = 1e6
MAX_VELOCITY_M_S = 1e4
MAX_ACCEL_RAD_S2 = 1e6
MAX_VELOCITY_RAD_S = 1e4
# the numeric cells: (name, upper bound, unit, "linear" or "angular")
NUMBERS = (("stroke_mm", MAX_STROKE_MM, "mm", "linear"), ("max_accel_m_s2", MAX_ACCEL_M_S2, "m/s^2", "linear"),
           ("max_velocity_m_s", MAX_VELOCITY_M_S, "m/s", "linear"), ("stroke_deg", MAX_STROKE_DEG, "deg", "angular"),
           ("max_accel_rad_s2", MAX_ACCEL_RAD_S2, "rad/s^2", "angular"),
           ("max_velocity_rad_s", MAX_VELOCITY_RAD_S, "rad/s", "angular"))
MOTION_KEYS = ("law", "direction") + tuple(name for name, *_ in NUMBERS)
DIRECTIONS = ("out", "back")   # the stroke away from the mechanism's rest position, or back to it
FRACTION_XTOL = 1e-14          # brentq's tolerance on x_c (a fraction of the angle)


@dataclass(frozen=True)
class Motion:
    """An operation's motion: its law's name, stroke [mm] (translating) or [deg] (oscillating, not
    both) and limits (None: not given; in m/s^2, m/s with stroke_mm, rad/s^2, rad/s with stroke_deg)."""
    law: str
    stroke_mm: Annotated[float | None, Gt(0), Le(MAX_STROKE_MM)] = None
    max_accel_m_s2: Annotated[float | None, Gt(0), Le(MAX_ACCEL_M_S2)] = None
    max_velocity_m_s: Annotated[float | None, Gt(0), Le(MAX_VELOCITY_M_S)] = None
    direction: str = "out"
    stroke_deg: Annotated[float | None, Gt(0), Le(MAX_STROKE_DEG)] = None
    max_accel_rad_s2: Annotated[float | None, Gt(0), Le(MAX_ACCEL_RAD_S2)] = None
    max_velocity_rad_s: Annotated[float | None, Gt(0), Le(MAX_VELOCITY_RAD_S)] = None

    @property
    def peaks(self) -> dict:
        return cam_law(self.law).peaks

    @property
    def angular(self) -> bool:
        """An oscillating output (stroke_deg)."""
        return self.stroke_deg is not None

    @property
    def stroke(self) -> float | None:
        """The stroke as given [mm, or deg for an oscillating output]; None without one."""
        return self.stroke_deg if self.angular else self.stroke_mm

    @property
    def stroke_si(self) -> float:
        """h [m, or rad for an oscillating output]; 0 without a stroke."""
        return math.radians(self.stroke_deg) if self.angular else (self.stroke_mm or 0.0) / 1000.0

    @property
    def units(self) -> tuple[str, str, str]:
        """(stroke, acceleration, velocity) units as key suffixes: mm, m_s2, m_s or deg, rad_s2, rad_s."""
        return ("deg", "rad_s2", "rad_s") if self.angular else ("mm", "m_s2", "m_s")

    def least_ms(self) -> tuple[float, str]:
        """The least duration the limits allow [ms] and which limit sets it ("max_accel",
        "max_velocity"; 0 and "" with none): T >= sqrt(Ca h / a_max), Cv h / v_max."""
        h, out = self.stroke_si, (0.0, "")
        a_max = self.max_accel_rad_s2 if self.angular else self.max_accel_m_s2
        v_max = self.max_velocity_rad_s if self.angular else self.max_velocity_m_s
        if a_max is not None:
            out = max(out, (1000.0 * math.sqrt(self.peaks["Ca"] * h / a_max), "max_accel"))
        if v_max is not None:
            out = max(out, (1000.0 * self.peaks["Cv"] * h / v_max, "max_velocity"))
        return out

    def displacement(self, xi):
        """The signed displacement at angle fractions xi (clipped to [0, 1]) [mm, deg for an
        oscillating output, or a fraction of the stroke without one]: + out, - back."""
        import numpy as np

        S = cam_law(self.law).values(np.clip(np.asarray(xi, dtype=float), 0.0, 1.0))[0]
        return (1.0 if self.direction == "out" else -1.0) * (self.stroke or 1.0) * S

    def peak_velocity(self, t_deg: float, speed_rpm: float) -> float:
        """Cv h / T, T = t / (6 n) s [m/s, or rad/s for an oscillating output]."""
        return self.peaks["Cv"] * self.stroke_si * 6.0 * speed_rpm / t_deg

    def peak_accel(self, t_deg: float, speed_rpm: float) -> float:
        """Ca h / T^2, T = t / (6 n) s [m/s^2, or rad/s^2 for an oscillating output]."""
        return self.peaks["Ca"] * self.stroke_si * (6.0 * speed_rpm / t_deg) ** 2

    def angle_fraction(self, c: float) -> float:
        """x_c: the fraction of the operation's angle at which the fraction c of the stroke is reached."""
        return _angle_fraction(self.law, float(c))


@lru_cache(maxsize=256)
def _angle_fraction(name: str, c: float) -> float:
    if c <= 0.0 or c >= 1.0:
        return min(max(c, 0.0), 1.0)
    # imported here: scipy's import (~0.5 s) is paid by a clearance alone, not by every cyclogram
    from scipy.optimize import brentq
    law = cam_law(name)
    # S rises monotonically from 0 to 1 (every library law: S' >= 0); brentq brackets the one root
    return brentq(lambda x: float(law.values([x])[0][0]) - c, 0.0, 1.0, xtol=FRACTION_XTOL)


def motion_of(op: dict, key: str) -> Motion | None:
    """The Motion of an operation row (None without a `law`), its cells checked: errors name the
    row and the key with the allowed range."""
    given = {k: op[k] for k in MOTION_KEYS if k in op and op[k] not in (None, "")}
    if not given:
        return None
    if "law" not in given:
        raise ModelError(f"{key}.{next(iter(given))}: a stroke or a limit needs the operation's motion law "
                         f"(column law)", key=f"{key}.law")
    try:
        cam_law(str(given["law"]))
    except MechoptError as exc:
        raise ModelError(f"{key}.{exc}", key=f"{key}.law") from None
    numbers, kinds = {}, {}
    for name, top, unit, kind in NUMBERS:
        if name not in given:
            continue
        value = given[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= top:
            raise ModelError(f"{key}.{name}={value!r}: allowed (0, {top:g}] {unit}", key=f"{key}.{name}")
        numbers[name], kinds[name] = float(value), kind
    _check_kinds(key, kinds)
    return Motion(str(given["law"]), **numbers, direction=_direction(key, given))


def _check_kinds(key: str, kinds: dict) -> None:
    """One stroke, of one kind, and limits of that kind: a translating output (stroke_mm, m/s^2,
    m/s) or an oscillating one (stroke_deg, rad/s^2, rad/s), never mixed."""
    if "stroke_mm" in kinds and "stroke_deg" in kinds:
        raise ModelError(f"{key}: stroke_mm and stroke_deg are exclusive (a translating or an oscillating output)",
                         key=f"{key}.stroke_deg")
    stroke = "stroke_deg" if "stroke_deg" in kinds else "stroke_mm" if "stroke_mm" in kinds else None
    for name, kind in kinds.items():
        if name.startswith("stroke"):
            continue
        need = "stroke_mm" if kind == "linear" else "stroke_deg"
        if stroke is None:
            raise ModelError(f"{key}: an acceleration or velocity limit needs the stroke ({need})", key=f"{key}.{need}")
        if stroke != need:
            other = {"linear": "max_accel_rad_s2, max_velocity_rad_s", "angular": "max_accel_m_s2, max_velocity_m_s"}
            raise ModelError(f"{key}.{name}: {'an' if kind == 'angular' else 'a'} {kind} limit with {stroke}; "
                             f"allowed with {stroke}: {other[kind]}", key=f"{key}.{name}")


def _direction(key: str, given: dict) -> str:
    direction = str(given.get("direction", "out"))
    if direction not in DIRECTIONS:
        raise ModelError(f"{key}.direction={direction!r}: allowed {', '.join(DIRECTIONS)}", key=f"{key}.direction")
    return direction


# a clearance: `operation` has reached `at` (a fraction of its stroke) before (or after) `other`
# reaches `other_at`, `other` of `cycles` cycles later (0: the same cycle)
CLEARANCE_COLUMNS = {"operation": str, "at": float, "relation": str, "other": str, "other_at": float,
                     "cycles": float, "mark": str, "why": str, "where": str, "what": str}
RELATIONS = ("before", "after")
LEAST_ANGLE = "least_angle"
# the least of t_k / sqrt(Ca_k h_k): maximising it minimises the largest peak acceleration of the set
LEAST_SCALED_ANGLE = "least_scaled_angle"
OBJECTIVES = (LEAST_ANGLE, LEAST_SCALED_ANGLE)


def objective_weights(maximize, arcs, motions, refs) -> tuple[float, ...]:
    """w_k of each operation of the objective's set (arc indices `arcs`, named `refs`), the LP's rows
    t_k >= z w_k: 1 for "least_angle"; for "least_scaled_angle" w_k = sqrt(Ca_k h_k) [h in m, or
    rad for an oscillating output], so that with T_k = t_k / (6 n) the peak acceleration
    a_k = Ca_k h_k (6 n)^2 / t_k^2 [m/s^2 or rad/s^2; t deg, n rpm] is at most (6 n)^2 / z^2, equal
    to it on every row that binds: the least scaled angle z maximised is the largest peak
    acceleration minimised, one LP for motions of different laws and strokes."""
    if maximize != LEAST_SCALED_ANGLE:
        return tuple(1.0 for _ in arcs)
    kinds = set()
    for j, (k, ref) in enumerate(zip(arcs, refs)):
        if k not in motions or motions[k].stroke is None:
            raise ModelError(f"least_angle_of[{j}]={ref!r}: maximize = {LEAST_SCALED_ANGLE!r} needs its motion law "
                             f"and stroke (columns law, stroke_mm or stroke_deg)", key=f"least_angle_of[{j}]")
        kinds.add(motions[k].units[1])
    if len(kinds) > 1:
        raise ModelError(f"least_angle_of: maximize = {LEAST_SCALED_ANGLE!r} over translating (stroke_mm) and "
                         f"oscillating (stroke_deg) motions compares m/s^2 with rad/s^2: name motions of one kind",
                         key="least_angle_of")
    return tuple(math.sqrt(motions[k].peaks["Ca"] * motions[k].stroke_si) for k in arcs)


@dataclass(frozen=True)
class Clearance:
    """p_a(x_a) <= p_b(x_b) + cycles T ("before"; "after": >=), p_k(x) = p(from_k) + x t_k: the
    instants operation a (arc index) and b reach their displacement fractions (x: the angle fractions)."""
    a: Annotated[int, Ge(0)]
    x_a: Annotated[float, Ge(0), Le(1)]
    b: Annotated[int, Ge(0)]
    x_b: Annotated[float, Ge(0), Le(1)]
    sign: Annotated[float, Ge(-1), Le(1)]          # +1 before, -1 after
    cycles: Annotated[int, Ge(0)]
    label: str


def operation_index(arcs, names, ref, key) -> int:
    """The arc index of an operation named in a table: by its `name` or as "from->to"."""
    ref = str(ref).strip()
    found = [k for k, name in enumerate(names) if name == ref] or \
        [k for k, (x, y) in enumerate(arcs) if f"{x}->{y}" == ref]
    if len(found) != 1:
        why = "names two operations" if found else "no such operation"
        shown = ", ".join(n or f"{x}->{y}" for n, (x, y) in list(zip(names, arcs))[:12])
        raise ModelError(f"{key}={ref!r}: {why}; give an operation's name or from->to: {shown}", key=key)
    return found[0]


def clearance_rows(table, arcs, names, motions, max_cycles) -> tuple[Clearance, ...]:
    """The clearances table checked and resolved: each row's operations, fractions in [0, 1]
    (inside it only on an operation with a law: the fraction of its angle comes from the law),
    relation and cycles."""
    if not isinstance(table, list):
        raise ModelError(f"clearances: expected a list of tables, got {table!r}", key="clearances")
    out = []
    for j, row in enumerate(table):
        key = f"clearances[{j}]"
        if not isinstance(row, dict):
            raise ModelError(f"{key}: expected a table, got {row!r}", key=key)
        unknown = sorted(set(row) - set(CLEARANCE_COLUMNS))
        missing = [k for k in ("operation", "at", "relation", "other", "other_at") if k not in row]
        if unknown or missing:
            raise ModelError(f"{key}: " + (f"unknown {', '.join(unknown)}; allowed: {', '.join(CLEARANCE_COLUMNS)}"
                                           if unknown else f"missing {', '.join(missing)}"), key=key)
        ends = []
        for op_key, at_key in (("operation", "at"), ("other", "other_at")):
            k = operation_index(arcs, names, row[op_key], f"{key}.{op_key}")
            c = row[at_key]
            if isinstance(c, bool) or not isinstance(c, (int, float)) or not 0.0 <= c <= 1.0:
                raise ModelError(f"{key}.{at_key}={c!r}: a fraction of the stroke, allowed [0, 1]", key=f"{key}.{at_key}")
            if 0.0 < c < 1.0 and k not in motions:
                raise ModelError(f"{key}.{at_key}={c:g}: inside the stroke needs the motion law of operation "
                                 f"{row[op_key]!r} (its column law)", key=f"{key}.{at_key}")
            ends.append((k, motions[k].angle_fraction(c) if k in motions else float(c)))
        if row["relation"] not in RELATIONS:
            raise ModelError(f"{key}.relation={row['relation']!r}: allowed {', '.join(RELATIONS)}", key=f"{key}.relation")
        cycles = row.get("cycles", 0)
        if cycles in (None, ""):
            cycles = 0
        if isinstance(cycles, bool) or not isinstance(cycles, (int, float)) or not float(cycles).is_integer() \
                or not 0 <= cycles <= max_cycles:
            raise ModelError(f"{key}.cycles={cycles!r}: a whole number in [0, {max_cycles}]", key=f"{key}.cycles")
        later = f" of {int(cycles)} cycle{'s' if cycles != 1 else ''} later" if cycles else ""
        label = (f"clearance {row['operation']!r} at {row['at']:g} {row['relation']} {row['other']!r} at "
                 f"{row['other_at']:g}{later}")
        out.append(Clearance(ends[0][0], ends[0][1], ends[1][0], ends[1][1],
                             1.0 if row["relation"] == "before" else -1.0, int(cycles), label))
    return tuple(out)
