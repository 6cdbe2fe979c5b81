"""Longest paths on the uniform constraints at a given cycle time T, watched for a positive
circuit of predecessor arcs: the pass of Dinkelbach's iteration (cycle_time.py)."""
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from mechopt.models.cyclogram_columns import topological_levels
from mechopt.solvers.cyclogram.cycle_uniform import Uniform
from mechopt.solvers.cyclogram.graph import ROUND_OFF, level_segments


class Circuits:
    """Longest paths on the uniform constraints at a given T from a virtual root (every time
    starts at 0), the predecessor arcs watched for a circuit. A round is one pass over the
    operations of one cycle (a DAG) in topological order, a level at a time (`graph.Levels`'s
    grouping), then the other arcs (recurrent operations, windows, syncs) relaxed together: a
    DAG settles in one pass, so the rounds number about the back arcs on a longest path, not the
    events. Every update must gain more than ROUND_OFF of the largest |weight|; with such strict
    updates a circuit of predecessor arcs has a positive sum (Cormen et al., Introduction to
    Algorithms, lemma 24.16: the arc into the circuit's last-updated event was set from an
    older, smaller time of its tail), so the first one seen is returned."""

    def __init__(self, u: Uniform, dag: int):
        self.u, self.n, self.dag = u, len(u.names), dag
        tails, heads = u.tails[:dag], u.heads[:dag]
        self.order, segments = level_segments(topological_levels(self.n, tails, heads), heads, self.n, reverse=False)
        self.t_fwd = tails[self.order]
        # per level: its slice, reduce starts, targets and each arc's group (its target's place)
        self.segments = [(a, b, starts, targets, np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, b - a])))
                         for a, b, starts, targets in segments]
        self.back = np.arange(dag, len(u.tails))
        self.passes = 0

    def longest(self, T: float):
        """(times p, None) when no circuit is positive at T; else (None, a positive circuit's arcs in order)."""
        self.passes += 1
        u, n = self.u, self.n
        w = u.weights(T)
        dist, pred = np.zeros(n), np.full(n, -1, dtype=np.int64)
        if not len(w):
            return dist, None
        eps = ROUND_OFF * max(1.0, float(np.abs(w).max()))
        w_fwd = w[:self.dag][self.order]
        back, bt, bh = self.back, u.tails[self.back], u.heads[self.back]
        for _ in range(len(back) + n + 2):
            gained = False
            for a, b, starts, targets, group in self.segments:
                gained |= _relax(dist, pred, self.t_fwd[a:b], w_fwd[a:b], starts, targets, group,
                                 self.order[a:b], eps)
            if len(back):
                cand = dist[bt] + w[back]
                gain = cand > dist[bh] + eps
                if gain.any():
                    # the best gaining arc into each event: sorted by (event, value), the last of each event
                    idx = np.flatnonzero(gain)
                    idx = idx[np.lexsort((cand[idx], bh[idx]))]
                    last = np.r_[bh[idx][1:] != bh[idx][:-1], True]
                    dist[bh[idx[last]]] = cand[idx[last]]
                    pred[bh[idx[last]]] = back[idx[last]]
                    gained = True
            if not gained:
                return dist, None
            circuit = _predecessor_circuit(n, u.tails, pred)
            if circuit is not None:
                return None, circuit
        raise Undecided(f"longest paths still improving after {len(back) + n + 2} rounds without a circuit "
                         f"of predecessors")


def _relax(dist, pred, ends, w, starts, targets, group, arcs, eps) -> bool:
    """One level: each target takes the best of its arcs' tail time + weight when that gains more
    than eps, its predecessor the first arc reaching it; whether any did."""
    cand = dist[ends] + w
    best = np.maximum.reduceat(cand, starts)
    gain = best > dist[targets] + eps
    if not gain.any():
        return False
    at_best = np.flatnonzero((cand == best[group]) & gain[group])
    first = at_best[np.r_[True, group[at_best][1:] != group[at_best][:-1]]]
    dist[targets[gain]] = best[gain]
    pred[targets[gain]] = arcs[first]
    return True


class Undecided(Exception):
    """Round-off stopped the iteration: no answer to trust."""


class StepLimit(Undecided):
    """The iteration's count of steps ran out (LIMIT)."""


def _predecessor_circuit(n, tails, pred) -> list[int] | None:
    """The arcs of a circuit of predecessor arcs (pred[v]: the arc into v), in order; None when none."""
    has = np.flatnonzero(pred >= 0)
    if not len(has):
        return None
    src = tails[pred[has]]
    graph = csr_matrix((np.ones(len(has)), (src, has)), shape=(n, n))
    count, label = connected_components(graph, directed=True, connection="strong")
    sizes = np.bincount(label, minlength=count)
    self_loop = has[src == has]
    cyclic = np.flatnonzero(sizes[label] > 1)
    start = int(cyclic[0]) if len(cyclic) else (int(self_loop[0]) if len(self_loop) else None)
    if start is None:
        return None
    arcs, v = [], start
    while True:                         # back along the predecessors until the start comes round
        k = int(pred[v])
        arcs.append(k)
        v = int(tails[k])
        if v == start:
            return arcs[::-1]
