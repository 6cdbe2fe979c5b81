"""Lever striking a stop: stiffness, impact and the inputs of the rebound equation (paper 004:
Podgorny, Maximchuk, Kirillov, Skeeba 2018, Sec. "Results and discussion", Figs. 5-8).

The microshuttle lift's lever (pivot A, cam roller, end C carrying the lift) is pressed against
a limit plate at the end of its travel. It strikes the plate, rebounds and rings; the first
rebound must stay within the weft-transfer accuracy, which gives the LP its amplitude limit.

Readings taken where the paper is silent or inconsistent (each pinned by a test):

* Stiffness, Fig. 5/6: c = 3 E J_x / ((a + b) b^2), the end deflection of a beam on two supports
  a apart with an overhang b. Fig. 5 (moving, no contact): arms `a_mm`, `b_mm`, and the lever
  length l = a + b (pivot A to end C). Fig. 6 (on the plate, extra support): the same formula
  with the arms `a_stop_mm`, `b_stop_mm` (the figure's dimensions are not printed).
* Contact time: tau = half the natural period of the lever *on the plate* (Fig. 6). During the
  contact the plate's support is engaged, and Panovko's rule [25] for an impact on an elastic
  support is half the natural period of the mass on that support.
* Eq. (2) is the single-mass response *on the plate*: omega_c = omega_stop (the paper studies
  "vibrations at the natural frequency after the contact with the stop", Fig. 8); q is the
  displacement of C from the plate, positive away from it; q0 = 0, q0' = omega_0 l as the paper
  computes (both the arrested approach and the plate's push throw C back).
* The Duhamel term runs over the whole pulse Q_F (rise to F at tau, fall to zero at 2 tau): its
  impulse is then F tau = S_C, as the paper's S_C = F tau says. The printed upper limit tau of
  the integral (half the pulse, half the impulse) is read as a misprint. In the scenes' chain the
  first rebound peaks at 0.29 ... 0.44 tau, before the pulse's top: both readings give it alike.
* Approach velocity, two sources. With the effect `cam_drive` (the scenes' chain) the cam's rise
  through the elastic lever gives v0 at the located contact with the plate (models/cam_follower.py,
  solvers/stop_impact/cam_follower.py). Without it, the earlier fitted proportionality
  v0 = velocity_factor * stroke * Omega / t (Omega = 2 pi n / 60, t the phase angle of the lift's
  travel), kept for comparison: for one motion law on a rigid lever v0 scales as n / t.
* J_A of S_C: m l^2 unless `inertia_A_kgm2` is given, the reduced mass at C seen from the pivot
  A, so that mass, inertia and frequency belong to one lever; the pulse's impulse is then
  (1 + k) m v0, the plate reversing the lever's momentum (what a separately fitted J_A does to the
  impulse: cases/stop-impact/impact-force.toml).
* Launch after the impact (structure `launch`), two readings of how C leaves the plate:
  "pulse_plus_v0" (the paper's eq. (2) as computed, q0' = omega_0 l away from the plate *and*
  the reversing pulse Q_F: C leaves at about (2 + k) v0) and "restitution" (Newton: the pulse
  is the restitution itself, C leaves at k v0; eq. (2) then runs with q0' = k v0 and no pulse).
  Under a v0 proportional to n / t both give a rebound proportional to n / t (one constant
  apart); they differ where the preload does not scale (177 rpm) and in the chain.
* Closure of the roller on its cam (structure `closure`, effect `cam_drive`), two readings:
  "force" (the roller held on one flank by `closure_force_N`; a contact force N = F + m x'' < 0
  is lift-off, past which the one-flank model does not hold: INFEASIBLE) and "groove" (form
  closure, the paper's Fig. 3 "кулачок пазовый": a grooved cam; `closure_force_N` then presses
  the roller on its driving wall, 0 for a bare groove, and N < 0 is a crossover to the other
  wall across `backlash_mm`, an impact located and reported, not a lift-off: the crossover comes
  before the stop impact eq. (2) starts from, and where it comes before C meets its plate its
  flight across the backlash moves the approach, so the chain takes the approach of the hybrid
  model with the backlash there: solvers/stop_impact/crossover.py, groove.py, law.py). "force"
  is the default (the scenes' earlier figures).
* Preload (effect `preload`): the cam drives the lever `preload_mm` past the plate; the moving
  lever (Fig. 5) holds that as a constant force P = c_free * preload pressing C onto the plate,
  a constant -P added to Q_F in eq. (2).

Effects a scene may call for (an effect not listed is not computed):

================  ============================================================  ===============
effect            adds                                                          paper
================  ============================================================  ===============
initial_velocity  q0' = omega_0 l: the arrested approach velocity of C           eq. (2), q0'
impact_pulse      the triangular force Q_F of peak F = J_A omega_0 (1+k)/(l tau)  S_C, F_ud, Fig. 7
damping           viscous damping n = zeta omega_c                               eq. (1)-(2), n
preload           constant force -c_free * preload_mm pressing C on the plate    Sec. Results (177 rpm)
cam_drive         v0 from the cam law through the elastic lever; roller force   Fig. 4
================  ============================================================  ===============

Units: the names say so (mm, GPa, kg, rpm, deg); the functions return SI (m, s, N, rad/s).
"""
import math
from dataclasses import dataclass
from typing import Annotated, ClassVar, Literal

