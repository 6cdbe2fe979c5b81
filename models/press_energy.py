"""What one revolution of a crank press costs and what its crank carries (paper 001): the cut's
work, the mean torque, the energy swing and the flywheel's rule of thumb, the motor's and belt's
figures at the crank, the stall check, and the reduced inertia J_k(phi) with the weights' potential
(table row 1), as numbers or CasADi Functions."""
from __future__ import annotations  # PressDrive only in annotations: models/press.py imports this module

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from mechopt.kit.cache import memoised
from mechopt.models.press_laws import FORCE_KEYS, rod_middle_m, travel_m

if TYPE_CHECKING:
    from mechopt.models.press import PressDrive

# --- what one revolution costs ------------------------------------------------------------------

def cut_work_J(task: PressDrive) -> float:
    """The work of one cut, the integral of eq. (1) over the penetration [0, Z] [J]; 0 without a cut."""
    if not task.cutting:
        return 0.0
    if task.load is not None:
        return task.load.work_J(task.travel)
    coeffs = [getattr(task, k) for k in FORCE_KEYS]
    antiderivative = [0, 0, *[c / (i + 2) for i, c in enumerate(coeffs)]]      # of eq. (1), N mm
    return float(np.polynomial.polynomial.polyval(task.blank_thickness_mm, antiderivative)) / 1000


def required_mean_torque_Nm(task: PressDrive) -> float:
    """The least mean torque at the crank a forward periodic motion needs [N m]: per revolution
    the cut's work plus 2 pi M_tr of friction (the weights give back what they take, belt
    damping only adds), over 2 pi."""
    friction = task.friction_torque_Nm if task.friction else 0.0
    return cut_work_J(task) / (2 * np.pi) + friction


def energy_swing_J(task: PressDrive, samples: int = 3600) -> float:
    """Delta E, the largest energy the flywheel gives up over one revolution [J], from the load
    diagram: a constant drive torque equal to the mean load (`required_mean_torque_Nm`) against the
    cut (eq. (1) over the cut window, the work done so far being its antiderivative at the
    penetration), the friction and the weights (their potential, `potential_J`). The surplus
    E(phi) = M_mean phi - W_cut(phi) - M_tr phi - (V(phi) - V(0)) swings by max E - min E."""
    phi = np.linspace(0.0, 2 * np.pi, samples + 1)
    work = np.zeros_like(phi)
    if task.load is not None:
        phi = np.union1d(phi, task.cut_window_rad())
        work = task.load.work_so_far_J(phi, task.travel)
    elif task.cutting:
        a, b = task.cut_window_rad()
        phi = np.union1d(phi, [a, b])       # the cut's end is the surplus's kink: a sample there
        Z = task.blank_thickness_mm
        depth = task.travel(phi) * 1000 - (task.stroke_mm - Z - task.shortfall_mm)
        depth = np.where(phi < a, 0.0, np.where(phi > b, Z, np.clip(depth, 0.0, Z)))
        coeffs = [getattr(task, k) for k in FORCE_KEYS]
        work = np.polynomial.polynomial.polyval(depth, [0, 0, *[c / (i + 2) for i, c in enumerate(coeffs)]]) / 1000
    friction = task.friction_torque_Nm if task.friction else 0.0
    weights = potential_J(task, phi) - potential_J(task, 0.0)
    surplus = (required_mean_torque_Nm(task) - friction) * phi - work - weights
    return float(surplus.max() - surplus.min())


def rule_of_thumb_flywheel_kgm2(task: PressDrive, speed_fluctuation: float) -> float:
    """The textbook flywheel I = Delta E / (C_s omega^2) (`energy_swing_J`; C_s the allowed speed
    fluctuation, omega `nominal_speed_rad_s`) less what the crank shaft already carries (the mean
    J_k without the flywheel) [kg m2], at least 0. A start for the design, not an answer: it leaves
    out the motor's slip, the belt and J_k(phi)."""
    needed = energy_swing_J(task) / (speed_fluctuation * task.nominal_speed_rad_s**2)
    return max(needed - (mean_crank_inertia_kgm2(task) - task.flywheel_inertia_kgm2), 0.0)


def inertia_at_crank_kgm2(task: PressDrive) -> float:
    """Everything that turns with the crank, reduced to it [kg m2]: the mean J_k (its flywheel, an
    intermediate shaft's by ratio^2, the linkage) plus, with a rigid drive (no belt), the motor side's
    (rotor and motor-shaft flywheel by i^2). The inertia the textbook's I = Delta E / (C_s omega^2) sizes."""
    motor_side = task.reduced_motor_inertia_kgm2() if (task.motor or task.torque_motor) and not task.belt else 0.0
    return mean_crank_inertia_kgm2(task) + motor_side


def breakdown_torque_at_crank_Nm(task: PressDrive) -> float:
    """The most the motor can ever give, M_k, reduced to the crank: i M_k [N m] (inf for an ideal drive)."""
    return task.gear_ratio * task.motor_breakdown_torque_Nm if task.motor else float("inf")


