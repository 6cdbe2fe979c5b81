"""A motion per operation of a cyclogram, and clearances between two motions.

An operation may carry a cam law (`mechopt.laws`: a unit rise S(xi), xi = its fraction of the
operation's angle) and a stroke h [mm]; its phase angle t is then the motion's duration. At a
main-shaft speed n [rpm] (omega = 2 pi n / 60 rad/s, the angle t deg lasting t / (6 n) s) its
peak velocity and acceleration are (Norton, Cam Design and Manufacturing Handbook, 2nd ed., ch. 3;
Rothbart (ed.), Cam Design Handbook, 2004, ch. 2)

    v = Cv h / T,    a = Ca h / T^2,      T = t / (6 n) s,

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

from scipy.optimize import brentq

from mechopt.kit.errors import MechoptError, ModelError
from mechopt.laws import law as cam_law

MAX_STROKE_MM = 1e5
MAX_ACCEL_M_S2 = 1e6
MAX_VELOCITY_M_S = 1e4
MOTION_KEYS = ("law", "stroke_mm", "max_accel_m_s2", "max_velocity_m_s")
FRACTION_XTOL = 1e-14          # brentq's tolerance on x_c (a fraction of the angle)


@dataclass(frozen=True)
class Motion:
    """An operation's motion: its law's name, stroke [mm] and limits (None: not given)."""
    law: str
    stroke_mm: float | None = None
    max_accel_m_s2: float | None = None
    max_velocity_m_s: float | None = None

    @property
    def peaks(self) -> dict:
        return cam_law(self.law).peaks

    def least_ms(self) -> tuple[float, str]:
        """The least duration the limits allow [ms] and which limit sets it ("max_accel",
        "max_velocity"; 0 and "" with none)."""
        h_m, out = (self.stroke_mm or 0.0) / 1000.0, (0.0, "")
        if self.max_accel_m_s2 is not None:
            out = max(out, (1000.0 * math.sqrt(self.peaks["Ca"] * h_m / self.max_accel_m_s2), "max_accel"))
        if self.max_velocity_m_s is not None:
            out = max(out, (1000.0 * self.peaks["Cv"] * h_m / self.max_velocity_m_s, "max_velocity"))
        return out

    def peak_velocity_m_s(self, t_deg: float, speed_rpm: float) -> float:
        """Cv h / T, T = t / (6 n) s [m/s]."""
        return self.peaks["Cv"] * (self.stroke_mm or 0.0) / 1000.0 * 6.0 * speed_rpm / t_deg

    def peak_accel_m_s2(self, t_deg: float, speed_rpm: float) -> float:
        """Ca h / T^2, T = t / (6 n) s [m/s^2]."""
        return self.peaks["Ca"] * (self.stroke_mm or 0.0) / 1000.0 * (6.0 * speed_rpm / t_deg) ** 2

    def angle_fraction(self, c: float) -> float:
        """x_c: the fraction of the operation's angle at which the fraction c of the stroke is reached."""
        return _angle_fraction(self.law, float(c))


@lru_cache(maxsize=256)
def _angle_fraction(name: str, c: float) -> float:
    if c <= 0.0 or c >= 1.0:
        return min(max(c, 0.0), 1.0)
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
    numbers = {}
    for name, top, unit in (("stroke_mm", MAX_STROKE_MM, "mm"), ("max_accel_m_s2", MAX_ACCEL_M_S2, "m/s^2"),
                            ("max_velocity_m_s", MAX_VELOCITY_M_S, "m/s")):
        if name not in given:
            continue
        value = given[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= top:
            raise ModelError(f"{key}.{name}={value!r}: allowed (0, {top:g}] {unit}", key=f"{key}.{name}")
        numbers[name] = float(value)
    if ("max_accel_m_s2" in numbers or "max_velocity_m_s" in numbers) and "stroke_mm" not in numbers:
        raise ModelError(f"{key}: an acceleration or velocity limit needs the stroke (stroke_mm)",
                         key=f"{key}.stroke_mm")
    return Motion(str(given["law"]), **numbers)
