"""Crank press cutting expanded-graphite gaskets (paper 001: Kobityansky, Beloborodov 2021).

A motor and its pulley (J_p) drive, through an elastic belt (C_p, h_p), the crank shaft with its
flywheel, connecting rod and tool (J_k(phi)); eqs. (2) and the table of coefficients. The tool
cuts the blank with the force of eq. (1), switched on by U while the tool travels through the
blank and dropping to zero at the end of the cut (the "jump").

SI units inside (m, rad, s, kg); the force law (1) is written in mm of penetration, as published.
Every function takes ``m=np`` or ``m=casadi`` so one line serves numbers and symbols.

Readings the paper leaves open (each pinned by a test):

* Tool travel X(phi) is the paper's lambda << 1 form (``kinematics="paper"``) or the exact
  crank-slider (``"exact"``); the dynamics use whichever the task names.
* J_k(phi) is built from the kinetic energy (rod as a point mass at its middle, crank mass at
  the pin, tool on the slider) and differentiated by CasADi: with the paper's X this is row 1 of
  the table exactly, with its d read as the rod middle's vertical velocity ratio
  sin(phi)(1 + lambda/2 cos(phi)) (the printed "sin phi + lambda/2 cos phi" lacks a factor sin phi).
* Weights enter through their potential energy (moment = -dV/dphi): both weights help on the way
  down (the table's signs, +G_i b and -G_sh d, disagree; we take the consistent one). The crank
  is balanced by its counterweight (no crank weight moment).
* Q, the "resulting cutting force" of Figs. 9-10, is the force the rod exerts on the tool along
  the stroke: Q = F U + m_tool (X'' - g) (the tool's own equation of motion). The paper plots Q
  "against tool travel and crank angle during the cut" without an equation; the other readings
  (F alone, the force along the rod) differ: at the jump of press/kd2322's 160 kN data F alone
  exceeds Q by 24.0 %, the force along the rod is Q's within 0.03 % (tests/spine/test_trust_paper_figures.py).
* Loads for sizing parts (`linkage_forces`): rod force at both ends, crank torque, main-bearing
  load, from the rod's Newton-Euler equations along the rod direction the task's X implies.
* Motor: the Kloss static characteristic of an induction motor, M = 2 M_k s s_k / (s^2 + s_k^2),
  s = 1 - omega_motor / omega_sync: it holds from standstill (s = 1, start-up) to idle (s = 0),
  where a linear characteristic overstates the starting torque several times.

The design question is its own task, `PressDesign`: the same press with some of
its drive (`DESIGN_VARIABLES`: flywheel inertia, gear ratio, belt stiffness, a motor scale) left to
an optimiser within bounds, an objective (`OBJECTIVES`) and limits.

The equations are written once (`equations`): built per structure (effects, kinematics) with every
number a caller may vary in one input p (`PARAMETERS`, filled by `parameters`). Simulation,
periodic orbit, sensitivity and design are the same Functions with another p: numbers for a run
(`dynamics` binds a task's), symbols for the design's variables (`design_parameters`) or the
sensitivity's parameters, so the NLP differentiates through the very equations the simulators
integrate and a what-if re-solves without a rebuild.

Single stroke is read as `single_stroke_margin_J` says (motor at rest, the crank shaft alone
carries one cut).

Effects a scene may call for (the model is assembled from these only):

====================  ========================================================  ==============
effect                adds                                                      paper
====================  ========================================================  ==============
belt_elasticity       belt twist and the pulley's speed as states; without it    eq. (2), C_p, h_p
                      motor and crank shaft are one rigid body (two states)
variable_inertia      J_k(phi) and the term 1/2 dJ_k/dphi omega^2; without it    table row 1
                      the constant mean of J_k over a revolution
gravity               weights of the tool and the rod                           table row 2
friction              Coulomb torque -M_tr sign(omega) on the crank shaft        table row 2
cutting_force         F(X) of eq. (1), switched by U with the die's shortfall   eq. (1), U
motor_characteristic  Kloss torque of the motor, reduced by i; without it the   table rows 3-4
                      pulley turns at the nominal speed (an ideal drive)
====================  ========================================================  ==============
"""
from dataclasses import dataclass, field, fields
from typing import Annotated, ClassVar, Literal

import casadi as ca
import numpy as np
from annotated_types import Ge, Gt, Le, Lt
from scipy.optimize import brentq

from mechopt.kit.cache import memoised
from mechopt.kit.errors import ModelError, require
from mechopt.kit.settings import check_fields, field_problem, range_fault
from mechopt.models.effects import Effect, check_effects
from mechopt.models.press_loads import LOAD_KEYS, Load, resolve_load

FORCE_KEYS = ("force_c1_N_mm", "force_c2_N_mm2", "force_c3_N_mm3", "force_c4_N_mm4")
WORK_NAMES = ("motor_work_J", "cut_work_J", "friction_work_J", "damping_work_J")


# --- kinematics -------------------------------------------------------------------------------

def travel_m(phi, r_m, lam, kinematics="paper", m=np):
    """Tool travel X from top dead centre, downwards [m].

    ``"paper"``: X = r [1 - cos phi + lambda/4 (1 - cos 2 phi)] (text after U, lambda << 1);
    ``"exact"``: X = r (1 - cos phi) + l (1 - sqrt(1 - lambda^2 sin^2 phi)), l = r / lambda.
    """
    if kinematics == "paper":
        return r_m * (1 - m.cos(phi) + lam / 4 * (1 - m.cos(2 * phi)))
    return r_m * (1 - m.cos(phi)) + r_m / lam * (1 - m.sqrt(1 - (lam * m.sin(phi)) ** 2))


