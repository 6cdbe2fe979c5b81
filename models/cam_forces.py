"""The forces between a cam and its follower: the follower force over the cycle, the jump speed of
a spring-closed follower, the crossovers of a form-closed one, and the Hertz line-contact stress.

Follower force along its motion s (positive: pressing the follower on the cam), the cam turning
at omega [rad/s] (Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., Industrial Press
2009, ch. 10 "Cam dynamics: force analysis"; Rothbart, *Cam Design Handbook*, ch. 11):

    Q(theta) = k s + F0 + F_ext + m omega^2 s'' / 1000      [N]

with k [N/mm], s [mm], F0 the spring's preload at s = 0 [N], F_ext a constant load [N], m [kg]
and s'' [mm/rad^2] (the /1000: mm/s^2 to m/s^2). The contact force along the profile's normal is
N = Q / (n . g) (`CamCurves.lever`; Q / cos(phi) for a translating follower). Damping and the
follower's elasticity are left out (a rigid follower).

Spring closure: the follower leaves the cam where Q < 0; Q first reaches 0 at the jump speed
omega_j^2 = min over s'' < 0 of (k s + F0 + F_ext) / (m (-s'') / 1000), in closed form over theta.
Form closure (a groove): Q < 0 presses the roller on the groove's other wall; each sign change of
Q is a crossover across the backlash (an impact), not a lift-off.

Hertz line contact of two cylinders (Johnson, *Contact Mechanics*, Cambridge 1985, sec. 4.3,
eq. (4.45)): p0 = sqrt(N' E* / (pi R*)), N' = N / w the load per unit width [N/mm],
1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 [1/MPa], 1/R* = 1/R1 + 1/R2 (a concave radius negative).
"""
import math

import numpy as np

G_PER_MM = 1e-3      # mm/s^2 -> m/s^2: m [kg] times s'' omega^2 [mm/s^2] in N


def omega_rad_s(speed_rpm: float) -> float:
    """Cam speed [rad/s] from [rpm]."""
    return speed_rpm * 2 * math.pi / 60


def follower_force_N(task, s, dds, omega: float):
    """Q(theta) [N] (module docstring) at the follower's s [mm], s'' [mm/rad^2], omega [rad/s]."""
    return holding_N(task, s) + task.mass_kg * omega**2 * dds * G_PER_MM


def holding_N(task, s):
    """The part of Q that holds the follower on the cam at rest: k s + F0 + F_ext [N]."""
    return task.spring_rate_N_per_mm * s + task.preload_N + task.external_force_N


def jump_speed(task, theta, s, dds) -> tuple[float, float]:
    """(jump speed [rpm], cam angle [rad] where Q first reaches 0) in closed form over the samples;
    0 where the holding force itself fails, inf where nothing pulls the follower off (no
    deceleration or no mass)."""
    hold = holding_N(task, s)
    if np.any(hold <= 0):
        i = int(np.argmin(hold))
        return 0.0, float(theta[i])
    pull = -task.mass_kg * dds * G_PER_MM
    if not np.any(pull > 0):
        return math.inf, math.nan
    with np.errstate(divide="ignore"):
        omega2 = np.where(pull > 0, hold / np.where(pull > 0, pull, 1.0), np.inf)
    i = int(np.argmin(omega2))
    return math.sqrt(omega2[i]) * 60 / (2 * math.pi), float(theta[i])


def sign_changes(theta, values) -> np.ndarray:
    """Cam angles [rad] where `values` (over one turn, sampled at increasing `theta` in [0, 2 pi))
    change sign, located by linear interpolation, the last sample joined to the first."""
    t = np.r_[theta, theta[0] + 2 * math.pi]
    v = np.r_[values, values[0]]
    i = np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)
    return np.mod(t[i] + (t[i + 1] - t[i]) * v[i] / (v[i] - v[i + 1]), 2 * math.pi)


def effective_modulus_MPa(task) -> float:
    """E* [MPa] of the cam and follower materials."""
    return 1.0 / ((1 - task.cam_nu**2) / task.cam_E_MPa + (1 - task.follower_nu**2) / task.follower_E_MPa)


def contact_radius_mm(task, curves, N) -> np.ndarray:
    """R* [mm] at each contact: the roller (radius r) on the wall it presses (the cam's surface,
    radius rho - r, where N >= 0; a groove's other wall, radius rho + r, where N < 0), or a flat
    face on the profile (radius rho). Infinite where both are flat."""
    rho = curves.pitch_radius_mm
    with np.errstate(divide="ignore"):
        if task.face == "flat":
            bend = 1.0 / rho
        else:
            r = task.roller_radius_mm
            bend = 1.0 / r + np.where(N >= 0, 1.0 / (rho - r), -1.0 / (rho + r))
    return np.where(bend > 0, 1.0 / np.where(bend > 0, bend, 1.0), np.inf)


def hertz_MPa(N, width_mm: float, E_star_MPa: float, radius_mm) -> np.ndarray:
    """p0 = sqrt(|N| / w E* / (pi R*)) [MPa] (Johnson eq. (4.45)); 0 where R* is infinite."""
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.sqrt(np.abs(N) / width_mm * E_star_MPa / (math.pi * radius_mm))
    return np.where(np.isfinite(radius_mm), p, 0.0)
