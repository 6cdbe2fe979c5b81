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
from dataclasses import dataclass, field
from typing import Annotated, ClassVar, Literal

import numpy as np
from annotated_types import Ge, Gt, Le, Lt
from scipy.optimize import brentq

from mechopt.kit.errors import ModelError, require
from mechopt.kit.settings import check_fields
from mechopt.models.effects import Effect, check_effects
from mechopt.models.press_energy import required_mean_torque_Nm
from mechopt.models.press_laws import (
    FORCE_KEYS,
    PAPER_KINEMATICS_TOLERANCE,
    cutting_force_N,
    paper_kinematics_error,
    travel_m,
)
from mechopt.models.press_loads import LOAD_KEYS, resolve_load

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


def __getattr__(name: str):
    """The design's tasks (models/press_design.py) build on `PressDrive`; scenes name them `press.PressDesign`
    and `press.PressCatalogue`, so this module hands them out (imported on first use: no import cycle)."""
    if name in DESIGN_TASKS:
        from mechopt.models import press_design
        return getattr(press_design, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


DESIGN_TASKS = ("PressDesign", "PressCatalogue")