def rod_middle_m(phi, r_m, lam, kinematics="paper", m=np):
    """(horizontal, vertical-down) position of the rod's middle [m]: half-way from pin to tool."""
    return 0.5 * r_m * m.sin(phi), 0.5 * (r_m * (1 - m.cos(phi)) + travel_m(phi, r_m, lam, kinematics, m))


def coefficient_b(phi, lam, m=np):
    """Table row 5: b = (1 + lambda cos phi) sin phi = dX/dphi / r of the paper's X [-]."""
    return (1 + lam * m.cos(phi)) * m.sin(phi)


def coefficient_d(phi, lam, m=np):
    """Table row 6 as read here: d = sin phi (1 + lambda/2 cos phi), the rod middle's vertical
    velocity ratio (the printed sin phi + lambda/2 cos phi is not dimensionally a velocity ratio
    of anything in the mechanism and gives d(0) != 0 at top dead centre)."""
    return m.sin(phi) * (1 + lam / 2 * m.cos(phi))


def coefficient_k(phi, lam, m=np):
    """Table row 7: k = lambda^2 cos^2 phi, the squared rod angular-velocity ratio [-]."""
    return lam**2 * m.cos(phi) ** 2


def rod_angle_rad(phi, lam, kinematics="paper", m=np):
    """Rod angle beta from the stroke line [rad]: the direction along which both rod ends move alike
    (v_pin - v_tool is normal to the rod, so the rod neither stretches nor shortens). Exact
    crank-slider: sin beta = lambda sin phi; the paper's X implies tan beta = lambda sin phi (its
    X' = r sin(phi + beta) / cos beta); the two differ by O(lambda^3)."""
    if kinematics == "paper":
        return m.arctan(lam * m.sin(phi))
    return m.arcsin(lam * m.sin(phi))


def linkage_forces(phi, beta, Q, rod_x, rod_y, r_m, m=np):
    """Joint forces of the crank-slider from the rod's Newton-Euler equations [N, N m].

    y along the stroke (+X), x across it; crank pin at r (sin phi, -cos phi), so its velocity is
    omega r (cos phi, sin phi). The model's X (paper's or exact, both with + lambda) is the tool
    moving towards the crank axis: the rod runs from the tool to the pin along u = (sin beta, cos
    beta), and pulls the tool through the cut. Q: the force of the rod on the tool along +X;
    (rod_x, rod_y) = m_rod (a_mid - g): what the rod's mass at its middle needs (no moment of
    inertia about it, as in J_k), so both ends carry the same force across the rod, half of it.

    Returns (axial rod force at the tool end, at the crank pin (each + when it drives the tool along
    +X: tension here, compression on a press whose crank sits above the slide), crank torque (what
    the shaft gives the linkage: power at the pin / omega), main-bearing load |pin force|, guide
    force across the stroke). With the crank balanced by its counterweight and the belt pull left
    out (its geometry is not given), the main bearing carries the pin force."""
    c, s = m.cos(beta), m.sin(beta)
    half_across = 0.5 * (rod_x * c - rod_y * s)
    By = -Q                                  # the tool's force on the rod
    Bx = (half_across + By * s) / c
    Ax, Ay = rod_x - Bx, rod_y - By          # the crank pin's force on the rod
    rod_tool = -(Bx * s + By * c)            # (rod on tool) . u
    rod_pin = Ax * s + Ay * c                # (pin on rod) . u
    torque = r_m * (Ax * m.cos(phi) + Ay * m.sin(phi))
    return rod_tool, rod_pin, torque, m.sqrt(Ax**2 + Ay**2), Bx


# The paper's X(phi) drops the O(lambda^3) terms of the crank-slider; past this error of the tool's
# acceleration (relative to its exact peak: about lambda = 0.29) the inertia loads it gives are off.
PAPER_KINEMATICS_TOLERANCE = 0.01


def paper_kinematics_error(rod_ratio: float, samples: int = 2881) -> float:
    """Largest error of the paper's X''(phi) / r = cos phi + lambda cos 2 phi against the exact
    crank-slider's, over a turn, relative to the exact peak [-] (0.00017 at lambda = 0.071)."""
    phi = np.linspace(0.0, 2 * np.pi, samples)
    s, c = np.sin(phi), np.cos(phi)
    root = np.sqrt(1 - rod_ratio**2 * s**2)
    exact = c + rod_ratio * (c**2 - s**2) / root + rod_ratio**3 * s**2 * c**2 / root**3
    paper = c + rod_ratio * np.cos(2 * phi)
    return float(np.max(np.abs(paper - exact)) / np.max(np.abs(exact)))


def cutting_force_N(penetration_mm, c1, c2, c3, c4):
    """Cutting force, eq. (1) [N], for the tool's penetration into the blank [mm]."""
    x = penetration_mm
    return ((c4 * x + c3) * x + c2) * x * x + c1 * x


def kloss_torque_Nm(slip, breakdown_torque_Nm, breakdown_slip):
    """Static characteristic of an induction motor (Kloss): torque at a slip [N m]."""
    return 2 * breakdown_torque_Nm * breakdown_slip * slip / (slip**2 + breakdown_slip**2)


