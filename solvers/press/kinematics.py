"""The press's crank-slider at constant crank speed: positions, velocities and accelerations of the
slider and the rod over a turn, no dynamics solved (a rigid ideal drive holds the crank at
`nominal_speed_rad_s`). The textbook first step of a press's analysis, and the reference the
dynamic runs' speed fluctuation is measured against.

With u = lambda sin phi, w = sqrt(1 - u^2), l = r / lambda, and phi' = omega constant:
  exact   X = r (1 - cos phi) + l (1 - w)              sin beta = u
          X' = r sin phi + r lambda sin phi cos phi / w
          X'' = r cos phi + r lambda cos 2phi / w + r lambda^3 sin^2 phi cos^2 phi / w^3
          beta' = lambda cos phi / w,   beta'' = (-lambda sin phi w^2 + u lambda^2 cos^2 phi) / w^3
  paper   X = r (1 - cos phi + lambda/4 (1 - cos 2phi))  tan beta = u   (models.press_laws.rod_angle_rad)
          X' = r (sin phi + lambda/2 sin 2phi),  X'' = r (cos phi + lambda cos 2phi)
          beta' = lambda cos phi / (1 + u^2),   beta'' = (-lambda sin phi (1 + u^2) - 2 u lambda^2 cos^2 phi) / (1 + u^2)^2
(primes: d/dphi); velocities are omega times the first, accelerations omega^2 times the second.
"""
import numpy as np

from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval
from mechopt.models.press import PressDrive
from mechopt.models.press_laws import FORCE_KEYS, cutting_force_N, linkage_forces, rod_angle_rad, travel_m

# what a value at a crank angle is named after (`at_deg`): each array of the result
AT_NAMES = ("travel_mm", "slider_velocity_m_s", "slider_acceleration_m_s2", "rod_angle_deg",
            "rod_angular_velocity_rad_s", "rod_angular_acceleration_rad_s2", "load_force_N", "load_torque_Nm", "Q_N",
            "rod_force_N", "crank_torque_Nm", "input_torque_Nm", "main_bearing_load_N", "guide_force_N")


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


def working_load(task: PressDrive, phi, X_m):
    """(force along the stroke [N], torque at the crank [N m]) of the task's working load at crank
    angles phi in [0, 2 pi] turning forward: eq. (1) on the penetration inside the cut window, or the
    constant load inside its window (both ends included); zero elsewhere and without a load."""
    zero = np.zeros_like(phi)
    window = task.cut_window_rad()
    if window is None:
        return zero, zero
    inside = (phi >= window[0]) & (phi <= window[1])
    if task.load is not None and task.load.table:
        return np.where(inside, task.load.table_force_N(phi, X_m * 1000), 0.0), zero
    if task.load is not None:
        return np.where(inside, task.load.force_N, 0.0), np.where(inside, task.load.torque_Nm, 0.0)
    depth = X_m * 1000 - (task.stroke_mm - task.blank_thickness_mm - task.shortfall_mm)
    return np.where(inside, cutting_force_N(depth, *(getattr(task, k) for k in FORCE_KEYS)), 0.0), zero


def kinetostatics(task: PressDrive, phi) -> dict:
    """Every rate, force and torque of the crank-slider at crank angles phi [rad] with the crank at the
    constant `nominal_speed_rad_s` (a rigid ideal drive: no dynamics solved). Forces as the dynamic
    model's outputs (`models.press_laws.linkage_forces`, the rod's mass at its middle, the tool's on the
    slide, weights with effect gravity); `crank_torque_Nm` is what the shaft gives the linkage,
    `input_torque_Nm` what the drive gives the crank: that, the constant load's torque and friction
    (the flywheel and the balanced crank need none at constant speed)."""
    omega, r_m, lam = task.nominal_speed_rad_s, task.r_m, task.rod_ratio
    phi = np.asarray(phi, dtype=float)
    X, dX, ddX, beta, db, ddb = slider_crank_rates(phi, r_m, lam, task.kinematics)
    force, torque = working_load(task, np.mod(phi, 2 * np.pi), X)
    g = task.gravity_m_s2 if "gravity" in task.effects else 0.0
    Q = force + task.tool_mass_kg * (ddX * omega**2 - g)
    # the rod's middle: x = r sin(phi) / 2, y = (r (1 - cos phi) + X) / 2 (models.press_laws.rod_middle_m)
    rod_x = task.rod_mass_kg * (-0.5 * r_m * np.sin(phi)) * omega**2
    rod_y = task.rod_mass_kg * (0.5 * (r_m * np.cos(phi) + ddX) * omega**2 - g)
    rod_tool, _, crank, bearing, guide = linkage_forces(phi, beta, Q, rod_x, rod_y, r_m)
    friction = task.friction_torque_Nm if task.friction else 0.0
    return {"crank_angle_deg": np.degrees(phi), "travel_mm": X * 1000, "slider_velocity_m_s": omega * dX,
            "slider_acceleration_m_s2": omega**2 * ddX, "rod_angle_deg": np.degrees(beta),
            "rod_angular_velocity_rad_s": omega * db, "rod_angular_acceleration_rad_s2": omega**2 * ddb,
            "load_force_N": force, "load_torque_Nm": torque, "Q_N": Q, "rod_force_N": rod_tool,
            "crank_torque_Nm": crank, "input_torque_Nm": crank + torque + friction,
            "main_bearing_load_N": bearing, "guide_force_N": guide}


