"""Difference constraints p(v) - p(u) >= w solved on the graph: the event-time LP's
dual, a longest-path problem.

The operations form a DAG; windows, syncs and the machine cycle add arcs of the other sign
("back arcs"). `Levels` sorts the DAG's arcs by the topological level of their head once per
structure, so a longest-path pass is one numpy reduce per level (no Python loop over arcs);
with back arcs, Bellman-Ford runs in rounds: a DAG pass, then the back arcs relaxed. A longest
simple path uses each back arc at most once, so len(back) + 1 rounds settle every distance
unless a positive cycle exists: still improving after them is the proof of one (the cycle is
then named by `conflicts.positive_cycle` on the labelled constraints).

Why numpy over levels, and a compiled pass for large networks: on the layered 10^5-event
network (3 x 10^5 arcs, 1000 levels) a numpy pass costs ~10 us of Python per level and call,
~9 ms per pass, so one forward and one backward pass with the floats, the critical chain and
the duals took ~30 ms (the target: 20 ms). A compiled loop over the arcs in level order
(kernel.py, numba) takes ~2 ms per pass: with it the whole solve measured ~9 ms (best of 15 on
the shared 2-core machine; medians under load are in `mechopt bench cyclogram`). numba stays
optional (extra `fast`): it is imported only for networks of COMPILED_MIN_ARCS arcs and more
(no scene of the package), its compiled code cached on disk, and without it the numpy levels
give the same answers. scipy.sparse.csgraph has no DAG pass and its Bellman-Ford is O(V E).
"""
import math
from dataclasses import dataclass

import numpy as np

from mechopt.kit.cache import BuildCache
from mechopt.kit.result import Status
from mechopt.models.cyclogram_columns import topological_levels  # Kahn's levels (the model's check too)
from mechopt.solvers.cyclogram.kernel import COMPILED_AFTER_LEVEL_CALLS, COMPILED_MIN_ARCS, kernels
from mechopt.solvers.cyclogram.plain_pass import SMALL_MAX_ARCS, PlainPass, PositiveCycleFound

ROUND_OFF = 1e-12          # relative: an improvement below it (of the largest |w|) is round-off, not a cycle

_LEVELS = BuildCache("cyclogram.graph_levels", maxsize=8)


@dataclass(frozen=True)
class BackArcs:
    """Arcs outside the DAG (windows, syncs, the cycle): p(heads) - p(tails) >= weights."""
    tails: np.ndarray
    heads: np.ndarray
    weights: np.ndarray

    @classmethod
    def of(cls, arcs) -> "BackArcs":
        """From (tail, head, weight) index triples."""
        a = np.array(arcs, dtype=float).reshape(-1, 3)
        return cls(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), a[:, 2])

    def __len__(self):
        return len(self.tails)


NO_BACK_ARCS = BackArcs.of([])


class PositiveCycle(Exception):
    """The constraints hold a cycle whose bounds sum to more than 0: no schedule exists."""


def _relax(dist, weights, ends, segments):
    """One pass over the levels: each segment's targets take the best of their arcs' far ends + weights."""
    for a, b, starts, targets in segments:
        best = np.maximum.reduceat(dist[ends[a:b]] + weights[a:b], starts)
        dist[targets] = np.maximum(dist[targets], best)