# --- the task ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class PressDrive:
    """A crank press cutting a blank: drive, belt, crank-slider and cutting force (paper 001).

    Geometry: `crank_radius_mm` r (stroke H = 2r), `rod_ratio` lambda = r/l. Masses [kg]: crank
    (reduced to the pin), tool with slider, rod; `flywheel_inertia_kgm2` J (flywheel and
    counterweight). Drive: `motor_inertia_kgm2` J_0 + J_shk on the motor shaft, `gear_ratio`
    i (motor speed / crank speed), `nominal_speed_rad_s` omega of the crank (with the effect
    motor_characteristic only the start speed and guess: the motor's characteristic sets the
    speed). Effects' own parameters: see `EFFECTS`. `effects` lists the effects the scene calls for; `kinematics`
    picks X(phi) (see `travel_m`).
    """
    # Upper ends: each far past any crank press (a 2 m stroke, about 10000 rpm, a 10 t 4 m flywheel, 100 t
    # parts, a 1 MW motor, 1e8 times a V-belt drive's stiffness, 10 g), there to refuse inf and values that
    # overflow the dynamics, not to judge a design. rod_ratio lambda = r/l < 1: else the crank-slider cannot
    # pass its dead centres.
    crank_radius_mm: Annotated[float, Gt(0), Le(1000)]
    rod_ratio: Annotated[float, Gt(0), Lt(1)]
    nominal_speed_rad_s: Annotated[float, Gt(0), Le(1000)]
    flywheel_inertia_kgm2: Annotated[float, Ge(0), Le(1e5)]
    crank_mass_kg: Annotated[float, Ge(0), Le(1e5)]
    tool_mass_kg: Annotated[float, Ge(0), Le(1e5)]
    rod_mass_kg: Annotated[float, Ge(0), Le(1e5)]
    motor_inertia_kgm2: Annotated[float, Ge(0), Le(1e3)] = 0.0
    gear_ratio: Annotated[float, Gt(0), Le(1e3)] = 1.0
    belt_stiffness_Nm_rad: Annotated[float | None, Ge(0), Le(1e12)] = None
    belt_damping_Nms_rad: Annotated[float | None, Ge(0), Le(1e6)] = None
    gravity_m_s2: Annotated[float | None, Ge(0), Le(100)] = None
    friction_torque_Nm: Annotated[float | None, Ge(0), Le(1e6)] = None
    force_c1_N_mm: Annotated[float | None, Ge(-1e9), Le(1e9)] = None
    force_c2_N_mm2: Annotated[float | None, Ge(-1e9), Le(1e9)] = None
    force_c3_N_mm3: Annotated[float | None, Ge(-1e9), Le(1e9)] = None
    force_c4_N_mm4: Annotated[float | None, Ge(-1e9), Le(1e9)] = None
    blank_thickness_mm: Annotated[float | None, Ge(0), Le(1000)] = None
    shortfall_mm: Annotated[float | None, Ge(0), Le(1000)] = None
    motor_sync_speed_rad_s: Annotated[float | None, Gt(0), Le(1e4)] = None
    motor_breakdown_torque_Nm: Annotated[float | None, Gt(0), Le(1e6)] = None
    motor_breakdown_slip: Annotated[float | None, Gt(0), Lt(1)] = None
    effects: tuple[str, ...] = field(default=())
    kinematics: Literal["paper", "exact"] = "paper"
    # the travel eq. (1) was fitted on, up to: past it a warning (`warnings`)
    force_fit_max_mm: Annotated[float | None, Ge(0), Le(1000)] = None
    # effect constant_load (models.press_loads): an interval in travel [mm] or crank angle [deg], and a
    # force, a torque or an energy with its shape
    load_from_mm: Annotated[float | None, Ge(0), Le(2000)] = None
    load_to_mm: Annotated[float | None, Gt(0), Le(2000)] = None
    load_from_deg: Annotated[float | None, Ge(0), Lt(360)] = None
    load_to_deg: Annotated[float | None, Gt(0), Lt(360)] = None
    load_force_N: Annotated[float | None, Ge(0), Le(1e9)] = None
    load_torque_Nm: Annotated[float | None, Ge(0), Le(1e9)] = None
    load_energy_J: Annotated[float | None, Ge(0), Le(1e9)] = None
    load_shape: Literal["constant_force", "constant_torque"] = "constant_force"
    # a measured load: rows [x, F_N], x the crank angle [deg] or the travel [mm] (`load_table_axis`)
    load_table: tuple = ()
    load_table_axis: Literal["crank_deg", "travel_mm"] = "crank_deg"
    # effect constant_torque_motor: its torque at the motor shaft; None: the cycle's mean load reduced by i
    motor_torque_Nm: Annotated[float | None, Ge(0), Le(1e6)] = None
    # flywheels on the other shafts: on the motor's (reduced by i^2, with the rotor) and on an intermediate
    # shaft turning `intermediate_ratio` times the crank's speed, rigidly geared to it (reduced by ratio^2)
    motor_flywheel_inertia_kgm2: Annotated[float, Ge(0), Le(1e5)] = 0.0
    intermediate_inertia_kgm2: Annotated[float, Ge(0), Le(1e5)] = 0.0
    intermediate_ratio: Annotated[float, Gt(0), Le(1e3)] = 1.0
    # crank angles [deg] a run reports its values at (`<name>_<deg>`, e.g. crank_torque_Nm_150): rates, forces, torques
    at_deg: tuple[float, ...] = ()

    EFFECTS: ClassVar[dict[str, Effect]] = {
        "belt_elasticity": Effect(adds="elastic belt between pulley and crank shaft: twist and pulley speed states",
                                  equation="(2)", params=("belt_stiffness_Nm_rad", "belt_damping_Nms_rad")),
        "variable_inertia": Effect(adds="J_k(phi) and 1/2 dJ_k/dphi omega^2 instead of the mean J_k",
                                   equation="(2), table row 1"),
        "gravity": Effect(adds="weights of tool and rod", equation="table row 2", params=("gravity_m_s2",)),
        "friction": Effect(adds="Coulomb torque on the crank shaft", equation="table row 2",
                           params=("friction_torque_Nm",)),
        "cutting_force": Effect(adds="cutting force (1) switched by U with shortfall delta", equation="(1), U",
                                params=FORCE_KEYS + ("blank_thickness_mm", "shortfall_mm")),
        "motor_characteristic": Effect(adds="Kloss static characteristic of the motor",
                                       equation="table rows 3-4",
                                       params=("motor_sync_speed_rad_s", "motor_breakdown_torque_Nm",
                                               "motor_breakdown_slip")),
        "constant_load": Effect(adds="a constant force or torque over a stated interval, or an energy per stroke "
                                     "with a stated shape (models.press_loads)", equation="textbook punching press"),
        "constant_torque_motor": Effect(adds="a motor giving a constant torque at its shaft (the textbook's motor "
                                             "that supplies energy at a uniform rate)", equation="textbook flywheel",
                                        params=()),
    }

    def __post_init__(self):
        object.__setattr__(self, "effects", tuple(self.effects))
        object.__setattr__(self, "at_deg", tuple(float(a) for a in self.at_deg))
        object.__setattr__(self, "load_table", tuple(tuple(r) if isinstance(r, list | tuple) else r
                                                     for r in self.load_table))
        check_fields(self)
        # which effects are on (`belt`, `motor`, `cutting`, `friction`) and the physical states in order
        # (`state_names`: only those the effects call for), set once: the solvers' loops read them
        # as attributes, not as calls into this module
        on = {"belt": "belt_elasticity", "motor": "motor_characteristic", "cutting": "cutting_force",
              "friction": "friction"}
        for name, effect in on.items():
            object.__setattr__(self, name, effect in self.effects)
        # a window-switched load of either kind (eq. (1) or `constant_load`); a motor of either kind
        object.__setattr__(self, "cutting", self.cutting or "constant_load" in self.effects)
        object.__setattr__(self, "torque_motor", "constant_torque_motor" in self.effects)
        object.__setattr__(self, "state_names", state_names(self.effects))
        check_effects(self)
        # relational rules only: each input's own range is on its field (check_fields, above)
        self._check_drive_and_load()
        require(self.crank_flywheel_kgm2() > 0 or self.crank_mass_kg > 0,
                f"flywheel_inertia_kgm2={self.flywheel_inertia_kgm2}, intermediate_inertia_kgm2 and crank_mass_kg are "
                "all 0: the crank shaft would have no inertia", key="flywheel_inertia_kgm2")
        if self.belt:
            require(self.belt_stiffness_Nm_rad > 0, f"belt_stiffness_Nm_rad={self.belt_stiffness_Nm_rad}: allowed > 0 "
                    "with effect 'belt_elasticity' (an elastic belt)", key="belt_stiffness_Nm_rad")
            if self.motor or self.torque_motor:
                require(self.motor_inertia_kgm2 + self.motor_flywheel_inertia_kgm2 > 0,
                        f"motor_inertia_kgm2={self.motor_inertia_kgm2}: allowed > 0 with "
                        "an elastic belt (the pulley side needs inertia)", key="motor_inertia_kgm2")
        if "cutting_force" in self.effects:
            need = self.blank_thickness_mm + self.shortfall_mm
            require(need <= 2 * self.crank_radius_mm,
                    f"blank_thickness_mm={self.blank_thickness_mm} plus shortfall_mm={self.shortfall_mm} is {need} mm, "
                    f"more than the stroke H = 2 crank_radius_mm = {2 * self.crank_radius_mm} mm: the tool never "
                    "reaches the blank", key="blank_thickness_mm")

    @property
    def r_m(self) -> float:
        return self.crank_radius_mm / 1000

    @property
    def stroke_mm(self) -> float:
        """H = 2 r [mm]."""
        return 2 * self.crank_radius_mm

    def travel(self, phi, m=np):
        """Tool travel X [m] (see `travel_m`)."""
        return travel_m(phi, self.r_m, self.rod_ratio, self.kinematics, m)

    def _check_drive_and_load(self):
        """The rules between the new drives and loads and the paper's: one load law, one motor."""
        both = [e for e in ("cutting_force", "constant_load") if e in self.effects]
        require(len(both) < 2, "effects list both 'cutting_force' and 'constant_load': one working load per stroke",
                key="effects")
        motors = [e for e in ("motor_characteristic", "constant_torque_motor") if e in self.effects]
        require(len(motors) < 2, "effects list both 'motor_characteristic' and 'constant_torque_motor': one motor",
                key="effects")
        if not self.torque_motor and self.motor_torque_Nm is not None:
            raise ModelError(f"motor_torque_Nm={self.motor_torque_Nm} belongs to effect 'constant_torque_motor', "
                             "which is not listed in effects", key="motor_torque_Nm")
        if "constant_load" in self.effects:
            object.__setattr__(self, "load", resolve_load(self, lambda x: _angle_at_travel(self, x)))
        else:
            stray = [k for k in LOAD_KEYS if getattr(self, k) is not None] + (["load_table"] if self.load_table else [])
            require(not stray, f"{stray[0] if stray else ''}: belongs to effect 'constant_load', which is not listed "
                    "in effects", key=stray[0] if stray else "effects")
            object.__setattr__(self, "load", None)
        bad = [a for a in self.at_deg if not 0 <= a <= 360]
        require(not bad, f"at_deg={list(self.at_deg)}: allowed crank angles in [0, 360] deg", key="at_deg")

    @property
    def motor_shaft_torque_Nm(self) -> float:
        """The constant-torque motor's torque at its shaft (`motor_torque_at_shaft_Nm`) [N m]."""
        return self.motor_torque_at_shaft_Nm()

    @property
    def applied_force_N(self) -> float:
        """The constant load's force along the stroke inside its window [N] (0 without one)."""
        return self.load.force_N if self.load is not None else 0.0

    @property
    def applied_torque_Nm(self) -> float:
        """The constant load's torque at the crank inside its window [N m] (0 without one)."""
        return self.load.torque_Nm if self.load is not None else 0.0

    def has_drive(self) -> bool:
        """Whether anything drives the crank's motion (a motor or a belt from an ideal drive); without,
        the crank turns at `nominal_speed_rad_s` by a rigid ideal drive: kinematics and kinetostatics only."""
        return self.belt or self.motor or self.torque_motor

    def require_drive(self, what: str = "a dynamic run"):
        """Refuse `what` for a press without a drive (`has_drive`): nothing sets its motion."""
        require(self.has_drive(), f"effects lack 'belt_elasticity', 'motor_characteristic' and "
                f"'constant_torque_motor': a rigid ideal drive leaves no motion to compute for {what}; add one of "
                "them, or use solver press.kinematics (the crank at constant speed: kinematics and kinetostatics)",
                key="effects")

    def motor_torque_at_shaft_Nm(self) -> float:
        """The constant-torque motor's torque at its shaft [N m]: `motor_torque_Nm`, or the cycle's mean
        load at the crank (`required_mean_torque_Nm`) over i; 0 without that motor."""
        if not self.torque_motor:
            return 0.0
        if self.motor_torque_Nm is not None:
            return self.motor_torque_Nm
        return required_mean_torque_Nm(self) / self.gear_ratio

    def crank_flywheel_kgm2(self) -> float:
        """Every flywheel on the crank's side of the belt reduced to the crank [kg m2]: the crank's own J
        plus the intermediate shaft's, times its speed ratio squared (kinetic energy alike)."""
        return self.flywheel_inertia_kgm2 + self.intermediate_inertia_kgm2 * self.intermediate_ratio**2

    def cut_window_rad(self) -> tuple[float, float] | None:
        """Crank angles (in (0, pi)) where U switches on and where the cut ends (the jump) [rad]:
        X = H - Z - delta and X = H - delta on the way down (with `constant_load`, its interval's
        angles). None without a cutting force or load."""
        if not self.cutting:
            return None
        if self.load is not None:
            return self.load.start_rad, self.load.end_rad
        H = self.stroke_mm / 1000
        top, bottom = H - (self.blank_thickness_mm + self.shortfall_mm) / 1000, H - self.shortfall_mm / 1000
        return tuple(_angle_at_travel(self, x) for x in (top, bottom))

    def reduced_motor_inertia_kgm2(self) -> float:
        """J_p = (J_0 + J_shk) i^2, table row 4, with a flywheel on the motor shaft beside the rotor [kg m2]."""
        return (self.motor_inertia_kgm2 + self.motor_flywheel_inertia_kgm2) * self.gear_ratio**2

    def warnings(self, values: dict) -> list[str]:
        """Where this press leaves what its source supports: eq. (1) beyond the travel it was
        fitted on, the paper's lambda << 1 kinematics at a large rod ratio. The answer stands."""
        out = []
        top = self.force_fit_max_mm
        eq1 = "cutting_force" in self.effects
        if eq1 and top is not None and self.blank_thickness_mm > top:
            forces = [cutting_force_N(x, *(getattr(self, k) for k in FORCE_KEYS))
                      for x in (self.blank_thickness_mm, top)]
            out.append(f"eq. (1) extrapolated beyond X = {top:g} mm, its fitted range: at X = blank_thickness_mm = "
                       f"{self.blank_thickness_mm:g} mm it gives {forces[0] / 1000:.3g} kN, "
                       f"{forces[0] / forces[1]:.2g}x its value at {top:g} mm")
        elif eq1 and top is None:          # a law's range belongs to it: unstated, it cannot be checked
            out.append(f"eq. (1)'s fitted range is not stated (force_fit_max_mm): whether X = blank_thickness_mm = "
                       f"{self.blank_thickness_mm:g} mm lies inside it is not checked")
        if self.kinematics == "paper":
            error = paper_kinematics_error(self.rod_ratio)
            if error > PAPER_KINEMATICS_TOLERANCE:
                out.append(f"kinematics = 'paper' (lambda << 1) at rod_ratio = {self.rod_ratio:g}: its tool "
                           f"acceleration is off by {error:.1%} of the exact crank-slider's peak; use "
                           f"kinematics = 'exact'")
        return out


