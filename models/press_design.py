"""The crank press's design question (paper 001): which drive (flywheel, gear ratio, belt, motor
size: `DESIGN_VARIABLES`) by optimisation over the periodic steady motion (`PressDesign`), from a
motor catalogue (`PressCatalogue`), or for one stroke (`single_stroke_margin_J`)."""
from dataclasses import dataclass, fields
from typing import Annotated, ClassVar

import numpy as np
from annotated_types import Ge, Gt, Le

from mechopt.kit.errors import ModelError, require
from mechopt.kit.settings import field_problem, range_fault
from mechopt.models.press import PressDrive
from mechopt.models.press_energy import (
    crank_inertia,
    cut_work_J,
    mean_crank_inertia_kgm2,
    potential_J,
    rule_of_thumb_flywheel_kgm2,
)
from mechopt.models.press_equations import parameters

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
