"""Network cyclogram of a machine: events, operations and their limits (paper 004: Podgorny et al. 2018).

Vertices are events (characteristic positions of mechanisms) with times p; arcs are operations
(x, y) with phase angle t(x, y) = p(y) - p(x) (the paper: "the difference of the event times").
Each operation carries a minimum angle [phi], optionally a contact-stress model of its cam pair
and an amplitude model of its working member. Angles are machine degrees of the main shaft, not
radians: the paper's coefficients (mm/deg) and every cyclogram are in degrees.

Every limit is a lower bound on the phase angle, so the cyclogram is a system of difference
constraints p(y) - p(x) >= lb(x, y); windows (p(y) - p(x) <= w) and synchronisations
(p(x) = p(y)) add arcs of the other sign. `lower_bounds_deg` gives lb for any limit values.

Effects a scene may call for:

==============  =====================================================  =====================
effect          adds                                                   paper
==============  =====================================================  =====================
contact_stress  sigma_max(t) <= [sigma_H] on operations naming a       constraint after (1)
                stress model; sigma_max = sigma_ref t_ref / t
stop_vibration  a(t) = slope t + intercept <= amplitude limit on       linearised a(3,7) (Results
                operations with amplitude = "linear"; its exact law    and discussion, last formula;
                a(t, n) from the lever table `lever` (the chain cam    Fig. 4 and eq. (2) for the
                -> approach velocity -> impact -> eq. (2))             exact law)
==============  =====================================================  =====================

Speed (`speed_rpm`, the main shaft's n): the stresses and the exact rebound law are taken at
n; the stress references (sigma_ref at t_ref) hold at `stress_speed_rpm` (default n). An operation may also need a time rather than an angle
(`min_ms`, e.g. the microshuttle's flight): at n it spans at least 6 n T deg (360 deg per
60/n s), so its lower bound is max(min_deg, 0.006 n min_ms).

Contact stress (our reading; the paper gives no law): a cam pair under inertial load carries
F = m h omega^2 C / t^2 (lift h over phase angle t, C the law's acceleration coefficient), and
the Hertz line-contact stress grows as sqrt(F), so sigma_max(t) = sigma_ref t_ref / t: one
reference point (t_ref, sigma_ref) per cam pair fixes the curve. sigma_max <= [sigma_H] is then
exactly t >= sigma_ref t_ref / [sigma_H] ("turned into a bound on the phase angle"); its tangent
at t_ref, `stress_bound_deg(..., form="linear")`, is the linearisation a linear design asks for.
At another speed n the inertial load scales as n^2, so sigma_max(t, n) = sigma_ref (t_ref / t)
(n / n_ref), n_ref the speed of the references: a function of n / t alone, as the rebound is:
the cam's rise in its own time depends on t / n only (lambda = omega t / Omega), so v0, the
pulse and the first rebound are a function h(n / t), not proportional to it, and h is wavy (the
lever rings during the rise): a(t) <= limit is then not one bound from one tangent.
"""
import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Annotated, ClassVar

import networkx as nx
import numpy as np
from annotated_types import Gt, Le, Lt

from mechopt.kit.errors import MechoptError, ModelError, some_of
from mechopt.kit.settings import check_fields
from mechopt.models.cyclogram_motions import (
    CLEARANCE_COLUMNS,
    LEAST_ANGLE,
    MOTION_KEYS,
    OBJECTIVES,
    Clearance,
    clearance_rows,
    motion_of,
    operation_index,
)
from mechopt.models.effects import Effect
from mechopt.models.provenance import provenance_problem
from mechopt.models.stop_impact import LeverStop

STRESS_FORMS = ("exact", "linear")
# stated limits of the inputs: past 1e6 deg (a thousand turns) the LP's feasibility tolerance
# (1e-7 relative) is coarser than the 1e-6 deg its answer is certified to; stresses past 1e6 MPa
# are no material's (and square past the float range in the sensitivities)
MAX_DEG = 1e6
MAX_MPA = 1e6
MAX_RPM = 1e6           # the lever model's stated range (models/stop_impact.py)
MAX_MS = 1e6
MAX_CYCLES = 1_000_000  # cycles a recurrent operation may span (a whole number)
AMPLITUDE_LAWS = ("linear",)
_NOTE_KEYS = {"mark", "why", "where", "what"}         # provenance and description, not physics
_EVENT_KEYS = {"mechanism", "group"} | _NOTE_KEYS
_OP_KEYS = {"from", "to", "min_deg", "min_ms", "max_deg", "stress", "amplitude", "name", "group",
            "mechanism", "cycles"} | set(MOTION_KEYS) | _NOTE_KEYS
# an operations table read from a designer's CSV (scene: `operations = { csv = "ops.csv", columns =
# [...] }`): its columns and their kinds; event names are text ("3", "10.1", "feed.start")
OPERATION_COLUMNS = {"from": str, "to": str, "name": str, "group": str, "mechanism": str, "min_deg": float,
                     "min_ms": float, "max_deg": float, "stress": str, "amplitude": str, "mark": str, "why": str,
                     "cycles": float, "law": str, "stroke_mm": float, "max_accel_m_s2": float,
                     "max_velocity_m_s": float, "direction": str}
WINDOW_COLUMNS = {"from": str, "to": str, "max_deg": float, "max_ms": float} | {k: str for k in sorted(_NOTE_KEYS)}
SYNC_COLUMNS = {"events": str} | {k: str for k in sorted(_NOTE_KEYS)}   # events "a;b;c": one sync per row
_STRESS_KEYS = {"sigma_ref_MPa", "t_ref_deg"} | _NOTE_KEYS
_WINDOW_KEYS = {"from", "to", "max_deg", "max_ms"} | _NOTE_KEYS
_SYNC_KEYS = {"events"} | _NOTE_KEYS
# a task table (activity on node): each task a duration and the tasks it waits for, "a;b", one k
# cycles before written "b@k"; turned into the event network by `task_operations`
TASK_COLUMNS = {"task": str, "min_ms": float, "min_deg": float, "after": str, "name": str, "group": str,
                "mechanism": str, "mark": str, "why": str}
_TASK_KEYS = set(TASK_COLUMNS) | _NOTE_KEYS