def state_names(effects) -> tuple[str, ...]:
    """The physical states of a press with these effects, in order."""
    if "belt_elasticity" in effects:
        motor = "motor_characteristic" in effects or "constant_torque_motor" in effects
        return ("twist_rad", "omega_p_rad_s", "phi_rad", "omega_rad_s") if motor \
            else ("twist_rad", "phi_rad", "omega_rad_s")
    return ("phi_rad", "omega_rad_s")


def _angle_at_travel(task, x_m):
    """The crank angle in [0, pi] at which the tool has travelled x_m [m] (X is monotone there)."""
    if x_m <= 0:
        return 0.0
    if x_m >= task.stroke_mm / 1000:
        return float(np.pi)
    return float(brentq(lambda p: task.travel(p) - x_m, 0.0, np.pi, xtol=1e-15, rtol=1e-15))


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
    J = _crank_inertia(phi, task.kinematics, task.r_m, task.rod_ratio, task.crank_flywheel_kgm2(),
                       task.crank_mass_kg, task.tool_mass_kg, task.rod_mass_kg)
    return ca.Function("J_k", [phi], [J]), ca.Function("dJ_k", [phi], [ca.jacobian(J, phi)])


def _crank_inertia(phi, kinematics, r, lam, flywheel, crank_mass, tool_mass, rod_mass):
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
    shares = [_crank_inertia(phi, kinematics, 1.0, lam, 0.0, 0.0, *masses)
              for masses in ((1.0, 0.0), (0.0, 1.0))]
    grid = np.linspace(0, 2 * np.pi, 720, endpoint=False).reshape(1, -1)     # exact for the paper's J_k
    return tuple(float(np.mean(np.asarray(ca.Function("share", [phi], [s])(grid)))) for s in shares)


