"""The crank press's equations (2) written once (paper 001): per structure (effects, kinematics, a
measured load's table) CasADi Functions of the state, the mode and one input p holding every number a
caller may vary (`PARAMETERS`); `dynamics` binds a task's p. Simulation, periodic orbit, sensitivity
and design call the same Functions with another p."""
from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError
from mechopt.models.press import PressDrive, state_names
from mechopt.models.press_energy import crank_inertia_expression, mean_inertia_ratios
from mechopt.models.press_laws import (
    FORCE_KEYS,
    cutting_force_N,
    kloss_torque_Nm,
    linkage_forces,
    rod_angle_rad,
    rod_middle_m,
    travel_m,
)
from mechopt.models.press_loads import Load

# --- the equations once: a structure's CasADi Functions with every number in the input p ---------

WORK_NAMES = ("motor_work_J", "cut_work_J", "friction_work_J", "damping_work_J")   # the work integrals' states

GIVEN = ("crank_radius_mm", "rod_ratio", "nominal_speed_rad_s", "flywheel_inertia_kgm2", "crank_mass_kg",
         "tool_mass_kg", "rod_mass_kg", "motor_inertia_kgm2", "gear_ratio", "belt_stiffness_Nm_rad",
         "belt_damping_Nms_rad", "gravity_m_s2", "friction_torque_Nm", *FORCE_KEYS, "blank_thickness_mm",
         "shortfall_mm", "motor_sync_speed_rad_s", "motor_breakdown_torque_Nm", "motor_breakdown_slip",
         "motor_flywheel_inertia_kgm2", "intermediate_inertia_kgm2", "intermediate_ratio", "applied_force_N",
         "applied_torque_Nm", "motor_shaft_torque_Nm")
PARAMETERS = (*GIVEN, "rod_weight_sign", "cut_start_rad", "cut_end_rad", "mean_tool_share", "mean_rod_share")
"""The order of p: the task's numbers (`GIVEN`; None reads 0), the rod-weight reading (+1: the rod's
weight helps on the way down, the model's; -1: the table's sign), and what follows from the geometry
(the cut window's angles, `cut_window_rad`; the mean-inertia shares, `mean_inertia_ratios`)."""


def structure(task: PressDrive) -> tuple:
    """What a build depends on besides numbers: the effects (as a sorted tuple) and the kinematics, and
    a measured load's table (`press_loads.Load.key`: its rows are not numbers in p)."""
    table = task.load.key() if task.load is not None else ()
    return (tuple(sorted(task.effects)), task.kinematics) + ((table,) if table else ())


def parameters(task: PressDrive, *, rod_weight_sign=1.0, **given) -> list:
    """p for `task` in `PARAMETERS` order; `given` replaces any of `GIVEN` (numbers or CasADi symbols:
    a design's variables, a sensitivity's parameters)."""
    unknown = sorted(set(given) - set(GIVEN))
    if unknown:
        raise ModelError(f"parameters {unknown}: allowed {', '.join(GIVEN)}", key=unknown[0])
    own = [given[k] if k in given else (getattr(task, k) or 0.0) for k in GIVEN]
    window = task.cut_window_rad() or (0.0, 0.0)
    return [*own, rod_weight_sign, *window, *mean_inertia_ratios(task)]


@dataclass(frozen=True)
class Equations:
    """Equations (2) of one structure (`structure`), as CasADi Functions of the state x
    (`state_names` followed by the work integrals `WORK_NAMES`), a mode and p (`PARAMETERS`).

    * ``rhs(x, mode, p) -> dx/dt`` with mode = [U, friction sign, stuck]: U the switching function's
      value, the friction sign, and stuck = 1 when the crank is held by static friction.
    * ``switched(x, p) -> dx/dt`` with U and sign(omega) evaluated from the state (the paper's U).
    * ``outputs(x, mode, p) -> [belt torque, motor torque, F, Q, X_mm, penetration_mm, E_kin, E_pot,
      crank torque without friction, crank acceleration, then the loads of `linkage_forces`]``
      (`OUTPUT_NAMES`).
    """
    rhs: ca.Function
    switched: ca.Function
    outputs: ca.Function
    state_names: tuple[str, ...]

    OUTPUT_NAMES: ClassVar[tuple[str, ...]] = ("belt_torque_Nm", "motor_torque_Nm", "force_N", "Q_N", "travel_mm",
                                               "penetration_mm", "kinetic_J", "potential_J", "drive_torque_Nm",
                                               "alpha_rad_s2", "rod_force_N", "rod_force_pin_N", "crank_torque_Nm",
                                               "main_bearing_load_N", "guide_force_N")

    def __post_init__(self):
        object.__setattr__(self, "n_states", len(self.state_names))


