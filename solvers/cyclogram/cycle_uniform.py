"""A recurrent machine's limits as uniform constraints p(v) - p(u) >= d - k T (Hanen & Munier
1995, the basic cyclic scheduling problem): operations, recurrent operations (cycles = k),
windows and syncs, time-based (T in ms, an angle a fraction phi / 360 of the cycle) or
angle-based (T in deg); the least cycle time's network (cycle_time.py)."""
from dataclasses import dataclass

import numpy as np

from mechopt.kit.errors import ModelError, some_of
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.cyclogram_bounds import time_floor_deg


@dataclass(frozen=True)
class Uniform:
    """The cyclogram's constraints p(heads) - p(tails) >= d - k T as arrays over every event."""
    names: list
    tails: np.ndarray
    heads: np.ndarray
    d: np.ndarray
    k: np.ndarray
    labels: np.ndarray       # how the designer names each arc ("a->b", "a->b[+1]", "window ...", "sync ...")
    operations: int          # arcs [0, operations) are operations (ordinary, then recurrent); windows and syncs follow
    unit: str                # "ms" (time-based operations) or "deg"

    def weights(self, T: float) -> np.ndarray:
        return self.d - self.k * T


def uniform_constraints(task: Cyclogram) -> Uniform:
    """The task's operations, recurrent operations, windows and syncs as uniform constraints. Time-
    based when an operation gives min_ms and the task no speed_rpm (T in ms; an angle a fraction
    phi / 360 of the cycle, module docstring; no stress or amplitude, whose angles are not
    fractions of T); else angle-based, each operation at its bound of every limit (a min_ms as the
    angle the shaft turns in it at speed_rpm)."""
    dag_names, dag_tails, dag_heads = task.index_arrays     # cached on the task: the one cycle's operations
    names = list(dag_names) + task.isolated_events             # events of recurrent operations alone come last
    index = task.event_index | {v: len(dag_names) + i for i, v in enumerate(task.isolated_events)}
    rec = task.recurrences
    timed = (bool(task.time_arcs()) or any(op["min_ms"] is not None for op in rec)) and task.speed_rpm is None
    if timed:
        _check_time_based(task)
        d_ops, k_ops, more = _time_based_operations(task)
        windows = [(str(w["from"]), str(w["to"]), *((-float(w["max_ms"]), 0.0) if "max_ms" in w
                                                     else (0.0, float(w["max_deg"]) / 360.0)),
                    f"{w.get('max_ms', w.get('max_deg')):.6g} {'ms' if 'max_ms' in w else 'deg'}")
                   for w in task.windows]
    else:
        d_ops, k_ops = task.lower_bounds_deg("exact")[0], np.zeros(len(dag_tails))
        d_rec = [op["min_deg"] if op["min_ms"] is None else max(op["min_deg"], time_floor_deg(op["min_ms"], task.speed_rpm))
                 for op in rec]
        more = [(op["from"], op["to"], d, op["cycles"], _recurrent_label(op)) for op, d in zip(rec, d_rec)]
        windows = [(a, b, -w, 0.0, f"{w:.6g} deg") for a, b, w in task.window_arcs()]
    operations = len(dag_tails) + len(more)
    more += [(b, a, d, k, f"window p({b}) - p({a}) <= {text}") for a, b, d, k, text in windows]
    more += [(u, v, 0.0, 0, f"sync p({a}) = p({b})") for a, b in task.sync_pairs() for u, v in ((a, b), (b, a))]
    tails = np.r_[dag_tails, np.array([index[m[0]] for m in more], dtype=np.int64)]
    heads = np.r_[dag_heads, np.array([index[m[1]] for m in more], dtype=np.int64)]
    d = np.r_[d_ops, np.array([m[2] for m in more], dtype=float)]
    k = np.r_[k_ops, np.array([m[3] for m in more], dtype=float)]
    labels = np.concatenate([task.operation_labels, np.array([m[4] for m in more], dtype=str)])
    return Uniform(names, tails, heads, d, k, labels, operations, "ms" if timed else "deg")


def _recurrent_label(op) -> str:
    return f"{op['from']}->{op['to']}[+{op['cycles']}]"


def _time_based_operations(task):
    """(d, k of the one cycle's operations, [recurrent and extra arcs]) in ms: a duration is d = min_ms,
    an angle phi is d = 0, k = cycles - phi / 360; an operation with both gets a second arc (its floor
    is the larger of the two at every T)."""
    d_ops, k_ops, more = [], [], []
    for x, y, data in task.graph.edges(data=True):      # `arcs` order
        phi, ms = data["min_deg"], data["min_ms"]
        d_ops.append(0.0 if ms is None else ms)
        k_ops.append(-phi / 360.0 if ms is None else 0.0)
        if ms is not None and phi > 0:
            more.append((x, y, 0.0, -phi / 360.0, f"{x}->{y}"))
    for op in task.recurrences:
        label, k = _recurrent_label(op), float(op["cycles"])
        if op["min_ms"] is not None:
            more.append((op["from"], op["to"], op["min_ms"], k, label))
        if op["min_ms"] is None or op["min_deg"] > 0:
            more.append((op["from"], op["to"], 0.0, k - op["min_deg"] / 360.0, label))
    return np.array(d_ops, dtype=float), np.array(k_ops, dtype=float), more


def _check_time_based(task):
    """A time-based network's angles are fractions of its cycle; a stress or rebound bound is an angle
    at a speed, not a fraction of T: refused, named."""
    mixed = [f"operations[{x}->{y}].stress" for x, y in (task.arcs[k] for k in task.stress_arcs())]
    mixed += [f"operations[{x}->{y}].amplitude" for x, y in (task.arcs[k] for k in task.amplitude_arcs())]
    if mixed:
        raise ModelError(f"{mixed[0]}: the least cycle time of a time-based network (min_ms) takes durations "
                         f"and angles (fractions of the cycle), not a bound set at a speed (also "
                         f"{some_of(mixed[1:], sep=', ') or 'nothing else'}); give speed_rpm, or use "
                         f"cyclogram.max_machine_speed", key=mixed[0].split(".")[0])
