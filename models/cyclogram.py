"""The network cyclogram of a cyclic machine: events, operations and their limits (the model of
Podgorny et al. 2018, paper 004; its STB loom is this wing's case, cases/loom/).

Vertices are events (characteristic positions of mechanisms) with times p; arcs are operations
(x, y) with phase angle t(x, y) = p(y) - p(x) (the paper: "the difference of the event times").
Each operation carries a minimum angle [phi] or a least duration (min_ms), optionally a motion
(models/cyclogram_motions.py) and, as on the STB loom, a contact-stress model of its cam pair and an
amplitude model of its working member (the loom's laws, models/loom_limits.py). Angles are machine
degrees of the main shaft, not radians: the paper's coefficients (mm/deg) and every cyclogram are
in degrees. An operation with `cycles` = k ends at an event of k cycles later (a recurrent machine).

Every limit is a lower bound on the phase angle, so the cyclogram is a system of difference
constraints p(y) - p(x) >= lb(x, y); windows (p(y) - p(x) <= w) and synchronisations
(p(x) = p(y)) add arcs of the other sign. `lower_bounds_deg` gives lb for any limit values.

Effects a scene may call for (the STB loom's limits):

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
n; the stress references (sigma_ref at t_ref) hold at `stress_speed_rpm` (default n). An operation
may also need a time rather than an angle (`min_ms`, e.g. the loom's microshuttle flight): at n it
spans at least 6 n T deg (360 deg per 60/n s), so its lower bound is max(min_deg, 0.006 n min_ms).

The task is one dataclass of parts, each one job: cyclogram_tables (the tables a scene gives, their
columns and checks, task tables), cyclogram_network (the graph built and checked), cyclogram_views
(index arrays and labels for the solvers), cyclogram_bounds (each operation's least angle).
"""
from dataclasses import dataclass, field
from functools import cached_property
from typing import Annotated, ClassVar

import numpy as np
from annotated_types import Gt, Le, Lt

from mechopt.kit.errors import ModelError
from mechopt.kit.settings import check_fields
from mechopt.models.cyclogram_bounds import Bounds
from mechopt.models.cyclogram_columns import PLAIN_COLUMNS
from mechopt.models.cyclogram_motions import (
    CLEARANCE_COLUMNS,
    LEAST_ANGLE,
    OBJECTIVES,
    Clearance,
    clearance_rows,
    objective_weights,
    operation_index,
)
from mechopt.models.cyclogram_network import Network
from mechopt.models.cyclogram_tables import (
    MAX_CYCLES,
    MAX_DEG,
    MAX_MPA,
    MAX_RPM,
    OPERATION_COLUMNS,
    SYNC_COLUMNS,
    TASK_COLUMNS,
    WINDOW_COLUMNS,
    check_table,
    events_of,
    split_windows,
    task_operations,
)
from mechopt.models.cyclogram_views import Views
from mechopt.models.effects import Effect
from mechopt.models.loom_limits import STRESS_FORMS, lever_stop
from mechopt.models.stop_impact import LeverStop