class Levels:
    """A DAG's arcs grouped by topological level for vectorised longest-path passes.

    Forward: arcs sorted by (level of head, head); per level one `maximum.reduceat` gives every
    head of that level its longest distance. Backward: the same by the level of the tail."""

    def __init__(self, n: int, tails: np.ndarray, heads: np.ndarray, compiled: bool | None = None):
        """`compiled`: None, the compiled passes once the numpy ones have cost numba's import
        (`_passes`); True, at once when numba imports (a process that solves many times, the
        benchmarks); False, the numpy levels only (the reference)."""
        self.n, self.tails, self.heads = n, np.asarray(tails, np.int64), np.asarray(heads, np.int64)
        level = topological_levels(n, self.tails, self.heads)
        self.forward_order, self.forward_segments = level_segments(level, self.heads, n, reverse=False)
        self.backward_order, self.backward_segments = level_segments(level, self.tails, n, reverse=True)
        self._t_fwd, self._h_bwd = self.tails[self.forward_order], self.heads[self.backward_order]
        # large networks: the compiled passes (kernel.py), once the numpy passes have cost about
        # numba's import (`_level_calls`); a one-off solve of a shallow network never imports it
        self._compiled, self._level_calls = (None if compiled else compiled), 0
        self._depth = len(self.forward_segments) + len(self.backward_segments)
        if compiled:
            self._level_calls = COMPILED_AFTER_LEVEL_CALLS
            self._passes()

    def _passes(self):
        """The compiled (forward, backward) passes once worth their import, else None (numpy levels)."""
        if self._compiled is None and len(self.tails) >= COMPILED_MIN_ARCS:
            if self._level_calls < COMPILED_AFTER_LEVEL_CALLS:
                self._level_calls += self._depth // 2
            if self._level_calls >= COMPILED_AFTER_LEVEL_CALLS:
                self._compiled = kernels() or False
                if self._compiled:      # the arcs' ends in pass order: the loop reads them in sequence
                    self._fwd_run = (self.forward_order, self._t_fwd, self.heads[self.forward_order])
                    bwd = np.ascontiguousarray(self.backward_order[::-1])        # last level first
                    self._bwd_run = (bwd, self.tails[bwd], self.heads[bwd])
        return self._compiled

    @classmethod
    def of(cls, n, tails, heads) -> "Levels":
        """Built once per structure (kept in a BuildCache)."""
        key = (n, np.asarray(tails).tobytes(), np.asarray(heads).tobytes())
        return _LEVELS.get(key, lambda: cls(n, tails, heads))[0]

    def forward(self, dist: np.ndarray, w: np.ndarray) -> None:
        """dist[v] = max(dist[v], dist[u] + w) over every DAG path, in place."""
        if self._passes():
            self._compiled[0](dist, *self._fwd_run, np.asarray(w, dtype=float))
        else:
            _relax(dist, w[self.forward_order], self._t_fwd, self.forward_segments)

    def backward(self, dist: np.ndarray, w: np.ndarray) -> None:
        """dist[u] = max(dist[u], w + dist[v]) over every DAG path (distances *to* a target), in place."""
        if self._passes():
            self._compiled[1](dist, *self._bwd_run, np.asarray(w, dtype=float))
        else:
            _relax(dist, w[self.backward_order], self._h_bwd, self.backward_segments)

    def longest_from(self, source: int, w: np.ndarray, back: BackArcs = NO_BACK_ARCS) -> np.ndarray:
        """Longest distances from `source` to every event (-inf: unreachable) [deg]; PositiveCycle
        when the constraints hold one."""
        dist = np.full(self.n, -np.inf)
        dist[source] = 0.0
        return self._rounds(dist, w, back, self.forward, back.tails, back.heads)

    def longest_to(self, target: int, w: np.ndarray, back: BackArcs = NO_BACK_ARCS) -> np.ndarray:
        """Longest distances from every event to `target` (-inf: it cannot reach it) [deg]."""
        dist = np.full(self.n, -np.inf)
        dist[target] = 0.0
        return self._rounds(dist, w, back, self.backward, back.heads, back.tails)

    def has_positive_cycle(self, w: np.ndarray, back: BackArcs = NO_BACK_ARCS) -> bool:
        """Whether the constraints hold a positive cycle anywhere (every event starts at 0: a
        virtual root, so cycles not reachable from the first event count too)."""
        try:
            self._rounds(np.zeros(self.n), w, back, self.forward, back.tails, back.heads)
        except PositiveCycle:
            return True
        return False

    def _rounds(self, dist, w, back, dag_pass, frm, to):
        if not len(back):
            dag_pass(dist, w)
            return dist
        eps = ROUND_OFF * max(1.0, _largest_finite(w), _largest_finite(back.weights))
        # the back arcs relaxed once before the first pass too (any order of relaxations is Bellman-Ford's):
        # a cycle's closing arc from the start then needs one DAG pass, not two
        with np.errstate(invalid="ignore"):
            cand = dist[frm] + back.weights
        gain = cand > dist[to]
        np.maximum.at(dist, to[gain], cand[gain])
        for _ in range(len(back) + 2):
            dag_pass(dist, w)
            cand = dist[frm] + back.weights
            gain = cand > dist[to] + eps
            if not gain.any():
                return dist
            np.maximum.at(dist, to[gain], cand[gain])
        raise PositiveCycle


def _largest_finite(a) -> float:
    """max |a| over its finite entries (0 when none): two reductions, no copy, unless an entry is
    infinite (an arc cut to -inf for ranging)."""
    if not len(a):
        return 0.0
    top, low = float(a.max()), float(a.min())
    if math.isfinite(top) and math.isfinite(low):
        return max(abs(top), abs(low))
    finite = np.abs(a[np.isfinite(a)])
    return float(finite.max(initial=0.0))