def stress_MPa(sigma_ref_MPa, t_ref_deg, t_deg):
    """Maximum contact stress of a cam pair moved over phase angle t [MPa]: sigma_ref t_ref / t
    (Hertz sigma ~ sqrt(inertial load), load ~ 1/t^2; see the module docstring)."""
    return sigma_ref_MPa * t_ref_deg / t_deg


def stress_bound_deg(sigma_ref_MPa, t_ref_deg, sigma_H_MPa, form="exact"):
    """Smallest phase angle with sigma_max(t) <= [sigma_H] [deg].

    ``exact``: t >= sigma_ref t_ref / [sigma_H]. ``linear``: the tangent of sigma_max at t_ref,
    sigma_ref (2 - t / t_ref) <= [sigma_H], i.e. t >= t_ref (2 - [sigma_H] / sigma_ref). The
    curve is convex, so the tangent lies under it: the linear bound is never above the exact one.
    """
    if form == "exact":
        return sigma_ref_MPa * t_ref_deg / sigma_H_MPa
    if form == "linear":
        return t_ref_deg * (2.0 - sigma_H_MPa / sigma_ref_MPa)
    raise ModelError(f"stress_form={form!r}: allowed {', '.join(STRESS_FORMS)}", key="stress_form")


def amplitude_mm(slope_mm_per_deg, intercept_mm, t_deg):
    """Vibration amplitude of the working member after its stop, linearised in t [mm]:
    a(3,7) = slope t(3,7) + intercept (paper 004, the law before Conclusions)."""
    return slope_mm_per_deg * t_deg + intercept_mm


def amplitude_bound_deg(slope_mm_per_deg, intercept_mm, limit_mm):
    """Smallest phase angle with a(t) <= limit [deg] (slope < 0): (intercept - limit) / -slope."""
    return (limit_mm - intercept_mm) / slope_mm_per_deg


def time_floor_deg(min_ms, speed_rpm):
    """Angle the main shaft turns in `min_ms` at `speed_rpm` [deg]: 360 n / 60 deg/s times T."""
    return 0.006 * speed_rpm * min_ms


def lever_stop(table) -> LeverStop:
    """The lift lever of the stop-impact model (models/stop_impact.py) from a scene's
    [structure.lever] table: LeverStop's parameters, each a number or {value, mark, why / where /
    on}, its `effects` and the cam's motion `law` (a name, effect cam_drive). The one place the
    cyclogram couples to the stop model."""
    _table(table, "lever", dict)
    args = {}
    for key, entry in table.items():
        if key in ("effects", "law"):
            args[key] = entry
            continue
        if isinstance(entry, dict):
            _entry(entry, f"lever.{key}", {"value", "on"} | _NOTE_KEYS, required=("value",))
            entry = entry["value"]
        args[key] = _number(entry, f"lever.{key}")
    known = {f.name for f in dataclasses.fields(LeverStop)}
    unknown = sorted(set(args) - known)
    if unknown:
        raise ModelError(f"lever: unknown {', '.join(unknown)}; allowed: {', '.join(sorted(known))}", key="lever")
    try:
        return LeverStop(**args)
    except MechoptError as exc:
        raise ModelError(f"lever.{exc}", key=f"lever.{exc.key}" if exc.key else "lever") from None
    except TypeError as exc:            # a required parameter missing
        raise ModelError(f"lever: {exc}", key="lever") from None


