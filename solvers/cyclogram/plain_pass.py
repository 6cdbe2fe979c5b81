"""The held span's what-if on a small network: plain Python lists in topological order.

Why: on loom/group1 (10 events, 11 operations) a numpy pass pays ~1-2 us of call overhead per
level and per array operation, the whole of its cost at that size (a one-limit what-if took
~25 us where a loop over the arcs in topological order takes ~3 us). Below SMALL_MAX_ARCS
constraints `graph.HeldSpan` runs this pass instead: the same relaxations in the same order of
levels (`graph.Levels`' forward order, a level's heads after every tail of theirs), the back arcs
relaxed together from the times before them with the same round-off threshold and round count
(`graph.Levels._rounds`), so the times are the numpy pass's bit for bit; the certificate
(`HeldSpan.solve`: every slack above -tol, a walk back along tight constraints) is the same too.
"""
import math

from mechopt.kit.result import Status

# constraints (operations + back arcs) up to which the plain pass is taken. Measured (a certified
# solve, medians): on random layered networks of 6-9 levels the plain pass is the faster up to
# ~300 constraints (38 arcs: 7 against 34 us; 265: 37 against 38 us; 539: 103 against 85 us)
SMALL_MAX_ARCS = 200
NEG_INF = -math.inf


class PositiveCycleFound(Exception):
    """Still improving after len(back) + 2 rounds: a positive cycle (graph.PositiveCycle's cause)."""


class PlainPass:
    """One network's constraints as Python lists: the DAG's arcs in forward level order (each as
    (tail, head, index into the bounds)), the back arcs (tail, head, weight) and every constraint
    (tail, head) in `HeldSpan`'s order (operations, then back arcs) for the certificate."""

    def __init__(self, n, forward_order, tails, heads, back, round_off):
        self.n = n
        t, h = tails.tolist(), heads.tolist()
        self.dag = [(t[k], h[k], k) for k in forward_order.tolist()]
        self.back = list(zip(back.tails.tolist(), back.heads.tolist(), back.weights.tolist()))
        self.back_w = back.weights.tolist()
        self.ends = list(zip(t + back.tails.tolist(), h + back.heads.tolist()))
        self.into = [[] for _ in range(n)]          # per event (index, tail) of the constraints into it, by index
        for k, (_, head) in enumerate(self.ends):
            self.into[head].append((k, self.ends[k][0]))
        self.round_off = round_off
        self.back_big = max((abs(x) for x in self.back_w if math.isfinite(x)), default=0.0)

    def longest_from(self, source: int, w: list) -> list:
        """Longest distances from `source` (-inf: unreached) for bounds w (a list, finite);
        PositiveCycleFound on a positive cycle."""
        dist = [NEG_INF] * self.n
        dist[source] = 0.0
        dag, back = self.dag, self.back
        if not back:
            for t, h, k in dag:
                c = dist[t] + w[k]
                if c > dist[h]:
                    dist[h] = c
            return dist
        eps = self.round_off * max(1.0, max(map(abs, w), default=0.0), self.back_big)
        self._relax_back(dist, 0.0)
        for _ in range(len(back) + 2):
            for t, h, k in dag:
                c = dist[t] + w[k]
                if c > dist[h]:
                    dist[h] = c
            if not self._relax_back(dist, eps):
                return dist
        raise PositiveCycleFound

    def _relax_back(self, dist, eps) -> bool:
        """Every back arc from the times before any of them (numpy's batch); whether one gained more than eps."""
        gains = [(h, c) for t, h, wt in self.back if (c := dist[t] + wt) > dist[h] + eps]
        for h, c in gains:
            if c > dist[h]:
                dist[h] = c
        return bool(gains)

    def solve(self, first: int, last: int, w: list, tol_deg: float):
        """`HeldSpan.solve` on the lists: (status, span, times as a list, None) or, when the walk
        along tight constraints fails with the times feasible (a zero cycle of syncs), (None, span,
        times, every constraint's bound) for the caller's breadth-first search. The certificate:
        every slack p(head) - p(tail) - w at least -tol (NaN, an unreached event, fails), and the
        chain walked back from last along the first tight constraint (slack <= tol, by index) into
        each event (`graph._walk_back` on the tight constraints) sums to the span within tol."""
        try:
            p = self.longest_from(first, w)
        except PositiveCycleFound:
            return Status.INFEASIBLE, None, None, None
        span = p[last] - p[first]
        if self.back_w:
            w = w + self.back_w
        tol = tol_deg * max(1.0, abs(span))
        neg = -tol
        for (t, h), wk in zip(self.ends, w):
            if not p[h] - p[t] - wk >= neg:
                return Status.INACCURATE, span, p, None
        chain, v, into, n = [], last, self.into, self.n
        while v != first:
            for k, t in into[v]:
                if p[v] - p[t] - w[k] <= tol:
                    break
            else:
                return None, span, p, w
            if len(chain) >= n:
                return None, span, p, w
            chain.append(w[k])
            v = t
        ok = abs(math.fsum(chain) - span) <= tol
        return (Status.SOLVED if ok else Status.INACCURATE), span, p, None

    def tight(self, p: list, w: list, tol: float) -> list:
        """The constraints with slack at most tol, by index."""
        return [k for k, ((t, h), wk) in enumerate(zip(self.ends, w)) if p[h] - p[t] - wk <= tol]