@dataclass(frozen=True)
class Cyclogram(Network, Views, Bounds):
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
    (`recurrences`; the least cycle time, `cyclogram.least_cycle_time`).
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

    Motions (models/cyclogram_motions.py): an operation may carry `law`, `stroke_mm`, `direction` and
    `max_accel_m_s2` / `max_velocity_m_s` (a least duration, folded into its min_ms);
    `clearances` [{operation, at, relation, other, other_at, cycles?}] (a CSV too) between two
    motions; `maximize = "least_angle"` over `least_angle_of` (operation names or "from->to"), or
    `"least_scaled_angle"` (the largest peak acceleration of that set minimised);
    `span_within_cycle` (default true: p(last) - p(first) <= cycle_deg; false when one cycle's
    motions run into the next). These three are rows of cyclogram.plan_motions' LP only.
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
    # motions (models/cyclogram_motions.py): clearances between them, and the objective over their angles
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
    # a plain operations table (names, angles, notes: no column beyond PLAIN_COLUMNS, so no marked
    # input) is read as whole columns: its network as arrays (models/cyclogram_columns.py), no object
    # per row; any other as rows
    COLUMNAR_TABLES: ClassVar[dict] = {"operations": PLAIN_COLUMNS}
    CSV_TABLES: ClassVar[dict] = {"operations": (("from", "to"), OPERATION_COLUMNS),
                                  "windows": (("from", "to"), WINDOW_COLUMNS),
                                  "syncs": (("events",), SYNC_COLUMNS), "tasks": (("task",), TASK_COLUMNS),
                                  "clearances": (("operation", "other"), CLEARANCE_COLUMNS)}

    def __post_init__(self):
        check_fields(self)
        self._take_columns()            # a plain CSV table: its network straight from the columns
        if self.tasks:                  # a task table becomes the operations it stands for
            ops = task_operations(self.tasks)
            if self.operations and self.operations != ops:
                raise ModelError("tasks: a network is given by its operations or by its tasks, not both", key="tasks")
            object.__setattr__(self, "operations", ops)
        elif not self.operations:
            raise ModelError("operations: missing (give the operations, or a task table `tasks`)", key="operations")
        if self._columnar is None:
            check_table(self.operations, "operations", list)
        check_table(self.events, "events", dict)
        if not self.events and self._columnar is None:  # events named by the operations need no table of their own
            object.__setattr__(self, "events", events_of(self.operations))
        if isinstance(self.syncs, list) and any(isinstance(s, dict) and isinstance(s.get("events"), str)
                                                for s in self.syncs):      # a CSV row names its events "a;b"
            object.__setattr__(self, "syncs", [s | {"events": [e.strip() for e in s["events"].split(";")]}
                                               if isinstance(s, dict) and isinstance(s.get("events"), str) else s
                                               for s in self.syncs])
        _ = self.recurrences    # checked before a window is split off an operation (none on a recurrent one)
        if self._columnar is None and any(isinstance(op, dict) and "max_deg" in op for op in self.operations):
            operations, windows = split_windows(self.operations)
            object.__setattr__(self, "operations", operations)
            object.__setattr__(self, "windows", list(self.windows) + windows)
        if self.lever is not None:
            _ = self.lever_model    # builds and validates the lever (cached)
        self._check_network()           # builds and validates the network (cached)
        self._check_bounds()
        self._check_motions()

    def _check_motions(self):
        """The clearances and the objective over the motions' angles, resolved (cached) and checked."""
        _ = self.clearance_rows
        if self.maximize is not None and self.maximize not in OBJECTIVES:
            raise ModelError(f"maximize={self.maximize!r}: allowed {', '.join(OBJECTIVES)}", key="maximize")
        if (self.maximize in OBJECTIVES) != bool(self.least_angle_of):
            raise ModelError(f"least_angle_of: maximize = {self.maximize or LEAST_ANGLE!r} needs the operations it "
                             f"takes the least angle of, and they need it", key="least_angle_of")
        _ = self.objective_weights
        if not isinstance(self.span_within_cycle, bool):
            raise ModelError(f"span_within_cycle={self.span_within_cycle!r}: allowed true, false", key="span_within_cycle")
        if self.clearance_rows and any(c.cycles for c in self.clearance_rows) and self.cycle_deg is None:
            raise ModelError("cycle_deg: a clearance with the other operation of a later cycle needs the cycle",
                             key="cycle_deg")

    @cached_property
    def clearance_rows(self) -> tuple[Clearance, ...]:
        """The `clearances` table resolved: operations as arc indices, displacements as angle fractions."""
        if isinstance(self.clearances, list) and not self.clearances:
            return ()
        names = [d["name"] for d in self._arc_data]
        return clearance_rows(self.clearances, self.arcs, names, self.motion_arcs, MAX_CYCLES)

    @cached_property
    def objective_weights(self) -> tuple[float, ...]:
        """w_k of each of least_angle_arcs: t_k >= z w_k (models/cyclogram_motions.objective_weights)."""
        return objective_weights(self.maximize, self.least_angle_arcs, self.motion_arcs, self.least_angle_of)

    @cached_property
    def least_angle_arcs(self) -> tuple[int, ...]:
        """Arc indices of the operations whose least angle `maximize = "least_angle"` maximises."""
        if not isinstance(self.least_angle_of, list):
            raise ModelError(f"least_angle_of={self.least_angle_of!r}: a list of operations (names or from->to)",
                             key="least_angle_of")
        if not self.least_angle_of:
            return ()
        names = [d["name"] for d in self._arc_data]
        return tuple(operation_index(self.arcs, names, ref, f"least_angle_of[{j}]")
                     for j, ref in enumerate(self.least_angle_of))

    def check_plain(self, solver: str) -> None:
        """ModelError when the task asks for what only cyclogram.plan_motions solves (clearances, the least angle)."""
        if self.clearances or self.maximize is not None or not self.span_within_cycle:
            key = "clearances" if self.clearances else ("maximize" if self.maximize else "span_within_cycle")
            raise ModelError(f"{key}: not solved by {solver} (difference constraints only); a clearance (a row of the event-time "
                             f"LP in two operations' angles), maximize = {LEAST_ANGLE!r} and span_within_cycle = false "
                             f"are solved by cyclogram.plan_motions", key=key)

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