@dataclass(frozen=True)
class Cyclogram:
    """A machine's network cyclogram and the question asked of it.

    Structure (from the scene's ``[structure]``): `operations` [{from, to, min_deg, min_ms?,
    max_deg?, stress?, amplitude?, name?, group?, mechanism?}] (min_deg is [phi] in deg; min_ms a
    least duration, then min_deg may be left out; max_deg the operation's window, moved to
    `windows`), as a list or a CSV timing table (`CSV_TABLES`); `events` {name: {mechanism, group}},
    by default the events the operations name, grouped as the operations ending at them agree;
    `stress_models` {name: {sigma_ref_MPa, t_ref_deg}}; `windows` [{from, to, max_deg}]:
    p(to) - p(from) <= max_deg (or max_ms, a time: its angle at speed_rpm, or a duration in a
    time-based network); `syncs` [{events = [a, b, ...]}]: equal times. Windows and syncs too may
    come from a CSV of any length (columns from, to, max_deg or max_ms; a sync's events "a;b;c").
    An operation with `cycles` = k > 0 is recurrent: it ends at its `to` of k cycles later
    (`recurrences`; the least cycle time, `loom.least_cycle_time`).
    `limiting_op` [x, y]: maximise t(x, y) inside `cycle_deg` instead of minimising the span.
    Every entry may carry provenance notes: mark (given / assumed / calibrated), why, where, what.

    Parameters: `cycle_deg` machine cycle [deg] (p(last) - p(first) <= cycle_deg);
    `sigma_H_limit_MPa` allowable contact stress [sigma_H] (effect contact_stress);
    `amplitude_slope_mm_per_deg`, `amplitude_intercept_mm`, `amplitude_limit_mm` the amplitude
    law and its limit (effect stop_vibration); `speed_rpm` the main shaft's speed n at which the
    exact rebound and the stresses are evaluated and `min_ms` turns into degrees;
    `stress_speed_rpm` the speed the stress references were taken at (default: speed_rpm).
    `lever` (structure): the lift lever's table (see `lever_stop`), the exact law a(t, n) behind
    the linear one; a task may give it instead of the linear law's slope and intercept.

    Motions (models/loom_motions.py): an operation may carry `law`, `stroke_mm`, `direction` and
    `max_accel_m_s2` / `max_velocity_m_s` (a least duration, folded into its min_ms);
    `clearances` [{operation, at, relation, other, other_at, cycles?}] (a CSV too) between two
    motions; `maximize = "least_angle"` over `least_angle_of` (operation names or "from->to");
    `span_within_cycle` (default true: p(last) - p(first) <= cycle_deg; false when one cycle's
    motions run into the next). These three are rows of loom.plan_motions' LP only.
    """
    operations: list = field(default_factory=list)
    tasks: list = field(default_factory=list)
    events: dict = field(default_factory=dict)
    stress_models: dict = field(default_factory=dict)
    windows: list = field(default_factory=list)
    syncs: list = field(default_factory=list)
    limiting_op: list | None = None
    cycle_deg: Annotated[float | None, Gt(0), Le(MAX_DEG)] = None
    sigma_H_limit_MPa: Annotated[float | None, Gt(0), Le(MAX_MPA)] = None
    # the rebound amplitude falls as the approach to the stop slows (a larger phase angle): slope < 0; the
    # intercept is the amplitude at t = 0, > 0, else the falling law is negative at every angle
    amplitude_slope_mm_per_deg: Annotated[float | None, Lt(0)] = None
    amplitude_intercept_mm: Annotated[float | None, Gt(0)] = None
    amplitude_limit_mm: Annotated[float | None, Gt(0)] = None
    speed_rpm: Annotated[float | None, Gt(0), Le(MAX_RPM)] = None
    stress_speed_rpm: Annotated[float | None, Gt(0), Le(MAX_RPM)] = None
    lever: dict | None = None
    # the highest speed the lever's law was studied at: above it a warning (`warnings`)
    lever_law_max_rpm: Annotated[float | None, Gt(0), Le(MAX_RPM)] = None
    # motions (models/loom_motions.py): clearances between them, and the objective over their angles
    clearances: list = field(default_factory=list)
    maximize: str | None = None
    least_angle_of: list = field(default_factory=list)
    span_within_cycle: bool = True

    EFFECTS: ClassVar[dict[str, Effect]] = {
        "contact_stress": Effect(adds="sigma_max(t) <= [sigma_H] on operations naming a stress model",
                                 equation="constraint after (1)", params=("sigma_H_limit_MPa",)),
        "stop_vibration": Effect(adds="a(t) = slope t + intercept <= limit on amplitude operations",
                                 equation="linearised a(3,7), Results and discussion",
                                 params=("amplitude_slope_mm_per_deg", "amplitude_intercept_mm",
                                         "amplitude_limit_mm")),
    }

    # structure tables a scene may read from a CSV file as rows of named, typed columns
    # tables a scene may read from a CSV beside it, any length (an inline list holds at most 100 rows)
    CSV_TABLES: ClassVar[dict] = {"operations": (("from", "to"), OPERATION_COLUMNS),
                                  "windows": (("from", "to"), WINDOW_COLUMNS),
                                  "syncs": (("events",), SYNC_COLUMNS), "tasks": (("task",), TASK_COLUMNS),
                                  "clearances": (("operation", "other"), CLEARANCE_COLUMNS)}

    def __post_init__(self):
        check_fields(self)
        if self.tasks:                  # a task table becomes the operations it stands for
            ops = task_operations(self.tasks)
            if self.operations and self.operations != ops:
                raise ModelError("tasks: a network is given by its operations or by its tasks, not both", key="tasks")
            object.__setattr__(self, "operations", ops)
        elif not self.operations:
            raise ModelError("operations: missing (give the operations, or a task table `tasks`)", key="operations")
        _table(self.operations, "operations", list)
        _table(self.events, "events", dict)
        if not self.events:             # events named by the operations need no table of their own
            object.__setattr__(self, "events", _events_of(self.operations))
        if isinstance(self.syncs, list) and any(isinstance(s, dict) and isinstance(s.get("events"), str)
                                                for s in self.syncs):      # a CSV row names its events "a;b"
            object.__setattr__(self, "syncs", [s | {"events": [e.strip() for e in s["events"].split(";")]}
                                               if isinstance(s, dict) and isinstance(s.get("events"), str) else s
                                               for s in self.syncs])
        _ = self.recurrences    # checked before a window is split off an operation (none on a recurrent one)
        if any(isinstance(op, dict) and "max_deg" in op for op in self.operations):
            operations, windows = _split_windows(self.operations)
            object.__setattr__(self, "operations", operations)
            object.__setattr__(self, "windows", list(self.windows) + windows)
        if self.lever is not None:
            _ = self.lever_model    # builds and validates the lever (cached)
        self.graph          # builds and validates the network (cached)
        self._check_bounds()
        self._check_motions()

    def _check_motions(self):
        """The clearances and the objective over the motions' angles, resolved (cached) and checked."""
        _ = self.clearance_rows
        if self.maximize is not None and self.maximize not in OBJECTIVES:
            raise ModelError(f"maximize={self.maximize!r}: allowed {', '.join(OBJECTIVES)}", key="maximize")
        if (self.maximize == LEAST_ANGLE) != bool(self.least_angle_of):
            raise ModelError(f"least_angle_of: maximize = {LEAST_ANGLE!r} needs the operations it takes the least "
                             f"angle of, and they need it", key="least_angle_of")
        _ = self.least_angle_arcs
        if not isinstance(self.span_within_cycle, bool):
            raise ModelError(f"span_within_cycle={self.span_within_cycle!r}: allowed true, false", key="span_within_cycle")
        if self.clearance_rows and any(c.cycles for c in self.clearance_rows) and self.cycle_deg is None:
            raise ModelError("cycle_deg: a clearance with the other operation of a later cycle needs the cycle",
                             key="cycle_deg")

    @cached_property
    def clearance_rows(self) -> tuple[Clearance, ...]:
        """The `clearances` table resolved: operations as arc indices, displacements as angle fractions."""
        names = [d["name"] for d in self._arc_data]
        return clearance_rows(self.clearances, self.arcs, names, self.motion_arcs, MAX_CYCLES)

    @cached_property
    def least_angle_arcs(self) -> tuple[int, ...]:
        """Arc indices of the operations whose least angle `maximize = "least_angle"` maximises."""
        if not isinstance(self.least_angle_of, list):
            raise ModelError(f"least_angle_of={self.least_angle_of!r}: a list of operations (names or from->to)",
                             key="least_angle_of")
        names = [d["name"] for d in self._arc_data]
        return tuple(operation_index(self.arcs, names, ref, f"least_angle_of[{j}]")
                     for j, ref in enumerate(self.least_angle_of))

    def check_plain(self, solver: str) -> None:
        """ModelError when the task asks for what only loom.plan_motions solves (clearances, the least angle)."""
        if self.clearances or self.maximize is not None or not self.span_within_cycle:
            key = "clearances" if self.clearances else ("maximize" if self.maximize else "span_within_cycle")
            raise ModelError(f"{key}: not solved by {solver} (difference constraints only); a clearance (a row of the event-time "
                             f"LP in two operations' angles), maximize = {LEAST_ANGLE!r} and span_within_cycle = false "
                             f"are solved by loom.plan_motions", key=key)

    def _check_bounds(self):
        """Every derived lower bound inside the stated range, named by the inputs that set it."""
        if self.speed_rpm is None and self.time_arcs():
            return      # durations without a speed have no angle yet: an angle solver asks for speed_rpm
        for form in STRESS_FORMS:
            lb, why = self.lower_bounds_deg(form)
            for k in np.flatnonzero(~(np.abs(lb) <= MAX_DEG)):
                x, y = self.arcs[k]
                keys = {"contact_stress": f"stress_models.{self.arc_data(k)['stress']} and sigma_H_limit_MPa",
                        "amplitude": "amplitude_slope_mm_per_deg, amplitude_intercept_mm and amplitude_limit_mm"
                        }.get(why[k], f"operations[{x}->{y}].min_deg")
                raise ModelError(f"operations[{x}->{y}]: its {why[k]} bound {lb[k]:.6g} deg ({form} form), set by "
                                 f"{keys}, is outside the allowed +-{MAX_DEG:g} deg", key=keys.split(" and ")[0].split(",")[0])

    # ------------------------------------------------------------------ the network

    @cached_property
    def graph(self) -> nx.DiGraph:
        """Events as nodes (mechanism, group), operations as arcs (min_deg, stress, amplitude)."""
        _table(self.events, "events", dict)
        g = nx.DiGraph()
        for name, attrs in self.events.items():
            _entry(attrs, f"events.{name}", _EVENT_KEYS, required=())
            g.add_node(str(name), mechanism=str(attrs.get("mechanism", "")), group=str(attrs.get("group", "")))
        _table(self.operations, "operations", list)
        for k, op in enumerate(self.operations):
            key = f"operations[{k}]"
            _entry(op, key, _OP_KEYS, required=("from", "to") if "min_ms" in op else ("from", "to", "min_deg"))
            x, y = str(op["from"]), str(op["to"])
            key = f"operations[{x}->{y}]"
            if _cycles(op, key):
                continue        # a recurrent operation: not an arc of the cycle's network (`recurrences`)
            for end in (x, y):
                _known_event(g, end, key)
            if x == y:
                raise ModelError(f"{key}: an operation must join two different events", key=key)
            if g.has_edge(x, y):
                raise ModelError(f"{key}: given twice; one operation per pair of events", key=key)
            phi, min_ms = _floors(op, key)
            motion = motion_of(op, key)
            motion_ms, motion_limit = motion.least_ms() if motion else (0.0, "")
            if motion_ms > (min_ms or 0.0):      # the motion's limits as a least duration (models/loom_motions.py)
                min_ms = motion_ms
            stress, amplitude = op.get("stress"), op.get("amplitude")
            if stress is not None:
                self._check_stress_ref(stress, key)
            if amplitude is not None:
                self._check_amplitude_ref(amplitude, key)
            g.add_edge(x, y, min_deg=phi, min_ms=min_ms, stress=stress, motion=motion, motion_limit=motion_limit
                       if motion_ms and motion_ms == min_ms else "", amplitude=amplitude,
                       name=str(op.get("name", "")), group=str(op.get("group", "")))
        if not nx.is_directed_acyclic_graph(g):
            cycle = nx.find_cycle(g)
            chain = some_of([cycle[0][0]] + [v for _, v in cycle], sep=" -> ")
            raise ModelError(f"operations: precedence cycle {chain}: an event cannot precede itself", key="operations")
        self._check_ends(g)
        return g

    def _check_stress_ref(self, name, key):
        _table(self.stress_models, "stress_models", dict)
        if name not in self.stress_models:
            raise ModelError(f"{key}.stress={name!r}: no such stress model; defined: "
                             f"{', '.join(self.stress_models) or 'none'}", key=f"{key}.stress")
        if self.sigma_H_limit_MPa is None:
            raise ModelError(f"{key}.stress={name!r} needs sigma_H_limit_MPa (effect contact_stress)",
                             key="sigma_H_limit_MPa")
        model = self.stress_models[name]
        _entry(model, f"stress_models.{name}", _STRESS_KEYS, required=("sigma_ref_MPa", "t_ref_deg"))
        for k, top in (("sigma_ref_MPa", MAX_MPA), ("t_ref_deg", MAX_DEG)):
            if not 0 < _number(model[k], f"stress_models.{name}.{k}") <= top:
                raise ModelError(f"stress_models.{name}.{k}={model[k]} must be in (0, {top:g}]",
                                 key=f"stress_models.{name}.{k}")

    def _check_amplitude_ref(self, law, key):
        if law not in AMPLITUDE_LAWS:
            raise ModelError(f"{key}.amplitude={law!r}: no such amplitude model; known: "
                             f"{', '.join(AMPLITUDE_LAWS)}", key=f"{key}.amplitude")
        missing = [k for k in ("amplitude_slope_mm_per_deg", "amplitude_intercept_mm") if getattr(self, k) is None]
        if len(missing) == 2 and self.lever is not None:
            missing = []                # the lever's exact law stands in for the linear one
        missing += ["amplitude_limit_mm"] if self.amplitude_limit_mm is None else []
        if missing:
            raise ModelError(f"{key}.amplitude={law!r} needs {', '.join(missing)} (effect stop_vibration)"
                             + (" (or, for slope and intercept, the exact law's table `lever`)"
                                if len(missing) > 1 else ""), key=missing[0])

    @property
    def has_linear_amplitude(self) -> bool:
        """Whether the linear law a = slope t + intercept is given (else only the lever's exact law)."""
        return self.amplitude_slope_mm_per_deg is not None

    def warnings(self, values: dict) -> list[str]:
        """Where the lever's exact law is applied beyond what it supports: its first mode slower
        than the cycle, a speed above the highest its source studied. The answer stands."""
        speed = values.get("max_speed_rpm", self.speed_rpm)
        if self.lever is None or speed is None:
            return []
        out = self.lever_model.slow_mode_warnings([speed])
        top = self.lever_law_max_rpm
        if top is not None and speed > top:
            out.append(f"the lever's rebound law is applied at {speed:.4g} rpm, above lever_law_max_rpm = {top:g} rpm, "
                       f"the highest speed its source studied: an extrapolation")
        return out

    @cached_property
    def lever_model(self) -> LeverStop:
        """The lever of the exact rebound law, from the `lever` table (ModelError without one)."""
        if self.lever is None:
            raise ModelError("lever: the exact rebound law needs the lift lever's table [structure.lever]",
                             key="lever")
        return lever_stop(self.lever)

    def _check_ends(self, g):
        linked = [v for v in g if g.degree(v) > 0]
        starts = [v for v in linked if g.in_degree(v) == 0]
        ends = [v for v in linked if g.out_degree(v) == 0]
        # a recurrent network is a circuit of cycles, not one cycle's chain from a first to a last event
        if (len(starts) != 1 or len(ends) != 1) and not self.recurrences:
            listed = [f"[{some_of(map(repr, events), sep=', ')}]" for events in (starts, ends)]
            raise ModelError(f"operations: a cyclogram needs one first and one last event; found first {listed[0]} "
                             f"and last {listed[1]} (join them with zero-angle operations)", key="operations")
        _table(self.windows, "windows", list)
        for k, w in enumerate(self.windows):
            key = f"windows[{k}]"
            _entry(w, key, _WINDOW_KEYS, required=("from", "to"))
            for end in (w["from"], w["to"]):
                _linked_event(g, str(end), key, self._recurrent_events)
            given = [unit for unit in ("max_deg", "max_ms") if unit in w]
            if len(given) != 1:
                raise ModelError(f"{key}: give max_deg (an angle) or max_ms (a time), one of them; got "
                                 f"{' and '.join(given) or 'neither'}", key=key)
            limit, top = (MAX_DEG, "deg") if given[0] == "max_deg" else (MAX_MS, "ms")
            if not abs(_number(w[given[0]], f"{key}.{given[0]}")) <= limit:
                raise ModelError(f"{key}.{given[0]}={w[given[0]]}: allowed within +-{limit:g} {top}",
                                 key=f"{key}.{given[0]}")
        _table(self.syncs, "syncs", list)
        for k, s in enumerate(self.syncs):
            key = f"syncs[{k}]"
            _entry(s, key, _SYNC_KEYS, required=("events",))
            if not isinstance(s["events"], list) or len(s["events"]) < 2:
                raise ModelError(f"{key}.events={s['events']!r}: give a list of two or more events", key=key)
            for end in s["events"]:
                _linked_event(g, str(end), key, self._recurrent_events)
        if self.limiting_op is not None:
            if not isinstance(self.limiting_op, list) or len(self.limiting_op) != 2 \
                    or not g.has_edge(str(self.limiting_op[0]), str(self.limiting_op[1])):
                raise ModelError(f"limiting_op={self.limiting_op!r}: must name an operation [from, to]",
                                 key="limiting_op")

    @cached_property
    def recurrences(self) -> tuple[dict, ...]:
        """The recurrent operations, rows with `cycles` = k > 0: p(to) + k T >= p(from) + d, the
        event `to` of k cycles later after `from` of this one (T the cycle; d its min_deg, or min_ms
        in a time-based network). `from` may equal `to` (a station busy for d before it starts
        again). They carry a floor only (min_deg or min_ms): no window, stress or amplitude. The
        least cycle time over them is `loom.least_cycle_time`; a one-cycle solver refuses them
        (`check_one_cycle`). Rows with cycles = 0 are ordinary operations."""
        _table(self.operations, "operations", list)
        out, seen = [], set()
        for op in self.operations:
            if not isinstance(op, dict) or "cycles" not in op or "from" not in op or "to" not in op:
                continue                # an ordinary row, or one the network's checks report
            x, y = str(op["from"]), str(op["to"])
            key = f"operations[{x}->{y}]"
            k = _cycles(op, key)
            if not k:
                continue
            _entry(op, key, _OP_KEYS, required=("from", "to") if "min_ms" in op else ("from", "to", "min_deg"))
            for end in (x, y):
                if end not in self.events:
                    raise ModelError(f"{key}: unknown event {end!r}; events: {some_of(self.events, sep=', ')}",
                                     key=key)
            extra = sorted(({"max_deg", "stress", "amplitude"} | set(MOTION_KEYS)) & op.keys())
            if extra:
                raise ModelError(f"{key}.cycles={k}: a recurrent operation carries min_deg or min_ms only, not "
                                 f"{', '.join(extra)}", key=f"{key}.{extra[0]}")
            if (x, y, k) in seen:
                raise ModelError(f"{key}.cycles={k}: given twice; one operation per pair of events and cycles",
                                 key=key)
            seen.add((x, y, k))
            phi, min_ms = _floors(op, key)
            out.append({"from": x, "to": y, "cycles": k, "min_deg": phi, "min_ms": min_ms,
                        "name": str(op.get("name", ""))})
        return tuple(out)

    @cached_property
    def _recurrent_events(self) -> frozenset:
        return frozenset(e for op in self.recurrences for e in (op["from"], op["to"]))

    def check_one_cycle(self, solver: str) -> None:
        """ModelError when the network has recurrent operations: `solver` schedules one cycle."""
        if self.recurrences:
            op = self.recurrences[0]
            key = f"operations[{op['from']}->{op['to']}].cycles"
            raise ModelError(f"{key}={op['cycles']}: {solver} schedules one cycle and takes no recurrent "
                             f"operation; the least cycle time of a recurrent network is loom.least_cycle_time",
                             key=key)

    # ------------------------------------------------------------------ views

    @property
    def event_names(self) -> list[str]:
        return list(self.graph.nodes)

    @cached_property
    def arcs(self) -> list[tuple[str, str]]:
        """Operations as (from, to), in the order every per-arc array uses."""
        return list(self.graph.edges)

    # the views below are cached (the task is frozen): a solve asks for them several times, and a
    # walk over the graph's nodes or edges costs ~0.1 s at 10^5 events

    @cached_property
    def index_arrays(self) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
        """(events in graph order without the isolated ones, tails, heads): the operations as
        index arrays into those events, in `arcs` order (read-only; the solvers' view)."""
        names, index = tuple(self.event_index), self.event_index
        tails = np.fromiter((index[x] for x, _ in self.arcs), dtype=np.int64, count=len(self.arcs))
        heads = np.fromiter((index[y] for _, y in self.arcs), dtype=np.int64, count=len(self.arcs))
        tails.flags.writeable = heads.flags.writeable = False
        return names, tails, heads

    @cached_property
    def event_index(self) -> dict[str, int]:
        """Event -> its index in `index_arrays` (graph order, isolated events left out); not to be changed."""
        isolated = set(self._isolated)
        return {v: i for i, v in enumerate(v for v in self.graph if v not in isolated)}

    @cached_property
    def group_indices(self) -> dict[str, np.ndarray]:
        """Group -> the indices (as `event_index`) of its events that have an operation."""
        index = self.event_index
        return {group: np.array([index[v] for v in events if v in index], dtype=np.int64)
                for group, events in self._groups.items()}

    @cached_property
    def operation_labels(self) -> np.ndarray:
        """Each operation as "from->to", in `arcs` order (read-only)."""
        labels = np.array([f"{x}->{y}" for x, y in self.arcs], dtype=str)
        labels.flags.writeable = False
        return labels

    @cached_property
    def first_event(self) -> str:
        return next(v for v in self.graph if self.graph.in_degree(v) == 0 and self.graph.out_degree(v) > 0)

    @cached_property
    def last_event(self) -> str:
        return next(v for v in self.graph if self.graph.out_degree(v) == 0 and self.graph.in_degree(v) > 0)

    @property
    def isolated_events(self) -> list[str]:
        return list(self._isolated)

    @cached_property
    def _isolated(self) -> tuple[str, ...]:
        return tuple(v for v, d in self.graph.degree if d == 0)

    @property
    def groups(self) -> dict[str, list[str]]:
        """Group name -> its events (events without a group are left out)."""
        return {group: list(events) for group, events in self._groups.items()}

    @cached_property
    def _groups(self) -> dict[str, tuple[str, ...]]:
        out: dict[str, list[str]] = {}
        for v, group in self.graph.nodes(data="group"):
            if group:
                out.setdefault(group, []).append(v)
        return {group: tuple(events) for group, events in out.items()}

    def group_graph(self, group: str) -> nx.DiGraph:
        """The subgraph of one group's events and the operations between them."""
        if group not in self.groups:
            raise ModelError(f"group={group!r}: no such group; known: {', '.join(self.groups) or 'none'}", key="group")
        return self.graph.subgraph(self.groups[group])

    def sync_pairs(self) -> list[tuple[str, str]]:
        """Each synchronisation as consecutive equal pairs (a, b): p(a) = p(b)."""
        return [(str(s["events"][i]), str(s["events"][i + 1])) for s in self.syncs for i in range(len(s["events"]) - 1)]

    def window_arcs(self) -> list[tuple[str, str, float]]:
        """(from, to, max_deg) of every window: p(to) - p(from) <= max_deg; a window in time (max_ms)
        as the angle the shaft turns in it at speed_rpm (a time becomes an angle at a speed)."""
        out = []
        for k, w in enumerate(self.windows):
            if "max_deg" in w:
                out.append((str(w["from"]), str(w["to"]), float(w["max_deg"])))
                continue
            if self.speed_rpm is None:
                raise ModelError(f"windows[{k}].max_ms needs speed_rpm (a time becomes an angle at a speed)",
                                 key="speed_rpm")
            out.append((str(w["from"]), str(w["to"]), time_floor_deg(float(w["max_ms"]), self.speed_rpm)))
        return out

    def time_windows(self) -> list[int]:
        """Indices of the windows given in time (max_ms): their angle grows with the speed."""
        return [k for k, w in enumerate(self.windows) if "max_ms" in w]

    def min_angles_deg(self) -> np.ndarray:
        """[phi] of every arc, in `arcs` order [deg] (a copy)."""
        return self._min_angles.copy()

    @cached_property
    def _min_angles(self) -> np.ndarray:
        phi = np.fromiter((d["min_deg"] for d in self._arc_data), dtype=float, count=len(self._arc_data))
        timed = self.time_arcs()
        if timed and self.speed_rpm is None:
            x, y = self.arcs[timed[0]]
            raise ModelError(f"operations[{x}->{y}].min_ms needs speed_rpm (a time becomes an angle at a speed)",
                             key="speed_rpm")
        if timed:
            phi[timed] = np.maximum(phi[timed], self.time_coeffs_deg_per_rpm()[timed] * self.speed_rpm)
        return phi

    def time_arcs(self) -> list[int]:
        """Indices (in `arcs` order) of the operations with a minimum duration `min_ms`."""
        return list(self._time_arcs)

    @cached_property
    def _time_arcs(self) -> tuple[int, ...]:
        return tuple(k for k, d in enumerate(self._arc_data) if d["min_ms"] is not None)

    def time_coeffs_deg_per_rpm(self) -> np.ndarray:
        """Per arc, the angle its `min_ms` asks for per rpm of main-shaft speed [deg/rpm] (0: none)."""
        out = np.zeros(len(self.arcs))
        for k in self.time_arcs():
            out[k] = time_floor_deg(self.arc_data(k)["min_ms"], 1.0)
        return out

    @property
    def stress_reference_rpm(self) -> float | None:
        """The speed the stress references hold at: stress_speed_rpm, else speed_rpm."""
        return self.speed_rpm if self.stress_speed_rpm is None else self.stress_speed_rpm

    def stress_at_MPa(self, k: int, t_deg, speed_rpm):
        """sigma_max of arc k's cam pair over t at speed n [MPa]: sigma_ref (t_ref / t) (n / n_ref)."""
        model = self.stress_models[self.arc_data(k)["stress"]]
        return stress_MPa(float(model["sigma_ref_MPa"]), float(model["t_ref_deg"]), t_deg) * speed_rpm \
            / self.stress_reference_rpm

    def stress_coeff_deg_per_rpm(self, k: int) -> float:
        """sigma_max(t, n) <= [sigma_H] as t >= coeff n: sigma_ref t_ref / ([sigma_H] n_ref)
        [deg/rpm], n_ref the speed the references hold at (`stress_reference_rpm`)."""
        if self.stress_reference_rpm is None:
            raise ModelError("stress_speed_rpm: the stress references need the speed they hold at",
                             key="stress_speed_rpm")
        model = self.stress_models[self.arc_data(k)["stress"]]
        return stress_bound_deg(float(model["sigma_ref_MPa"]), float(model["t_ref_deg"]),
                                self.sigma_H_limit_MPa) / self.stress_reference_rpm

    def stress_arcs(self) -> list[int]:
        """Indices (in `arcs` order) of the operations with a contact-stress model."""
        return list(self._model_arcs[0])

    def amplitude_arcs(self) -> list[int]:
        """Indices (in `arcs` order) of the operations with an amplitude model."""
        return list(self._model_arcs[1])

    @cached_property
    def _model_arcs(self):
        data = self._arc_data
        return ([k for k, d in enumerate(data) if d["stress"] is not None],
                [k for k, d in enumerate(data) if d["amplitude"] is not None])

    @cached_property
    def _arc_data(self) -> tuple[dict, ...]:
        """Each arc's attributes, in `arcs` order: one walk of the graph's edges for the views
        above (a walk through networkx's views per attribute cost ~0.3 s each at 3 x 10^5 arcs)."""
        return tuple(d for _, _, d in self.graph.edges(data=True))

    def stress_reference(self, k: int) -> tuple[float, float]:
        """(sigma_ref_MPa, t_ref_deg) of arc k's cam pair at the task's speed: the reference
        stress scaled by speed_rpm / stress_speed_rpm when both are given (sigma ~ n / t)."""
        model = self.stress_models[self.arc_data(k)["stress"]]
        scale = 1.0 if self.stress_speed_rpm is None or self.speed_rpm is None else self.speed_rpm / self.stress_speed_rpm
        return float(model["sigma_ref_MPa"]) * scale, float(model["t_ref_deg"])

    @cached_property
    def operation_names(self) -> dict[tuple[str, str], str]:
        """(from, to) -> ' "name"' for the operations the table names (the conflict messages' words)."""
        return {(x, y): f' "{name}"' for x, y, name in self.graph.edges(data="name") if name}

    @cached_property
    def motion_arcs(self) -> dict:
        """Arc index (in `arcs` order) -> its Motion (models/loom_motions.py), for the operations with a law."""
        return {k: d["motion"] for k, d in enumerate(self._arc_data) if d["motion"] is not None}

    def motion_values(self, t_deg, speed_rpm) -> dict:
        """Peak acceleration [m/s^2] and velocity [m/s] of every motion with a stroke, its angle
        t (per arc, `arcs` order) at speed n: accel_<x>_<y>_m_s2, velocity_<x>_<y>_m_s."""
        out = {}
        for k, motion in self.motion_arcs.items() if speed_rpm else ():
            if motion.stroke_mm is not None and t_deg[k] > 0:
                x, y = self.arcs[k]
                out[f"accel_{x}_{y}_m_s2"] = motion.peak_accel_m_s2(float(t_deg[k]), speed_rpm)
                out[f"velocity_{x}_{y}_m_s"] = motion.peak_velocity_m_s(float(t_deg[k]), speed_rpm)
        return out

    def arc_data(self, k: int) -> dict:
        x, y = self.arcs[k]
        return self.graph.edges[x, y]

    def lower_bounds_deg(self, stress_form: str = "exact") -> tuple[np.ndarray, list[str]]:
        """Each arc's smallest phase angle [deg] under every limit, and which limit sets it
        ("min_angle", "min_time", "contact_stress" or "amplitude")."""
        lb = self.min_angles_deg()
        why = ["min_angle"] * lb.size
        for k in self.time_arcs():
            if lb[k] > self.arc_data(k)["min_deg"]:
                why[k] = self.arc_data(k)["motion_limit"] or "min_time"
        for k in self.stress_arcs():
            bound = stress_bound_deg(*self.stress_reference(k), self.sigma_H_limit_MPa, stress_form)
            if bound > lb[k]:
                lb[k], why[k] = bound, "contact_stress"
        for k in self.amplitude_arcs() if self.has_linear_amplitude else ():
            bound = amplitude_bound_deg(self.amplitude_slope_mm_per_deg, self.amplitude_intercept_mm,
                                        self.amplitude_limit_mm)
            if bound > lb[k]:
                lb[k], why[k] = bound, "amplitude"
        return lb, why