from annotated_types import Interval

from mechopt.kit.errors import ModelError, require
from mechopt.kit.settings import check_fields, range_fault
from mechopt.models.cam_law import SplineLaw
from mechopt.models.cam_laws import law as library_law
from mechopt.models.effects import Effect, check_effects


def reduced_stiffness_N_per_m(E_GPa, J_x_mm4, a_mm, b_mm):
    """Reduced stiffness at the lever's end, c = 3 E J_x / ((a + b) b^2) [N/m] (Sec. Results).

    Parameters
    ----------
    E_GPa : Young's modulus [GPa].
    J_x_mm4 : second moment of area of the lever's section [mm^4].
    a_mm, b_mm : span between the supports and the overhang to the loaded end [mm].

    Examples
    --------
    >>> round(reduced_stiffness_N_per_m(210.0, 13021.0, 80.0, 120.0))
    2848344
    """
    return 3.0 * E_GPa * 1e9 * J_x_mm4 * 1e-12 / ((a_mm + b_mm) * b_mm**2 * 1e-9)


# The range each input of the lever model (and its solvers) is tested over: a lever of a machine,
# generously (a micro-mechanism to a press frame). A hard input rule: past it the beam formulas and
# eq. (2)'s closed form overflow, divide by zero or lose every digit, so an input outside is refused
# before any work. Declared on its field through `stated`, where the model's check
# (kit.settings.check_fields), describe, the scene loader and the docs read it.
STATED_RANGE = {
    "E_GPa": (1e-3, 1e4), "J_x_mm4": (1e-6, 1e12), "a_mm": (1e-3, 1e5), "b_mm": (1e-3, 1e5),
    "a_stop_mm": (1e-3, 1e5), "b_stop_mm": (1e-3, 1e5), "mass_kg": (1e-6, 1e6), "stroke_mm": (1e-6, 1e5),
    "velocity_factor": (1e-6, 1e3), "speed_nominal_rpm": (1e-3, 1e6),
    "amplitude_limit_mm": (1e-9, 1e5), "inertia_A_kgm2": (1e-12, 1e6), "damping_ratio": (0.0, 1e3),
    "preload_mm": (0.0, 1e5), "closure_force_N": (0.0, 1e7), "backlash_mm": (0.0, 10.0),
}


def speed_tag(speed_rpm) -> str:
    """A speed as a value-name suffix: 280.0 -> '280', 177.5 -> '177p5' (mechopt.units reads it back)."""
    return f"{speed_rpm:g}".replace(".", "p")


def stated(key):
    """The stated range of an input as its field's annotation."""
    low, high = STATED_RANGE[key]
    return Interval(ge=low, le=high)


