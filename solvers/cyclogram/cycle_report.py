"""What the least cycle time reports beside T: the critical circuits at T* (ties named), each
operation's float, a task table's starts and floats, and a circuit in the designer's words."""
import math

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from mechopt.kit.errors import NAMED, some_of
from mechopt.solvers.cyclogram.graph import a_path


def why_no_cycle(u, circuit) -> str:
    D, K = math.fsum(u.d[circuit]), math.fsum(u.k[circuit])
    if K == 0:
        return f" spans no cycle (height 0) yet needs {D:.6g} {u.unit}"
    if D < 0:               # D - K T <= 0 holds for T <= D / K only
        return (f" holds at a cycle time of at most {D / K:.6g} {u.unit} (its angles grow with the cycle), less "
                f"than the machine's other circuits ask for")
    return (f" asks for {-K * 360:.6g} deg more than its cycles hold (height {K:.6g})"
            + (f" and {D:.6g} {u.unit} besides" if D > 0 else "") + ": a longer cycle only lengthens its angles")


def describe_circuit(u, circuit) -> dict:
    events = [u.names[u.tails[a]] for a in circuit]
    ops = [str(u.labels[a]) for a in circuit]
    return {"events": events[:NAMED], "operations": ops[:NAMED], "arcs": len(circuit),
            "cycles": _height(u, circuit), f"length_{u.unit}": math.fsum(u.d[circuit])}


def _height(u, circuit) -> int | float:
    """K(C): whole cycles, or (angles in a time-based network) a real number of them."""
    K = math.fsum(u.k[circuit])
    return int(round(K)) if abs(K - round(K)) <= 1e-12 else K


def circuit_text(u, circuit) -> str:
    return some_of((u.labels[a] for a in circuit), sep=", ")


def critical_of(u, p, T, circuit) -> dict:
    """The critical circuits at T*: the arcs tight for the times p (every critical circuit is a
    zero circuit there, so all of its arcs are tight) grouped in strongly connected components;
    a component holding a recurrent arc holds a critical circuit, one named per component."""
    if circuit is None:
        return {"critical_circuit": None, "critical_circuits": [], "critical_ops": []}
    w = u.weights(T)
    tol = 1e-9 * max(1.0, abs(T), float(np.abs(u.d).max(initial=0.0)))
    tight = np.flatnonzero(p[u.heads] - p[u.tails] - w <= tol)
    t_tails, t_heads = u.tails[tight], u.heads[tight]
    n = len(u.names)
    _, label = connected_components(csr_matrix((np.ones(len(tight)), (t_tails, t_heads)), shape=(n, n)),
                                    directed=True, connection="strong")
    inside = tight[label[t_tails] == label[t_heads]]
    components = list(dict.fromkeys(int(label[u.tails[a]]) for a in inside if u.k[a] > 0))
    first = int(label[u.tails[circuit[0]]])
    circuits = [describe_circuit(u, circuit)]
    for c in components:
        if c == first:
            continue
        arcs = inside[label[u.tails[inside]] == c]
        closing = int(arcs[u.k[arcs] > 0][0])
        back = a_path(n, u.tails[arcs], u.heads[arcs], int(u.heads[closing]), int(u.tails[closing]))
        circuits.append(describe_circuit(u, [closing] + [int(arcs[j]) for j in back]))
    ops = [str(u.labels[a]) for a in inside if a < u.operations and label[u.tails[a]] in components]
    return {"critical_circuit": circuits[0], "critical_circuits": circuits, "critical_ops": ops}


def floats_of(u, T) -> dict:
    """Per operation, -(its weight + the longest path back from its head to its tail) at T*: how
    far its duration may grow before a circuit through it closes (T rises, or, on a circuit of
    height 0, no T fits); None when no path leads back (on no circuit). A max-plus Floyd-Warshall."""
    n, w = len(u.names), u.weights(T)
    L = np.full((n, n), -np.inf)
    np.maximum.at(L, (u.tails, u.heads), w)
    np.fill_diagonal(L, np.maximum(np.diag(L), 0.0))          # the empty path (a station's own recurrence)
    for m in range(n):
        L = np.maximum(L, L[:, m, None] + L[None, m, :])
    out = {}
    for a in range(u.operations):
        back = L[u.heads[a], u.tails[a]]
        out[str(u.labels[a])] = None if not np.isfinite(back) else max(0.0, -(w[a] + back)) + 0.0
    return out


def per_task(task, u, p, floats, critical) -> dict:
    """Per task of a task table (`task_operations`): its start in the earliest schedule repeating
    every T*, its float (how far its duration may grow with T* unchanged; None: on no circuit, or
    not computed past cycle_time.FLOAT_MAX_EVENTS) and whether it lies on a critical circuit."""
    at = {v: i for i, v in enumerate(u.names)}
    out = {}
    for row in task.tasks:
        name = str(row["task"]).strip()
        op = f"{name}.start->{name}.end"
        out[name] = {f"start_{u.unit}": float(p[at[f"{name}.start"]]),
                     f"float_{u.unit}": None if floats is None else floats.get(op), "critical": op in critical}
    return out