def mean_crank_inertia_kgm2(task: PressDrive) -> float:
    """The mean of J_k over a revolution [kg m2] (J_k without the effect variable_inertia)."""
    tool, rod = mean_inertia_ratios(task)
    return task.crank_flywheel_kgm2() + task.r_m**2 * (task.crank_mass_kg + tool * task.tool_mass_kg
                                                       + rod * task.rod_mass_kg)


# --- the equations once: a structure's CasADi Functions with every number in the input p ---------

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


# --- sizing: what a design may change --------------------------------------------------------------

DESIGN_VARIABLES = {
    "flywheel_inertia_kgm2": "flywheel inertia J [kg m2]",
    "gear_ratio": "belt drive ratio i = motor speed / crank speed [-]",
    "belt_stiffness_Nm_rad": "belt stiffness C_p reduced to the crank shaft [N m/rad]",
    "motor_scale": "motor size: breakdown torque M_k and rotor inertia J_0 + J_shk both times this factor [-]",
}


def sizing(task: PressDrive, design: dict) -> dict:
    """The drive's sizing parameters with `design` (`DESIGN_VARIABLES` -> numbers or CasADi symbols)
    applied: flywheel inertia, gear ratio, belt stiffness, motor breakdown torque and inertia.
    `motor_scale` multiplies the motor's breakdown torque and its inertia alike (one reading of
    "a bigger motor": catalogue rotor inertia grows about as fast as the torque within a frame series)."""
    scale = design.get("motor_scale", 1.0)
    return {"flywheel_inertia_kgm2": design.get("flywheel_inertia_kgm2", task.flywheel_inertia_kgm2),
            "gear_ratio": design.get("gear_ratio", task.gear_ratio),
            "belt_stiffness_Nm_rad": design.get("belt_stiffness_Nm_rad", task.belt_stiffness_Nm_rad),
            "motor_breakdown_torque_Nm": (None if task.motor_breakdown_torque_Nm is None
                                          else scale * task.motor_breakdown_torque_Nm),
            "motor_inertia_kgm2": scale * task.motor_inertia_kgm2}