def _events_of(operations) -> dict:
    """{event: {group, mechanism}} from the operations naming them, in order of first mention: an
    event takes the group (and mechanism) on which every operation ending at it agrees (the motion
    that brings it about), or, with none ending at it (the first event), every one starting at it;
    where they differ (a junction of groups, the last event) it takes none."""
    into, out = {}, {}                  # event -> [group, mechanism] agreed so far ("" when none)
    for op in operations:
        if not isinstance(op, dict) or "from" not in op or "to" not in op:
            continue                    # reported by the network's checks
        about = [str(op.get("group", "")), str(op.get("mechanism", ""))]
        for side, name in ((out, str(op["from"])), (into, str(op["to"]))):
            seen = side.get(name)
            if seen is None:
                side[name] = list(about)
            elif seen != about:
                seen[:] = [s if s == a else "" for s, a in zip(seen, about)]
    names = dict.fromkeys(name for op in operations if isinstance(op, dict) and "from" in op and "to" in op
                          for name in (str(op["from"]), str(op["to"])))
    return {name: {k: v for k, v in zip(("group", "mechanism"), into.get(name) or out[name]) if v} for name in names}


def task_operations(tasks) -> list[dict]:
    """A task table (activity on node: rows {task, min_ms or min_deg, after}) as the operations of
    its event network: each task t an operation t.start -> t.end of its duration; each task b it
    waits for an operation b.end -> t.start of 0 (cycles = k for "b@k", b of k cycles before);
    a task waiting for none of this cycle starts after the event `start`, one none waits for ends
    before `end`. Errors name the task's row."""
    _table(tasks, "tasks", list)
    rows = {}
    for j, row in enumerate(tasks):
        _entry(row, f"tasks[{j}]", _TASK_KEYS, required=("task",))
        name = str(row["task"]).strip()
        if not name or name in rows or name in ("start", "end"):
            why = "given twice" if name in rows else "a task needs a name other than start and end"
            raise ModelError(f"tasks[{j}].task={row['task']!r}: {why}", key=f"tasks[{j}].task")
        if "min_ms" not in row and "min_deg" not in row:
            raise ModelError(f"tasks[{name}]: give its duration, min_ms or min_deg", key=f"tasks[{name}]")
        rows[name] = row
    ops, waits, awaited = [], set(), set()
    for name, row in rows.items():
        ops.append({"from": f"{name}.start", "to": f"{name}.end", "name": str(row.get("name", name))}
                   | {k: row[k] for k in ("min_ms", "min_deg", "group", "mechanism", "mark", "why") if k in row})
        for before, k in _predecessors(row.get("after", ""), f"tasks[{name}].after", rows):
            ops.append({"from": f"{before}.end", "to": f"{name}.start", "min_deg": 0.0} | ({"cycles": k} if k else {}))
            if not k:
                waits.add(name)
                awaited.add(before)
    ops += [{"from": "start", "to": f"{t}.start", "min_deg": 0.0} for t in rows if t not in waits]
    ops += [{"from": f"{t}.end", "to": "end", "min_deg": 0.0} for t in rows if t not in awaited]
    return ops