def stall_check(task: PressDrive) -> tuple[dict, str] | None:
    """(values, message) when the motor cannot deliver a revolution's work even at its breakdown
    torque, so no forward periodic motion exists; None otherwise (or without a motor). Every solver
    asks this before any work (a stall is a finding, INFEASIBLE, not a failed integration)."""
    need, most = required_mean_torque_Nm(task), breakdown_torque_at_crank_Nm(task)
    if need <= most:
        return None
    friction = task.friction_torque_Nm if task.friction else 0.0
    values = {"required_mean_torque_Nm": need, "breakdown_torque_at_crank_Nm": most,
              "cut_work_J": cut_work_J(task), "friction_torque_Nm": friction}
    return values, (f"the motor cannot deliver the cycle's work: mean load torque {need:.4g} N m at the crank "
                    f"(cut work {cut_work_J(task):.4g} J per turn / 2 pi + friction {friction:.4g} N m) against "
                    f"breakdown torque {most:.4g} N m (reduced to the crank: i {task.gear_ratio:.4g} x "
                    f"{task.motor_breakdown_torque_Nm:.4g} N m at the motor)")


def belt_mode_rad_s(task: PressDrive) -> float:
    """Angular frequency of the belt mode [rad/s]: the belt's stiffness between the pulley's
    reduced inertia and the crank shaft's mean one (the pulley held at its speed by an ideal
    drive: the crank shaft alone); 0 without an elastic belt."""
    if not task.belt:
        return 0.0
    inverse = 1 / mean_crank_inertia_kgm2(task)
    if task.motor:
        inverse += 1 / task.reduced_motor_inertia_kgm2()
    return float(np.sqrt(task.belt_stiffness_Nm_rad * inverse))


# --- reduced inertia and moments (CasADi) -------------------------------------------------------

def potential_J(task: PressDrive, phi, m=np):
    """Potential energy of the weights [J], 0 without effect gravity: both weights do work on the way
    down, V = -g (m_tool X + m_rod y_mid)."""
    if "gravity" not in task.effects:
        return 0.0 * phi
    rod_drop = rod_middle_m(phi, task.r_m, task.rod_ratio, task.kinematics, m)[1]
    return -task.gravity_m_s2 * (task.tool_mass_kg * task.travel(phi, m) + task.rod_mass_kg * rod_drop)


def crank_inertia(task: PressDrive):
    """J_k(phi) and dJ_k/dphi as CasADi Functions [kg m2], table row 1, from the kinetic energy:
    J_k = J + r^2 m_k + m_tool X'^2 + m_rod (x_mid'^2 + y_mid'^2); derivative by AD."""
    phi = ca.SX.sym("phi")
    J = crank_inertia_expression(phi, task.kinematics, task.r_m, task.rod_ratio, task.crank_flywheel_kgm2(),
                       task.crank_mass_kg, task.tool_mass_kg, task.rod_mass_kg)
    return ca.Function("J_k", [phi], [J]), ca.Function("dJ_k", [phi], [ca.jacobian(J, phi)])


def crank_inertia_expression(phi, kinematics, r, lam, flywheel, crank_mass, tool_mass, rod_mass):
    """J_k(phi) as a CasADi expression of numbers or symbols (see `crank_inertia`)."""
    X = travel_m(phi, r, lam, kinematics, ca)
    xm, ym = rod_middle_m(phi, r, lam, kinematics, ca)
    return (flywheel + r**2 * crank_mass + tool_mass * ca.jacobian(X, phi) ** 2
            + rod_mass * (ca.jacobian(xm, phi) ** 2 + ca.jacobian(ym, phi) ** 2))


def mean_inertia_ratios(task: PressDrive) -> tuple[float, float]:
    """The means over a revolution of X'^2 / r^2 and of (x_mid'^2 + y_mid'^2) / r^2 [-]: the tool's
    and the rod's shares of the mean J_k per kg, over r^2 (they depend on lambda and the kinematics
    only, so the mean J_k is linear in the masses, the flywheel and r^2)."""
    return _mean_shares(task.kinematics, task.rod_ratio)


@memoised(maxsize=256)
def _mean_shares(kinematics: str, lam: float) -> tuple[float, float]:
    phi = ca.SX.sym("phi")
    shares = [crank_inertia_expression(phi, kinematics, 1.0, lam, 0.0, 0.0, *masses)
              for masses in ((1.0, 0.0), (0.0, 1.0))]
    grid = np.linspace(0, 2 * np.pi, 720, endpoint=False).reshape(1, -1)     # exact for the paper's J_k
    return tuple(float(np.mean(np.asarray(ca.Function("share", [phi], [s])(grid)))) for s in shares)


def mean_crank_inertia_kgm2(task: PressDrive) -> float:
    """The mean of J_k over a revolution [kg m2] (J_k without the effect variable_inertia)."""
    tool, rod = mean_inertia_ratios(task)
    return task.crank_flywheel_kgm2() + task.r_m**2 * (task.crank_mass_kg + tool * task.tool_mass_kg
                                                       + rod * task.rod_mass_kg)