def design_parameters(task: PressDrive, design: dict) -> list:
    """p (`parameters`) with `design` (`DESIGN_VARIABLES` -> numbers or symbols) applied by `sizing`."""
    unknown = [k for k in design if k not in DESIGN_VARIABLES]
    if unknown:
        raise ModelError(f"design {unknown}: allowed {', '.join(DESIGN_VARIABLES)}", key=unknown[0])
    return parameters(task, **{k: v for k, v in sizing(task, design).items() if v is not None})


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
        J = _crank_inertia(phi, kin, r, lam, *masses)
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


# --- the design question: which drive, by optimisation ----------------------------------------

OBJECTIVES = {
    "least_flywheel_inertia": "the smallest flywheel inertia J [kg m2]",
    "least_motor_rms_torque": "the smallest RMS torque at the motor shaft over the steady revolution [N m] (what "
                              "heats the motor: its rated torque must cover it)",
    "least_energy_per_stroke": "the least energy the motor draws per stroke, read as air-gap energy "
                               "(motor shaft torque x synchronous speed, integrated: the shaft work plus the rotor's "
                               "slip loss) [J]",
}
BOUNDS = {"flywheel_inertia_kgm2": ("flywheel_inertia_min_kgm2", "flywheel_inertia_max_kgm2"),
          "gear_ratio": ("gear_ratio_min", "gear_ratio_max"),
          "belt_stiffness_Nm_rad": ("belt_stiffness_min_Nm_rad", "belt_stiffness_max_Nm_rad"),
          "motor_scale": ("motor_scale_min", "motor_scale_max")}