class Bound:
    """A Function of (..., p) with p fixed: called with the other inputs; `map(n)` broadcasts p."""

    def __init__(self, function: ca.Function, p):
        self.function, self.p = function, p

    def __call__(self, *args):
        return self.function(*args, self.p)

    def map(self, n: int):
        mapped = self.function.map(n)
        return lambda *args: mapped(*args, self.p)

    def size1_in(self, i: int) -> int:
        return self.function.size1_in(i)


@dataclass(frozen=True)
class Dynamics:
    """A task's equations: its structure's `Equations` with its p (`parameters`) bound, so `rhs(x,
    mode)`, `switched(x)` and `outputs(x, mode)` take the state and mode alone."""
    task: PressDrive
    equations: Equations
    p: np.ndarray

    OUTPUT_NAMES: ClassVar[tuple[str, ...]] = Equations.OUTPUT_NAMES

    def __post_init__(self):
        # `n_states` and the Functions with p bound (`rhs`, `switched`, `outputs`: `Bound`), set once
        for name in ("rhs", "switched", "outputs"):
            object.__setattr__(self, name, Bound(getattr(self.equations, name), self.p))
        object.__setattr__(self, "n_states", self.equations.n_states)


def dynamics(task: PressDrive) -> Dynamics:
    """Eqs. (2) for `task`: its structure's `equations` (built once per structure) with its p bound."""
    return Dynamics(task, equations(structure(task)), np.asarray(parameters(task), dtype=float))


