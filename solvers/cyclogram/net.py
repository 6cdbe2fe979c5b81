"""The cyclogram as the solvers read it: events and operations as index arrays, each operation's
lower bound and what sets it, windows, syncs and the machine cycle as back arcs, and the plan as
a table (one row per operation)."""
import numpy as np

from mechopt.kit.errors import ModelError
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram.graph import BackArcs


class Net:
    """The task as index arrays (events in graph order, isolated events left out)."""

    def __init__(self, task: Cyclogram, stress_form: str):
        self.stress_form = stress_form
        self._index_arrays(task)
        self.stress_rows = task.stress_arcs()
        refs = [task.stress_reference(k) for k in self.stress_rows]
        self.stress_ref = (np.array([r[0] for r in refs]), np.array([r[1] for r in refs]))
        self.amp_rows = task.amplitude_arcs()
        if self.amp_rows and not task.has_linear_amplitude:
            raise ModelError("amplitude_slope_mm_per_deg: the LP needs the linear amplitude law; with the lever's "
                             "exact law alone use loom.repair_cyclogram or cyclogram.max_machine_speed",
                             key="amplitude_slope_mm_per_deg")
        self.lb, self.lb_why = task.lower_bounds_deg(stress_form)

    @classmethod
    def structure(cls, task: Cyclogram) -> "Net":
        """The index arrays alone (events, arcs, ends, windows, syncs), for LPs with their own bounds."""
        net = cls.__new__(cls)
        net._index_arrays(task)
        return net

    @classmethod
    def of_arrays(cls, n: int, tails, heads, lb, first: int = 0, last: int | None = None) -> "Net":
        """A network given as index arrays alone, events 0..n-1 (a generated one, a benchmark's),
        with its operations' bounds `lb` [deg]: no task, no windows, syncs or limiting operation."""
        net = cls.__new__(cls)
        net.names, net.tails, net.heads, net.lb = range(n), tails, heads, lb
        net.first, net.last, net.limiting = first, n - 1 if last is None else last, None
        return net

    def _index_arrays(self, task):
        task.check_one_cycle("plan_cyclogram, max_machine_speed and repair_cyclogram")
        task.check_plain("plan_cyclogram (graph and lp), max_machine_speed and repair_cyclogram")
        self.task = task
        names, self.tails, self.heads = task.index_arrays       # cached on the task: built once per network
        self.names = list(names)
        self.arcs = task.arcs
        self.first, self.last = task.end_indices
        index = self.index if task.windows or task.syncs or task.limiting_op is not None else {}
        self.window_idx = [(index[a], index[b]) for a, b, _ in task.window_arcs()]
        self.sync_idx = [(index[a], index[b]) for a, b in task.sync_pairs()]
        lim = task.limiting_op
        self.limiting = None if lim is None else (index[str(lim[0])], index[str(lim[1])])

    @property
    def index(self) -> dict[str, int]:
        """Event -> its index, shared with the task (read only); built when a name is looked up."""
        return self.task.event_index

    def signature(self):
        """What the compiled problem depends on (everything except the Parameters' values)."""
        return (self.stress_form, len(self.names), self.tails.tobytes(), self.heads.tobytes(), self.first,
                self.last, tuple(self.stress_rows), self.stress_ref[0].tobytes(), self.stress_ref[1].tobytes(),
                tuple(self.amp_rows), tuple(self.window_idx), tuple(self.sync_idx), self.limiting,
                self.task.cycle_deg is not None)

    def arc_label(self, k):
        x, y = self.arcs[k]
        return f"t({x}->{y}) >= {self.lb[k]:.6g} deg ({self.lb_why[k]}){self.task.operation_names.get((x, y), '')}"


PER_NAME_MAX_OPS = 10_000   # above it, per-event and per-operation figures live in Result.arrays only


def per_name(net) -> bool:
    """Whether the values and diagnostics name every event and operation (p_*, t_*, float_deg, ...):
    up to PER_NAME_MAX_OPS operations. A timing table of 10^5 rows gets its figures as arrays: a
    dict entry per operation costs more than the solve (measured: 0.4 s of dicts against 10 ms)."""
    return len(net.tails) <= PER_NAME_MAX_OPS


def plan_arrays(net, values, diagnostics, p=None, floats=None) -> dict:
    """The plan as a table, one row per operation named `operation` ("3->7"): its start and end
    event times, its duration and its total float [deg] (`--csv`; for networks up to
    PER_NAME_MAX_OPS operations the values hold the same by name). `p` (event times in net order)
    and `floats` (per operation) default to the values' p_* and the diagnostics' float_deg."""
    if p is None:
        p = np.array([values[f"p_{v}_deg"] for v in net.names])
    arrays = {"operation": net.task.operation_labels, "start_deg": p[net.tails], "end_deg": p[net.heads],
              "duration_deg": p[net.heads] - p[net.tails]}
    if floats is None and isinstance(diagnostics.get("float_deg"), dict):    # else "not available" (round-off)
        floats = list(diagnostics["float_deg"].values())
    if floats is not None:
        arrays["float_deg"] = floats
    return arrays


def back_arcs(net, with_cycle=True):
    """Windows, syncs and (with_cycle) the machine cycle as BackArcs over event indices, with
    their kinds ("window", "sync", "cycle"), in that order (windows in task order)."""
    task, arcs, kinds = net.task, [], []
    for (a, b), (_, _, w) in zip(net.window_idx, task.window_arcs()):
        arcs.append((b, a, -w))
        kinds.append("window")
    for a, b in net.sync_idx:
        arcs += [(a, b, 0.0), (b, a, 0.0)]
        kinds += ["sync", "sync"]
    if with_cycle and task.cycle_deg is not None:
        arcs.append((net.last, net.first, -task.cycle_deg))
        kinds.append("cycle")
    return BackArcs.of(arcs), kinds