@dataclass(frozen=True)
class PressDesign(PressDrive):
    """The drive of a `PressDrive` chosen by optimisation over its periodic steady motion.

    `variables` (any of `DESIGN_VARIABLES`) are free within their bounds (`BOUNDS`: e.g.
    `flywheel_inertia_min_kgm2` ... `flywheel_inertia_max_kgm2`); the press's own values of them
    are the starting design (`start`: the flywheel under a speed-fluctuation limit from the rule of
    thumb instead). `objective` is one of `OBJECTIVES`. Limits, each on when given:
    `max_speed_fluctuation` ((omega_max - omega_min) / omega_mean over the revolution),
    `belt_slip_torque_Nm` (|belt torque| at the crank shaft), `motor_safety_factor` (|motor shaft
    torque| <= M_k / factor), `single_stroke_speed_drop` (see `single_stroke_margin_J`). With the
    gear ratio free, the mean crank speed is held at `nominal_speed_rad_s` (the strokes per minute).
    """
    objective: str = "least_flywheel_inertia"
    variables: tuple[str, ...] = ("flywheel_inertia_kgm2",)
    max_speed_fluctuation: Annotated[float | None, Gt(0), Le(2)] = None
    belt_slip_torque_Nm: Annotated[float | None, Gt(0), Le(1e6)] = None
    motor_safety_factor: Annotated[float | None, Ge(1), Le(100)] = None
    single_stroke_speed_drop: Annotated[float | None, Gt(0), Le(1)] = None
    flywheel_inertia_min_kgm2: Annotated[float, Gt(0), Le(1e5)] = 0.01
    flywheel_inertia_max_kgm2: Annotated[float, Gt(0), Le(1e5)] = 100.0
    gear_ratio_min: Annotated[float, Gt(0), Le(1e3)] = 1.0
    gear_ratio_max: Annotated[float, Gt(0), Le(1e3)] = 50.0
    belt_stiffness_min_Nm_rad: Annotated[float, Gt(0), Le(1e12)] = 1e3
    belt_stiffness_max_Nm_rad: Annotated[float, Gt(0), Le(1e12)] = 1e7
    motor_scale_min: Annotated[float, Gt(0), Le(1e3)] = 0.1
    motor_scale_max: Annotated[float, Gt(0), Le(1e3)] = 10.0

    # (needs, why) of each design input: the effect it acts through
    NEEDS: ClassVar[dict[str, tuple[str, str]]] = {
        "gear_ratio": ("motor_characteristic", "without a motor the pulley turns at the nominal speed whatever i is"),
        "motor_scale": ("motor_characteristic", "there is no motor to size"),
        "belt_stiffness_Nm_rad": ("belt_elasticity", "there is no elastic belt"),
        "belt_slip_torque_Nm": ("belt_elasticity", "there is no elastic belt"),
        "motor_safety_factor": ("motor_characteristic", "there is no motor"),
        "least_motor_rms_torque": ("motor_characteristic", "there is no motor"),
        "least_energy_per_stroke": ("motor_characteristic", "there is no motor"),
        "single_stroke_speed_drop": ("cutting_force", "there is no cut to carry"),
    }

    def __post_init__(self):
        object.__setattr__(self, "variables", tuple(self.variables))
        super().__post_init__()
        if self.objective not in OBJECTIVES:
            raise ModelError(f"objective={self.objective!r}; allowed: {', '.join(OBJECTIVES)}", key="objective")
        unknown = [v for v in self.variables if v not in DESIGN_VARIABLES]
        if unknown or not self.variables or len(set(self.variables)) < len(self.variables):
            raise ModelError(f"variables={list(self.variables)}: expected one or more of "
                             f"{', '.join(DESIGN_VARIABLES)}, each once", key="variables")
        if self.objective == "least_flywheel_inertia" and "flywheel_inertia_kgm2" not in self.variables:
            raise ModelError("objective='least_flywheel_inertia' needs 'flywheel_inertia_kgm2' in variables",
                             key="variables")
        used = [*self.variables, self.objective, *(k for k in ("belt_slip_torque_Nm", "motor_safety_factor",
                                                                 "single_stroke_speed_drop") if getattr(self, k))]
        for key in used:
            need = self.NEEDS.get(key)
            if need and need[0] not in self.effects and not (need[0] == "cutting_force" and self.cutting):
                raise ModelError(f"{key} needs effect '{need[0]}': {need[1]}", key=key)
        for low_key, high_key in BOUNDS.values():
            low, high = getattr(self, low_key), getattr(self, high_key)
            require(low < high, range_fault(high_key, high, f"allowed > {low_key}={low:g}"), key=high_key)

    def bounds(self, name: str) -> tuple[float, float]:
        """(lowest, highest) allowed value of a design variable."""
        return tuple(getattr(self, key) for key in BOUNDS[name])

    def start(self, rule_of_thumb: bool = True) -> dict[str, float]:
        """The starting design, clipped into the bounds: the press's own values (motor_scale 1), but
        with a speed-fluctuation limit and the flywheel free (and `rule_of_thumb`), the flywheel of
        `rule_of_thumb_flywheel_kgm2` for that limit (so that a press far from the scene's flywheel
        starts near its answer)."""
        flywheel = self.flywheel_inertia_kgm2
        free = "flywheel_inertia_kgm2" in self.variables
        if rule_of_thumb and free and self.max_speed_fluctuation is not None:
            flywheel = rule_of_thumb_flywheel_kgm2(self, self.max_speed_fluctuation)
        own = {"flywheel_inertia_kgm2": flywheel, "gear_ratio": self.gear_ratio,
               "belt_stiffness_Nm_rad": self.belt_stiffness_Nm_rad or 0.0, "motor_scale": 1.0}
        return {k: float(np.clip(own[k], *self.bounds(k))) for k in self.variables}

    def drive(self, design: dict) -> PressDrive:
        """The press (a plain `PressDrive`) built with numbers for the design variables."""
        own = {f.name: getattr(self, f.name) for f in fields(PressDrive)}
        return PressDrive(**(own | {k: float(v) for k, v in sizing(self, design).items() if v is not None}))