@memoised(maxsize=32)
def equations(key: tuple) -> Equations:
    """Build eqs. (2) for a structure (`structure`: effects, kinematics) from its listed effects only
    (see the module's effect table), every number a symbol of p (`PARAMETERS`)."""
    effects, kin = key[0], key[1]
    table = Load(0.0, 0.0, 0.0, 0.0, key[2][2], key[2][1]) if len(key) > 2 else None
    names = state_names(effects)
    n = len(names)
    x = ca.SX.sym("x", n + len(WORK_NAMES))
    mode = ca.SX.sym("mode", 3)
    p = ca.SX.sym("p", len(PARAMETERS))
    q = dict(zip(PARAMETERS, ca.vertsplit(p)))
    belt, kloss, torque_motor = ("belt_elasticity" in effects, "motor_characteristic" in effects,
                                 "constant_torque_motor" in effects)
    motor = kloss or torque_motor
    cutting, friction_on = "cutting_force" in effects, "friction" in effects
    constant_load = "constant_load" in effects
    gear, stiffness, damping = q["gear_ratio"], q["belt_stiffness_Nm_rad"], q["belt_damping_Nms_rad"]
    # table row 4, with a flywheel on the motor shaft beside the rotor: kinetic energy 1/2 J (i omega)^2
    reduced_motor_inertia = (q["motor_inertia_kgm2"] + q["motor_flywheel_inertia_kgm2"]) * gear**2
    U, sgn, stuck = mode[0], mode[1], mode[2]
    s = dict(zip(names, ca.vertsplit(x[:n])))
    phi, w = s["phi_rad"], s["omega_rad_s"]
    r, lam = q["crank_radius_mm"] / 1000, q["rod_ratio"]
    # the crank's flywheel and an intermediate shaft's, reduced by its speed ratio squared
    flywheel = q["flywheel_inertia_kgm2"] + q["intermediate_inertia_kgm2"] * q["intermediate_ratio"] ** 2
    masses = (flywheel, q["crank_mass_kg"], q["tool_mass_kg"], q["rod_mass_kg"])

    if "variable_inertia" in effects:
        J = crank_inertia_expression(phi, kin, r, lam, *masses)
        dJ = ca.jacobian(J, phi)
    else:               # the mean over a revolution: linear in the masses (`mean_inertia_ratios`)
        J = masses[0] + r**2 * (masses[1] + q["mean_tool_share"] * masses[2] + q["mean_rod_share"] * masses[3])
        dJ = 0.0

    X = travel_m(phi, r, lam, kin, ca)
    dX = ca.jacobian(X, phi)
    ddX = ca.jacobian(dX, phi)
    g = q["gravity_m_s2"]
    xm, ym = rod_middle_m(phi, r, lam, kin, ca)
    potential = (-g * (q["tool_mass_kg"] * X + q["rod_weight_sign"] * q["rod_mass_kg"] * ym)
                 if "gravity" in effects else 0.0 * phi)
    gravity_moment = -ca.jacobian(potential, phi) if "gravity" in effects else 0.0

    penetration_mm = 0.0 * phi
    force = 0.0 * phi
    U_paper = 0.0 * phi
    if cutting:
        Z = q["blank_thickness_mm"]
        penetration_mm = X * 1000 - (2 * q["crank_radius_mm"] - Z - q["shortfall_mm"])
        # the one place eq. (1) is evaluated: beyond the fitted range when the penetration leaves [0, Z]
        force = U * cutting_force_N(penetration_mm, *(q[k] for k in FORCE_KEYS))
        # the paper's U: on while the tool is inside the blank and moving down
        U_paper = ca.logic_and(ca.logic_and(penetration_mm >= 0, penetration_mm <= Z), w * dX > 0)
    load_torque = 0.0 * phi
    if constant_load:           # models.press_loads: constant force and torque inside the window, turning forward
        a, b = q["cut_start_rad"], q["cut_end_rad"]
        turn = phi - 2 * np.pi * ca.floor(phi / (2 * np.pi))
        penetration_mm = X * 1000 - travel_m(a, r, lam, kin, ca) * 1000
        force = U * (table.table_force_N(turn, X * 1000, ca) if table is not None else q["applied_force_N"])
        load_torque = U * q["applied_torque_Nm"]
        U_paper = ca.logic_and(ca.logic_and(turn >= a, turn <= b), w > 0)
    friction = q["friction_torque_Nm"] if friction_on else 0.0

    # motor side
    if motor:
        w_p = s["omega_p_rad_s"] if belt else w
        if kloss:
            slip = 1 - gear * w_p / q["motor_sync_speed_rad_s"]
            motor_torque = gear * kloss_torque_Nm(slip, q["motor_breakdown_torque_Nm"], q["motor_breakdown_slip"])
        else:
            motor_torque = gear * q["motor_shaft_torque_Nm"] + 0.0 * phi
    else:
        w_p, motor_torque = q["nominal_speed_rad_s"], 0.0 * phi
    if belt:
        twist = s["twist_rad"]
        belt_torque = stiffness * twist + damping * (w_p - w)
        damping_power = damping * (w_p - w) ** 2
        drive = belt_torque
        J_total = J
        belt_energy = 0.5 * stiffness * twist**2
    else:
        belt_torque, damping_power, drive = motor_torque, 0.0 * phi, motor_torque
        J_total = J + reduced_motor_inertia
        belt_energy = 0.0

    load = gravity_moment - force * dX - load_torque          # M_pc without friction, table row 2
    drive_torque = drive + load                 # what static friction must hold when stuck
    free_acc = (drive_torque - sgn * friction - 0.5 * dJ * w**2) / J_total
    acc = (1 - stuck) * free_acc
    dphi = (1 - stuck) * w

    derivs = {"phi_rad": dphi, "omega_rad_s": acc}
    if belt:
        derivs["twist_rad"] = w_p - dphi
        if motor:
            derivs["omega_p_rad_s"] = (motor_torque - belt_torque) / reduced_motor_inertia
    motor_power = motor_torque * w_p if motor else belt_torque * w_p
    works = [motor_power, (force * dX + load_torque) * dphi, sgn * friction * dphi, damping_power]
    xdot = ca.vertcat(*[derivs[k] for k in names], *works)

    kinetic = 0.5 * J * w**2 + (0.5 * reduced_motor_inertia * w_p**2 if motor else 0.0)
    Q = force + q["tool_mass_kg"] * (ddX * dphi**2 + dX * acc - g)
    rod_x, rod_y = (q["rod_mass_kg"] * (ca.jacobian(ca.jacobian(c, phi), phi) * dphi**2 + ca.jacobian(c, phi) * acc)
                    for c in (xm, ym))
    loads = linkage_forces(phi, rod_angle_rad(phi, lam, kin, ca), Q, rod_x, rod_y - q["rod_mass_kg"] * g, r, ca)
    outputs = ca.vertcat(belt_torque, motor_torque, force, Q, X * 1000, penetration_mm, kinetic,
                         potential + belt_energy, drive_torque, acc, *loads)

    switched_mode = ca.vertcat(U_paper, ca.sign(w), 0)
    rhs = ca.Function("rhs", [x, mode, p], [xdot])
    switched = ca.Function("switched", [x, p], [rhs(x, switched_mode, p)])
    out = ca.Function("outputs", [x, mode, p], [outputs])
    return Equations(rhs, switched, out, names)