@dataclass(frozen=True)
class Impact:
    """The inputs of eq. (2) for one approach, SI: q'' + 2 n q' + omega^2 q = (Q_F(t) - P) / m,
    q(0) = 0, q'(0) = v0; Q_F rises to `force_N` at `tau_s` and falls to zero at 2 tau."""
    omega_rad_s: float      # omega_c, natural circular frequency on the plate
    damping_rad_s: float    # n (may exceed omega: overdamped)
    mass_kg: float
    v0_m_s: float           # q0'
    force_N: float          # F_ud, peak of the triangular pulse
    tau_s: float            # contact time; the pulse lasts 2 tau
    preload_N: float = 0.0  # P

    @property
    def window_s(self) -> float:
        """Where the first rebound is sought: the pulse and one undamped period after it [s]."""
        return 2.0 * self.tau_s + 2.0 * math.pi / self.omega_rad_s


@dataclass(frozen=True)
class LeverStop:
    """The lift lever striking its plate (paper 004, Figs. 3, 5-8).

    Parameters (units in the names): `E_GPa`, `J_x_mm4` material and section; `a_mm`, `b_mm`
    arms of the moving lever (Fig. 5); `a_stop_mm`, `b_stop_mm` arms on the plate (Fig. 6);
    `mass_kg` reduced mass at C; `stroke_mm` travel of C over the phase angle; `velocity_factor`
    the approach velocity over stroke * Omega / t; `t_deg` the phase angle of the lift's travel
    t(3,7) at which rebounds are computed; `speeds_rpm` main-shaft speeds to report (structure);
    `speed_nominal_rpm`, `amplitude_limit_mm` the operating speed (where the amplitude law is
    linearised, where `operating_point` is measured) and the limit the rebound must keep;
    `restitution` k (effect impact_pulse) and `inertia_A_kgm2` J_A (optional: m l^2 when not
    given); `closure` "force" | "groove" and `backlash_mm` (groove only: the groove's play,
    reduced to C's travel) the roller's closure (module docstring); `damping_ratio` zeta (effect damping, of the link in the rise and of the plate);
    `preload_mm` (effect preload); `closure_force_N` the force holding the roller on its cam and
    `law` the cam's motion law (structure; effect cam_drive, which replaces `velocity_factor`);
    `law_slope_mm_per_deg`, `law_intercept_mm` the amplitude law a(3,7) = slope t + intercept the
    chain's stroke and t are fitted to (solvers/stop_impact/fit.py finds every root of that fit);
    `launch` how C leaves the plate (structure, module docstring: "pulse_plus_v0" | "restitution");
    `effects` the effects the scene calls for (structure:
    the scene's own list, repeated, until the spine hands it to the task).
    """
    E_GPa: Annotated[float, stated("E_GPa")]
    J_x_mm4: Annotated[float, stated("J_x_mm4")]
    a_mm: Annotated[float, stated("a_mm")]
    b_mm: Annotated[float, stated("b_mm")]
    a_stop_mm: Annotated[float, stated("a_stop_mm")]
    b_stop_mm: Annotated[float, stated("b_stop_mm")]
    mass_kg: Annotated[float, stated("mass_kg")]
    stroke_mm: Annotated[float | None, stated("stroke_mm")] = None
    velocity_factor: Annotated[float | None, stated("velocity_factor")] = None
    t_deg: Annotated[float | None, Interval(ge=1e-3, lt=360)] = None      # a phase angle of one cycle
    speed_nominal_rpm: Annotated[float | None, stated("speed_nominal_rpm")] = None
    amplitude_limit_mm: Annotated[float | None, stated("amplitude_limit_mm")] = None
    inertia_A_kgm2: Annotated[float | None, stated("inertia_A_kgm2")] = None
    restitution: Annotated[float | None, Interval(ge=0, le=1)] = None
    damping_ratio: Annotated[float | None, stated("damping_ratio")] = None
    preload_mm: Annotated[float | None, stated("preload_mm")] = None
    closure_force_N: Annotated[float | None, stated("closure_force_N")] = None
    backlash_mm: Annotated[float | None, stated("backlash_mm")] = None
    law_slope_mm_per_deg: Annotated[float | None, Interval(lt=0)] = None
    law_intercept_mm: Annotated[float | None, Interval(gt=0)] = None
    law: str | SplineLaw = ""       # a library law's name, or a synthesised law (solvers/stop_impact/synthesis.py)
    launch: Literal["pulse_plus_v0", "restitution"] = "pulse_plus_v0"   # how C leaves the plate (module docstring)
    closure: Literal["force", "groove"] = "force"     # what N < 0 means (module docstring)
    speeds_rpm: tuple = ()
    effects: tuple = ()

    EFFECTS: ClassVar[dict[str, Effect]] = {
        "initial_velocity": Effect(adds="q0' = omega_0 l, the approach velocity of C", equation="(2)"),
        "impact_pulse": Effect(adds="triangular pulse Q_F, peak F = J_A omega_0 (1+k)/(l tau)",
                               equation="S_C, F_ud, Fig. 7, (2)", params=("restitution",)),
        "damping": Effect(adds="viscous damping n = zeta omega_c", equation="(1)-(2)", params=("damping_ratio",)),
        "preload": Effect(adds="constant force c_free * preload_mm pressing C onto the plate",
                          equation="Sec. Results, 177 rpm", params=("preload_mm",)),
        "cam_drive": Effect(adds="approach velocity from the cam's motion law through the elastic lever "
                                 "(models/cam_follower.py), the roller's contact force against its closure",
                            equation="Fig. 4", params=("closure_force_N",)),
    }

    def __post_init__(self):
        object.__setattr__(self, "speeds_rpm", _names_or_numbers(self, "speeds_rpm", number=True))
        object.__setattr__(self, "effects", _names_or_numbers(self, "effects", number=False))
        check_fields(self)
        check_effects(self)
        if not isinstance(self.law, SplineLaw) and self.law != "":
            jumps = library_law(self.law).interior_jumps()      # any law of the library (mechopt.laws)
            if jumps:       # the chain integrates the rise as one phase: it would step over the jump
                xi, order, _ = jumps[0]
                raise ModelError(f"law={self.law!r}: its {('velocity', 'acceleration')[order - 1]} steps inside "
                                 f"the rise (at xi = {xi:g}); the lift's chain integrates the rise as one phase "
                                 "and does not step over a jump: choose a law whose S'' is continuous inside the "
                                 "rise", key="law")
        if self.launch == "restitution":     # C leaves at k v0: needs k and the approach it reverses
            for effect in ("initial_velocity", "impact_pulse"):
                require(effect in self.effects, f"launch={self.launch!r} needs the effect '{effect}' (C leaves at k v0)",
                        key="launch")
        if self.closure == "groove":         # the groove's play: needed, and only there
            require("cam_drive" in self.effects and self.backlash_mm is not None,
                    f"closure='groove' needs the effect 'cam_drive' and backlash_mm (the groove's play reduced to C, "
                    f"mm; got backlash_mm={self.backlash_mm})", key="backlash_mm")
        else:
            require(self.backlash_mm is None, f"backlash_mm={self.backlash_mm} belongs to closure='groove' "
                    f"(closure={self.closure!r}); drop it or set closure='groove'", key="backlash_mm")
        if "cam_drive" in self.effects:      # one source of the approach velocity: the cam, not a fitted factor
            require(self.velocity_factor is None, f"velocity_factor={self.velocity_factor} is not used with the "
                    "effect 'cam_drive' (the cam computes the approach velocity); drop it", key="velocity_factor")
            for key in ("law", "stroke_mm", "t_deg"):
                require(bool(getattr(self, key)), f"{key}={getattr(self, key)!r} is needed by the effect 'cam_drive'",
                        key=key)
            if "preload" in self.effects and self.preload_mm is not None:    # else C starts on its plate
                require(self.preload_mm < self.stroke_mm, range_fault(
                    "preload_mm", self.preload_mm, f"allowed < stroke_mm={self.stroke_mm:g} (the plate would stand "
                    "at or below the rise's start: the cam could not lift C onto it)"), key="preload_mm")
        require(self.inertia_A_kgm2 is None or "impact_pulse" in self.effects,
                f"inertia_A_kgm2={self.inertia_A_kgm2} belongs to effect 'impact_pulse', which is not listed in "
                "effects; add it or drop the parameter", key="inertia_A_kgm2")
        top = STATED_RANGE["speed_nominal_rpm"][1]
        bad = [s for s in self.speeds_rpm if not 0 < s <= top]
        if bad:
            raise ModelError(f"speeds_rpm={list(self.speeds_rpm)}: every speed must be > 0 and <= {top:g} (got {bad})",
                             key="speeds_rpm")
        for name, keys in (("f_free_Hz", "E_GPa, J_x_mm4, a_mm, b_mm, mass_kg"),
                           ("f_stop_Hz", "E_GPa, J_x_mm4, a_stop_mm, b_stop_mm, mass_kg")):
            if getattr(self, name) > MAX_FREQUENCY_HZ:      # each input in range, together a tuning fork
                raise ModelError(f"{name} = {getattr(self, name):.4g} Hz from {keys}: above {MAX_FREQUENCY_HZ:g} Hz, "
                                 "where no rise or rebound is resolved in reasonable time; check the arms and the "
                                 "section", key=keys.split(", ")[3])

    # ---------------------------------------------------------------- stiffness and frequencies

    @property
    def lever_length_m(self) -> float:
        """l: pivot A to end C, a + b of the moving lever (Fig. 5) [m]."""
        return (self.a_mm + self.b_mm) * 1e-3

    @property
    def c_free_N_per_m(self) -> float:
        """Reduced stiffness of the moving lever, Fig. 5 [N/m]."""
        return reduced_stiffness_N_per_m(self.E_GPa, self.J_x_mm4, self.a_mm, self.b_mm)

    @property
    def c_stop_N_per_m(self) -> float:
        """Reduced stiffness on the plate, Fig. 6 (the extra support) [N/m]."""
        return reduced_stiffness_N_per_m(self.E_GPa, self.J_x_mm4, self.a_stop_mm, self.b_stop_mm)

    @property
    def omega_free_rad_s(self) -> float:
        return math.sqrt(self.c_free_N_per_m / self.mass_kg)

    @property
    def omega_stop_rad_s(self) -> float:
        return math.sqrt(self.c_stop_N_per_m / self.mass_kg)

    @property
    def f_free_Hz(self) -> float:
        """Natural frequency of the moving lever, sqrt(c/m)/(2 pi) [Hz] (the scenes calibrate the mass on the paper's figure)."""
        return self.omega_free_rad_s / (2 * math.pi)

    @property
    def f_stop_Hz(self) -> float:
        """Natural frequency on the plate [Hz] (the scenes calibrate b_stop_mm on the paper's figure)."""
        return self.omega_stop_rad_s / (2 * math.pi)

    @property
    def contact_time_s(self) -> float:
        """tau: half the natural period on the plate, pi / omega_stop [s] (Panovko's rule [25])."""
        return math.pi / self.omega_stop_rad_s

    # ---------------------------------------------------------------- impact

    def approach_velocity_m_s(self, speed_rpm, t_deg=None):
        """v0 = omega_0 l = velocity_factor * stroke * Omega / t [m/s], Omega = 2 pi n / 60 (arrays allowed).
        With the effect `cam_drive` the cam computes v0 (solvers/stop_impact/cam_follower.py), not this."""
        if "cam_drive" in self.effects:
            raise ModelError("effects lists 'cam_drive': the approach velocity comes from the cam's rise "
                             "(solvers.stop_impact.cam_follower.follow_cam), not from velocity_factor", key="effects")
        t_deg = self.t_deg if t_deg is None else t_deg
        self.need("velocity_factor", "stroke_mm", "t_deg" if t_deg is None else None)
        omega_shaft = 2 * math.pi * speed_rpm / 60.0
        return self.velocity_factor * self.stroke_mm * 1e-3 * omega_shaft / (t_deg * math.pi / 180.0)

    @property
    def inertia_A_used_kgm2(self) -> float:
        """J_A of S_C: the scene's `inertia_A_kgm2` when given (the paper's separate figure), else
        m l^2, the reduced mass at C seen from the pivot A (one lever: mass and inertia agree)."""
        return self.inertia_A_kgm2 if self.inertia_A_kgm2 is not None else self.mass_kg * self.lever_length_m**2

    def impact_force_N(self, v0_m_s):
        """F_ud = J_A omega_0 (1 + k) / (l tau), omega_0 = v0 / l [N] (Sec. Results; S_C = F tau)."""
        self.need_effect("impact_pulse")
        l = self.lever_length_m
        return self.inertia_A_used_kgm2 * (v0_m_s / l) * (1 + self.restitution) / (l * self.contact_time_s)

    @property
    def preload_N(self) -> float:
        """P = c_free * preload: the cam's interference held by the moving lever [N]; 0 without the effect."""
        return self.c_free_N_per_m * self.preload_mm * 1e-3 if "preload" in self.effects else 0.0

    def impact(self, speed_rpm, t_deg=None, *, v0_m_s=None) -> Impact:
        """The inputs of eq. (2) at one speed and phase angle, with only the listed effects; `v0_m_s`
        the approach velocity when the cam computed it (effect cam_drive). Under the launch
        reading "restitution" C leaves at k v0 and no pulse follows (the pulse is the restitution)."""
        v0 = self.approach_velocity_m_s(speed_rpm, t_deg) if v0_m_s is None else v0_m_s
        omega = self.omega_stop_rad_s
        pulse = "impact_pulse" in self.effects and self.launch == "pulse_plus_v0"
        launch = v0 * (self.restitution if self.launch == "restitution" else 1.0)
        return Impact(omega_rad_s=omega,
                      damping_rad_s=self.damping_ratio * omega if "damping" in self.effects else 0.0,
                      mass_kg=self.mass_kg,
                      v0_m_s=launch if "initial_velocity" in self.effects else 0.0,
                      force_N=self.impact_force_N(v0) if pulse else 0.0,
                      tau_s=self.contact_time_s, preload_N=self.preload_N)

    def warnings(self, values: dict) -> list[str]:
        """Where the single-mass lever leaves what it supports, at the speeds this task names."""
        return self.slow_mode_warnings([*self.speeds_rpm, self.speed_nominal_rpm])

    def slow_mode_warnings(self, speeds_rpm) -> list[str]:
        """A single-mass lever model needs its first mode faster than the cycle it is struck in."""
        slow = [n for n in speeds_rpm if n is not None and self.f_free_Hz < n / 60]
        if not slow:
            return []
        return [f"the lever's first mode ({self.f_free_Hz:.3g} Hz) is slower than the cycle at {max(slow):g} rpm "
                f"({max(slow) / 60:.3g} Hz): it does not settle between strikes, which the single-mass rebound "
                f"assumes"]

    # ---------------------------------------------------------------- checks for solvers

    def need(self, *keys):
        """Raise ModelError naming the first parameter a computation needs and the task lacks."""
        for key in keys:
            if key is not None and getattr(self, key) is None:
                raise ModelError(f"{key} is not given; this computation needs it", key=key)

    def need_effect(self, effect):
        if effect not in self.effects:
            raise ModelError(f"effects={list(self.effects)}: this computation needs the effect '{effect}'",
                             key="effects")


def _names_or_numbers(task, key, *, number):
    value = getattr(task, key)
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise ModelError(f"{key}={value!r}: expected a list of " + ("numbers" if number else "effect names"),
                         key=key)
    for v in value:
        ok = (isinstance(v, (int, float)) and not isinstance(v, bool)) if number else isinstance(v, str)
        if not ok:
            raise ModelError(f"{key}={list(value)}: {v!r} is not " + ("a number" if number else "an effect name"),
                             key=key)
    return tuple(float(v) for v in value) if number else tuple(value)


MAX_FREQUENCY_HZ = 1e5      # a lever's natural frequency: past it the solvers' steps run into the millions

