"""The press's crank-slider at constant crank speed: positions, velocities and accelerations of the
slider and the rod over a turn, no dynamics solved (a rigid ideal drive holds the crank at
`nominal_speed_rad_s`). The textbook first step of a press's analysis, and the reference the
dynamic runs' speed fluctuation is measured against.

With u = lambda sin phi, w = sqrt(1 - u^2), l = r / lambda, and phi' = omega constant:
  exact   X = r (1 - cos phi) + l (1 - w)              sin beta = u
          X' = r sin phi + r lambda sin phi cos phi / w
          X'' = r cos phi + r lambda cos 2phi / w + r lambda^3 sin^2 phi cos^2 phi / w^3
          beta' = lambda cos phi / w,   beta'' = (-lambda sin phi w^2 + u lambda^2 cos^2 phi) / w^3
  paper   X = r (1 - cos phi + lambda/4 (1 - cos 2phi))  tan beta = u   (models.press.rod_angle_rad)
          X' = r (sin phi + lambda/2 sin 2phi),  X'' = r (cos phi + lambda cos 2phi)
          beta' = lambda cos phi / (1 + u^2),   beta'' = (-lambda sin phi (1 + u^2) - 2 u lambda^2 cos^2 phi) / (1 + u^2)^2
(primes: d/dphi); velocities are omega times the first, accelerations omega^2 times the second.
"""
import numpy as np

from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval
from mechopt.models.press import PressDrive, rod_angle_rad, travel_m


def slider_crank_rates(phi, r_m, lam, kinematics="paper"):
    """(X, X', X'', beta, beta', beta'') of the crank-slider at crank angles phi [m, m/rad, m/rad^2,
    rad, -, 1/rad]: derivatives with respect to the crank angle."""
    s, c = np.sin(phi), np.cos(phi)
    u, du, ddu = lam * s, lam * c, -lam * s
    if kinematics == "paper":
        dX = r_m * (s + lam / 2 * np.sin(2 * phi))
        ddX = r_m * (c + lam * np.cos(2 * phi))
        q = 1 + u * u
        db = du / q
        ddb = (ddu * q - 2 * u * du * du) / q**2
    else:
        w = np.sqrt(1 - u * u)
        dX = r_m * s + r_m * lam * s * c / w
        ddX = r_m * c + r_m * lam * np.cos(2 * phi) / w + r_m * lam**3 * s * s * c * c / w**3
        db = du / w
        ddb = (ddu * w * w + u * du * du) / w**3
    return travel_m(phi, r_m, lam, kinematics), dX, ddX, rod_angle_rad(phi, lam, kinematics), db, ddb


def kinematics(task: PressDrive, *, samples: Annotated[int, Interval(ge=3, le=1_000_000)] = 3601) -> Result:
    """Slider and rod over one turn at the constant crank speed `nominal_speed_rad_s`, with the
    task's `kinematics` ("exact" or "paper"). Arrays: crank_angle_deg, travel_mm,
    slider_velocity_m_s, slider_acceleration_m_s2, rod_angle_deg, rod_angular_velocity_rad_s,
    rod_angular_acceleration_rad_s2. Values: the stroke, the largest slider speed and acceleration
    and the largest rod rates (magnitudes) with the crank angles where they occur (on the samples)."""
    clock = Clock()
    omega, r_m, lam = task.nominal_speed_rad_s, task.r_m, task.rod_ratio
    phi = np.linspace(0.0, 2 * np.pi, samples)
    X, dX, ddX, beta, db, ddb = slider_crank_rates(phi, r_m, lam, task.kinematics)
    arrays = {"crank_angle_deg": np.degrees(phi), "travel_mm": X * 1000, "slider_velocity_m_s": omega * dX,
              "slider_acceleration_m_s2": omega**2 * ddX, "rod_angle_deg": np.degrees(beta),
              "rod_angular_velocity_rad_s": omega * db, "rod_angular_acceleration_rad_s2": omega**2 * ddb}
    values = {"stroke_mm": float(X.max() - X.min()) * 1000}
    for name in ("slider_velocity_m_s", "slider_acceleration_m_s2", "rod_angular_velocity_rad_s",
                 "rod_angular_acceleration_rad_s2"):
        k = int(np.argmax(np.abs(arrays[name])))
        stem, unit = name.rsplit("_", 2)[0], "_".join(name.rsplit("_", 2)[1:])
        values[f"{stem}_max_{unit}"] = float(abs(arrays[name][k]))
        values[f"{stem}_max_at_deg"] = float(arrays["crank_angle_deg"][k])
    return clock.result(Status.SOLVED, values, arrays=arrays,
                        message=f"crank at a constant {omega:g} rad/s (a rigid ideal drive): kinematics only, "
                                f"no dynamics solved ({task.kinematics} crank-slider)")