def _predecessors(after, key, rows) -> list[tuple[str, int]]:
    """(task, cycles) of an `after` cell "a;b@1" (a list of such names too), each a task of the table."""
    if not isinstance(after, (str, list)) or (isinstance(after, list) and not all(isinstance(a, str) for a in after)):
        raise ModelError(f"{key}={after!r}: expected the tasks waited for, as 'a;b' (or 'b@k': k cycles before)",
                         key=key)
    out = []
    for item in (after.split(";") if isinstance(after, str) else after):
        name, _, k = item.strip().partition("@")
        name = name.strip()
        if not name:
            continue
        if name not in rows:
            raise ModelError(f"{key}: unknown task {name!r}; tasks: {some_of(rows, sep=', ')}", key=key)
        if k and not (k.strip().isdigit() and int(k) <= MAX_CYCLES):
            raise ModelError(f"{key}: {item.strip()!r}: the cycles after '@' must be a whole number in "
                             f"[0, {MAX_CYCLES}]", key=key)
        out.append((name, int(k) if k else 0))
    return out


def _split_windows(operations) -> tuple[list, list]:
    """(operations, windows): an operation's `max_deg` (its window, p(to) - p(from) <= max_deg)
    taken out as a window of its own, so the solvers see one kind of window."""
    ops, windows = [], []
    for op in operations:
        if isinstance(op, dict) and "max_deg" in op:
            op = dict(op)
            window = {"from": op.get("from"), "to": op.get("to"), "max_deg": op.pop("max_deg")}
            if op.get("mark", "given") != "given":
                window |= {"mark": op["mark"], "why": op.get("why", "")}
            windows.append(window)
        ops.append(op)
    return ops, windows