def single_stroke_margin_J(task: PressDrive, flywheel_inertia_kgm2, omega_start_rad_s, speed_drop, m=np):
    """Single-stroke reading: the motor at rest gives no torque (and the slack belt none),
    so the crank shaft alone, entering the cut at omega_start, must carry the cut's work, the friction
    and the weights to the cut's end and still turn at (1 - speed_drop) omega_start there. Energy
    balance from cut start a to cut end b (exact: no integration):
    1/2 J_k(a) w_a^2 - V(b) + V(a) - W_cut - M_tr (b - a) - 1/2 J_k(b) ((1 - drop) w_a)^2 [J];
    >= 0 when the flywheel is big enough. J_k is linear in the flywheel's J."""
    a, b = task.cut_window_rad()
    J_fun, _ = crank_inertia(task)
    if "variable_inertia" in task.effects:
        J_a, J_b = (float(J_fun(angle)) for angle in (a, b))
    else:
        J_a = J_b = mean_crank_inertia_kgm2(task)
    extra = flywheel_inertia_kgm2 - task.flywheel_inertia_kgm2
    friction = task.friction_torque_Nm if task.friction else 0.0
    lost = cut_work_J(task) + friction * (b - a) + float(potential_J(task, b) - potential_J(task, a))
    return 0.5 * (J_a + extra) * omega_start_rad_s**2 - lost - 0.5 * (J_b + extra) * ((1 - speed_drop) * omega_start_rad_s)**2


CATALOGUE_COLUMNS = ("name", "rated_power_kW", "breakdown_torque_Nm", "inertia_kgm2")


@dataclass(frozen=True)
class PressCatalogue(PressDesign):
    """A `PressDesign` whose motor and belt ratio are chosen from a catalogue: `motors`, rows of
    (`CATALOGUE_COLUMNS`: name, rated power [kW], breakdown torque M_k [N m], rotor and pulley inertia
    J_0 + J_shk [kg m2]), and `ratios`, the standard belt ratios i on offer. Every (row, ratio) is a
    drive whose `variables` (the flywheel: the continuous NLP inside) are designed as `PressDesign`
    says; it is feasible when that design is SOLVED and the mean crank speed is within
    `max_speed_deviation` of `nominal_speed_rad_s` (the strokes per minute). The cheapest row is the
    one of least rated power (then least breakdown torque) with a feasible ratio."""
    motors: tuple = ()
    ratios: tuple = ()
    max_speed_deviation: Annotated[float, Gt(0), Le(0.5)] = 0.05

    def __post_init__(self):
        object.__setattr__(self, "motors", tuple(tuple(row) for row in self.motors))
        object.__setattr__(self, "ratios", tuple(float(r) for r in self.ratios))
        super().__post_init__()
        if not self.motor:
            raise ModelError("a motor catalogue needs effect 'motor_characteristic'", key="effects")
        chosen = [v for v in self.variables if v in ("gear_ratio", "motor_scale")]
        if chosen:
            raise ModelError(f"variables={list(self.variables)}: {chosen} come from the catalogue here; "
                             "leave them out", key="variables")
        if not self.motors or not self.ratios:
            raise ModelError("motors and ratios must each list one or more rows", key="motors" if not self.motors
                             else "ratios")
        for k, row in enumerate(self.motors):
            ok = (len(row) == 4 and isinstance(row[0], str)
                  and all(isinstance(v, int | float) and 0 < v < 1e6 for v in row[1:]))
            if not ok:
                raise ModelError(f"motors[{k}]={list(row)}: expected [name, rated power kW, breakdown torque N m, "
                                 f"inertia kg m2], the numbers in (0, 1e6)", key="motors")
        for k, ratio in enumerate(self.ratios):
            problem = field_problem(PressDrive.__dataclass_fields__["gear_ratio"].type, ratio)    # gear_ratio's own range
            require(not problem, range_fault(f"ratios[{k}]", ratio, problem), key="ratios")

    def candidate(self, row: tuple, ratio: float) -> PressDesign:
        """The design question for one catalogue row and ratio (a plain `PressDesign`)."""
        own = {f.name: getattr(self, f.name) for f in fields(PressDesign)}
        return PressDesign(**(own | {"motor_breakdown_torque_Nm": float(row[2]), "motor_inertia_kgm2": float(row[3]),
                                     "gear_ratio": float(ratio)}))