def at_name(name: str, deg: float) -> str:
    """The value of `name` at the crank angle `deg`: `<name>_<deg>`, the angle in deg as the name's case
    number after its unit (`crank_torque_Nm_150`; a fraction's point as p: `..._22p5`)."""
    return f"{name}_{deg:g}".replace(".", "p")


def at_angles(arrays_at, at_deg) -> dict:
    """Values `at_name(name, deg)` of `AT_NAMES` from `arrays_at(phi)` evaluated at the crank angles asked for."""
    if not at_deg:
        return {}
    found = arrays_at(np.radians(np.asarray(at_deg, dtype=float)))
    return {at_name(name, deg): float(found[name][k]) for k, deg in enumerate(at_deg) for name in AT_NAMES
            if name in found}


def kinematics(task: PressDrive, *, samples: Annotated[int, Interval(ge=3, le=1_000_000)] = 3601) -> Result:
    """Slider and rod over one turn at the constant crank speed `nominal_speed_rad_s`, with the
    task's `kinematics` ("exact" or "paper"), and the forces and torques of the working load, the
    weights and the inertia at that speed (`kinetostatics`). Arrays: crank_angle_deg, travel_mm,
    slider_velocity_m_s, slider_acceleration_m_s2, rod_angle_deg, rod_angular_velocity_rad_s,
    rod_angular_acceleration_rad_s2, load_force_N, load_torque_Nm, Q_N, rod_force_N, crank_torque_Nm,
    input_torque_Nm, main_bearing_load_N, guide_force_N. Values: the stroke, the largest slider speed
    and acceleration and the largest rod rates (magnitudes) with the crank angles where they occur (on
    the samples), the largest input torque, the work per turn, and every array's value at each crank
    angle of the task's `at_deg` (`<name>_<deg>`, `at_name`; exact: computed there, not interpolated)."""
    clock = Clock()
    omega = task.nominal_speed_rad_s
    phi = np.linspace(0.0, 2 * np.pi, samples)
    window = task.cut_window_rad()
    if window is not None:          # the load's switching angles are samples, its jumps 1e-9 rad wide
        edges = np.asarray(window)
        phi = np.union1d(phi, np.r_[edges, edges - 1e-9, edges + 1e-9].clip(0.0, 2 * np.pi))
    arrays = kinetostatics(task, phi)
    X = arrays["travel_mm"]
    values = {"stroke_mm": float(X.max() - X.min())}
    for name in ("slider_velocity_m_s", "slider_acceleration_m_s2", "rod_angular_velocity_rad_s",
                 "rod_angular_acceleration_rad_s2", "input_torque_Nm"):
        k = int(np.argmax(np.abs(arrays[name])))
        stem, unit = name.rsplit("_", 2)[0], "_".join(name.rsplit("_", 2)[1:])
        values[f"{stem}_max_{unit}"] = float(abs(arrays[name][k]))
        values[f"{stem}_max_at_deg"] = float(arrays["crank_angle_deg"][k])
    values["input_work_per_turn_J"] = float(np.trapezoid(arrays["input_torque_Nm"], phi))
    values |= at_angles(lambda angles: kinetostatics(task, angles), task.at_deg)
    return clock.result(Status.SOLVED, values, arrays=arrays,
                        message=f"crank at a constant {omega:g} rad/s (a rigid ideal drive): kinematics and "
                                f"kinetostatics only, no dynamics solved ({task.kinematics} crank-slider)")