def _cycles(op, key) -> int:
    """An operation's `cycles` (0 when not given), checked: a whole number in [0, MAX_CYCLES]."""
    k = op.get("cycles", 0)
    if isinstance(k, bool) or not isinstance(k, (int, float)) or not float(k).is_integer() \
            or not 0 <= k <= MAX_CYCLES:
        raise ModelError(f"{key}.cycles={k!r}: a count of cycles must be a whole number in [0, {MAX_CYCLES}]",
                         key=f"{key}.cycles")
    return int(k)


def _floors(op, key) -> tuple[float, float | None]:
    """(min_deg, min_ms or None) of an operation row, checked (a timed operation may leave out min_deg)."""
    phi = _number(op.get("min_deg", 0.0), f"{key}.min_deg")
    if phi < 0:
        raise ModelError(f"{key}.min_deg={phi}: a minimum phase angle must be >= 0", key=f"{key}.min_deg")
    if phi > MAX_DEG:
        raise ModelError(f"{key}.min_deg={phi}: a minimum phase angle must be <= {MAX_DEG:g} deg",
                         key=f"{key}.min_deg")
    min_ms = op.get("min_ms")
    if min_ms is not None and not 0 <= _number(min_ms, f"{key}.min_ms") <= MAX_MS:
        raise ModelError(f"{key}.min_ms={min_ms}: a minimum duration must be in [0, {MAX_MS:g}] ms",
                         key=f"{key}.min_ms")
    return phi, None if min_ms is None else float(min_ms)