def level_segments(level, ends, n, reverse):
    """Arcs sorted by (level of `ends`, end) and, per level, the slice, the reduce starts and the ends."""
    order = np.argsort(level[ends] * n + ends, kind="stable")
    sorted_ends = ends[order]
    lv = level[sorted_ends]
    bounds = np.searchsorted(lv, np.arange(int(lv.max(initial=0)) + 2))
    segments = []
    for depth in range(len(bounds) - 1):
        a, b = int(bounds[depth]), int(bounds[depth + 1])
        if a == b:
            continue
        e = sorted_ends[a:b]
        starts = np.flatnonzero(np.r_[True, e[1:] != e[:-1]])
        segments.append((a, b, starts, e[starts]))
    return order, segments[::-1] if reverse else segments


def tight_arcs(tails, heads, w, dist, tol) -> np.ndarray:
    """Indices of the arcs on which dist[head] = dist[tail] + w within tol (dist finite: an
    unreached end makes the difference -inf or NaN, never tight)."""
    with np.errstate(invalid="ignore"):
        return np.flatnonzero(dist[tails] + w - dist[heads] >= -tol)


WALK_MIN_EVENTS = 10_000    # from this many events a_path first tries the walk back (no sort, no sparse matrix)


def a_path(n, tails, heads, source, target) -> list[int] | None:
    """Indices of the arcs of one path source -> target (fewest arcs, breadth first); None when
    there is none. Parallel arcs: one of them. From WALK_MIN_EVENTS events: first a walk back from
    target along one arc into each event (tight arcs of a longest path reach the source that
    way), breadth first only when the walk ends elsewhere or loops (a zero cycle of syncs)."""
    if n >= WALK_MIN_EVENTS:
        path = _walk_back(n, tails, heads, source, target)
        if path is not None:
            return path
    pair = tails * n + heads
    pairs, first = np.unique(pair, return_index=True)
    pred = breadth_first_predecessors(n, pairs // n, pairs % n, source)
    if target != source and pred[target] < 0:
        return None
    nodes, v = [target], target
    while v != source:
        v = pred[v]
        nodes.append(v)
    nodes = np.array(nodes[::-1], dtype=np.int64)
    return first[np.searchsorted(pairs, nodes[:-1] * n + nodes[1:])].tolist()


def breadth_first_predecessors(n, tails, heads, source) -> list[int]:
    """Each event's predecessor breadth first from `source` (-9999: unreached, and the source),
    over distinct arcs sorted by (tail, head), an event's successors in increasing order: what
    scipy.sparse.csgraph.breadth_first_order gives on their CSR matrix, without scipy's import
    (~0.3 s of a small network's run)."""
    starts, succ = np.searchsorted(tails, np.arange(n + 1)).tolist(), heads.tolist()
    pred, seen, queue = [-9999] * n, [False] * n, [source]
    seen[source] = True
    for v in queue:                     # the list grows as it is walked: a FIFO queue
        for w in succ[starts[v]:starts[v + 1]]:
            if not seen[w]:
                seen[w], pred[w] = True, v
                queue.append(w)
    return pred


def _walk_back(n, tails, heads, source, target) -> list[int] | None:
    """Arcs of a path source -> target found by following one arc into each event back from
    target; None when the walk stops short of source or comes back on itself."""
    into = np.full(n, -1, dtype=np.int64)
    into[heads[::-1]] = np.arange(len(heads) - 1, -1, -1)      # the first arc listed into each event:
    # a DAG arc before a window's or a sync's (they come last), so the walk rarely meets a zero cycle
    path, v = [], int(target)
    while v != source:
        k = int(into[v])
        if k < 0 or len(path) >= n:
            return None
        path.append(k)
        v = int(tails[k])
    return path[::-1]


class HeldSpan:
    """One network's span held for what-ifs: a limit changed, the bounds
    re-solved by a fresh pass over the held levels with its own certificate (`solve`), and an
    LP's re-solve certified by it (`certify`).

    Why a fresh pass and not an incremental one (only the affected cone moves): on loom/group1
    (11 events) the whole pass is a few tens of microseconds, about what finding the cone costs;
    at 10^5 events a compiled pass is ~2 ms (kernel.py), and an incremental update would pay
    only when one limit moves a small cone, which the what-if slider does not promise. Up to
    plain_pass.SMALL_MAX_ARCS constraints the pass and its certificate run on Python lists
    (plain_pass.py: numpy's per-call overhead is the whole cost there), with the same answers."""

    def __init__(self, n: int, tails, heads, first: int, last: int, back: BackArcs = NO_BACK_ARCS,
                 plain: bool | None = None):
        """`plain`: None, the plain-Python pass up to SMALL_MAX_ARCS constraints (plain_pass.py);
        False, the numpy levels only (the reference); True, the plain pass at any size."""
        self.levels, self.first, self.last, self.back = Levels.of(n, tails, heads), first, last, back
        self.n = n
        self._tails = np.r_[self.levels.tails, back.tails]        # every constraint p(head) - p(tail) >= w
        self._heads = np.r_[self.levels.heads, back.heads]
        # a small network: the same passes on Python lists (plain_pass.py; numpy's call overhead is their cost)
        self._plain = (PlainPass(n, self.levels.forward_order, self.levels.tails, self.levels.heads, back, ROUND_OFF)
                       if (len(self._tails) <= SMALL_MAX_ARCS if plain is None else plain)
                       and np.isfinite(back.weights).all() else None)

    def _plain_bounds(self, lb) -> list | None:
        """lb as a list when the plain pass takes it: a small network, every bound finite (an infinite
        one, a cut for ranging, keeps numpy's NaN semantics); else None."""
        if self._plain is None:
            return None
        w = lb.tolist()
        total = sum(w)
        return w if total - total == 0.0 else None

    def solve(self, lb: np.ndarray, tol_deg: float = 1e-9):
        """(status, span [deg], event times) for bounds lb, certified by LP duality: the times
        meet every constraint (primal feasible) and a chain of constraints met with equality
        leads first -> last with bounds summing to the span (a dual solution of the same value),
        both to tol_deg per degree above 1. SOLVED when both hold, INACCURATE when not (round-off
        past tol_deg), INFEASIBLE (span and times None) on a positive cycle."""
        w = self._plain_bounds(lb)
        if w is not None:                                     # a small network: plain_pass.py
            status, span, p, walk = self._plain.solve(self.first, self.last, w, tol_deg)
            if walk is not None:
                return self._walk_failed(span, p, walk, tol_deg)
            return status, span, (None if p is None else np.array(p))
        try:
            p = self.levels.longest_from(self.first, lb, self.back)
        except PositiveCycle:
            return Status.INFEASIBLE, None, None
        span = float(p[self.last] - p[self.first])
        w = np.r_[lb, self.back.weights]
        with np.errstate(invalid="ignore"):                 # an unreached event: -inf - -inf, NaN
            slack = p[self._heads] - p[self._tails] - w
        tol = tol_deg * max(1.0, abs(span))
        feasible = bool(np.all(slack >= -tol))            # NaN (an unreached event) fails too
        tight = np.flatnonzero(slack <= tol)
        chain = _walk_back(self.n, self._tails[tight], self._heads[tight], self.first, self.last) if feasible else None
        if chain is None and feasible:                      # a zero cycle in the walk: breadth first
            chain = a_path(self.n, self._tails[tight], self._heads[tight], self.first, self.last)
        dual = None if chain is None else math.fsum(w[tight[chain]].tolist())
        ok = dual is not None and abs(dual - span) <= tol
        return (Status.SOLVED if ok else Status.INACCURATE), span, p

    def _walk_failed(self, span, p, w, tol_deg):
        """The plain pass's times feasible but its walk back failed (a zero cycle of syncs): the
        chain breadth first over the tight constraints, as `solve` on the levels does."""
        tol = tol_deg * max(1.0, abs(span))
        tight = np.asarray(self._plain.tight(p, w, tol), dtype=np.int64)
        path = a_path(self.n, self._tails[tight], self._heads[tight], self.first, self.last)
        ok = path is not None and abs(math.fsum([w[k] for k in tight[path].tolist()]) - span) <= tol
        return (Status.SOLVED if ok else Status.INACCURATE), span, np.array(p)

    def span(self, lb: np.ndarray) -> float:
        """The longest path first -> last with bounds lb [deg]; PositiveCycle when none exists."""
        w = self._plain_bounds(lb)
        if w is not None:
            try:
                return self._plain.longest_from(self.first, w)[self.last]
            except PositiveCycleFound:
                raise PositiveCycle from None
        return float(self.levels.longest_from(self.first, lb, self.back)[self.last])

    def certify(self, lb: np.ndarray, lp_span: float | None, tol_deg: float = 1e-9):
        """(SOLVED, the graph's span) when an LP's span (None: it said infeasible) agrees with the
        graph's to tol_deg per degree above 1; (INACCURATE, the graph's span, None when it
        finds a positive cycle) when not: a held HiGHS re-solve has returned "Optimal" with a
        worse objective (HiGHS issues 3194, 3294, 2026)."""
        try:
            mine = self.span(lb)
        except PositiveCycle:
            return (Status.INFEASIBLE if lp_span is None else Status.INACCURATE), None
        agree = lp_span is not None and abs(lp_span - mine) <= tol_deg * max(1.0, abs(mine))
        return (Status.SOLVED if agree else Status.INACCURATE), mine