def _table(value, key, kind):
    if not isinstance(value, kind):
        raise ModelError(f"{key}: expected a {'table' if kind is dict else 'list of tables'}, got {value!r}", key=key)


def _entry(entry, key, allowed, required):
    if not isinstance(entry, dict):
        raise ModelError(f"{key}: expected a table, got {entry!r}", key=key)
    if entry.keys() <= allowed and all(k in entry for k in required) and "mark" not in entry:
        return                  # the common case, checked fast: 10^5-event networks pass through here
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise ModelError(f"{key}: unknown {', '.join(unknown)}; allowed: {', '.join(sorted(allowed))}", key=key)
    missing = [k for k in required if k not in entry]
    if missing:
        raise ModelError(f"{key}: missing {', '.join(missing)}", key=key)
    problem = provenance_problem(entry.get("mark", "given"), entry.get("why", ""))
    if problem:
        raise ModelError(f"{key}{'.' if problem.startswith('mark=') else ': '}{problem}", key=key)


def _known_event(g, name, key):
    if name not in g:
        raise ModelError(f"{key}: unknown event {name!r}; events: {some_of(g.nodes, sep=', ')}", key=key)


def _linked_event(g, name, key, also=frozenset()):
    _known_event(g, name, key)
    if g.degree(name) == 0 and name not in also:
        raise ModelError(f"{key}: event {name!r} has no operation; a window or sync needs events of the network",
                         key=key)


def _number(value, key):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ModelError(f"{key}={value!r}: expected a finite number", key=key)
    return float(value)
