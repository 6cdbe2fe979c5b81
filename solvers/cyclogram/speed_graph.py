"""The highest speed on the graph (method "graph"): `SpeedGraph`, Newton on the positive
cycles of the parametric longest-path problem, its limiting cycle named and ranged, and its
certificate (n (1 - tol) fits, n (1 + tol) does not)."""
import math

import numpy as np

from mechopt.kit.result import Clock, Status
from mechopt.solvers.cyclogram.conflicts import positive_cycle
from mechopt.solvers.cyclogram.graph import Levels, a_path, tight_arcs
from mechopt.solvers.cyclogram.net import back_arcs


class Undecided(Exception):
    """A feasibility LP that was neither optimal nor infeasible: bisection cannot go on."""


GRAPH_TOL = 1e-10            # relative to the cycle [deg/deg]: a chain closing the cycle within it fits
UNBOUNDED_RPM = 1e12         # the parametric search starts here; a machine that still fits has no speed limit
NEWTON_MAX_STEPS = 200
RANGING_MAX_LIMITS = 8       # limits on the limiting cycle re-solved without them (one solve each)


class SpeedGraph:
    """The speed problem on the graph: arc k needs t >= max(phi_k, g_k n) (a + b n, piecewise),
    windows and syncs are back arcs, the cycle closes first -> last. Speed n fits when no cycle of
    these constraints has a positive sum.

    Why Newton on cycles (Dinkelbach's iteration for the parametric problem) and not Howard's
    policy iteration or bisection: each cycle's sum W_C(n) is convex, piecewise linear and
    non-decreasing in n, and the highest speed is the least root over the cycles. From a speed
    that does not fit, the positive cycle the longest-path pass finds has a root below it; at
    that root the cycle closes exactly. The next pass either finds the speed fits (the root is
    the answer, exact: no tolerance in n, unlike bisection's ~40 passes) or a cycle with a lower
    root. Each step is one numpy longest-path pass (graph.Levels) on the structure's levels;
    in practice 2-4 steps. Howard's algorithm needs a strongly connected policy graph and a
    ratio form (the max(phi, g n) arcs are not a ratio); it was not worth writing for 2-4 passes."""

    def __init__(self, task, net, phi, g):
        self.task, self.net, self.phi, self.g, self.cycle = task, net, phi, g, float(task.cycle_deg)
        self.levels = Levels.of(len(net.names), net.tails, net.heads)
        self.back, self.kinds = back_arcs(net, with_cycle=False)
        self.tol = GRAPH_TOL * max(1.0, self.cycle)
        self.passes = 0

    def bounds(self, n_rpm: float, g=None) -> np.ndarray:
        return np.maximum(self.phi, (self.g if g is None else g) * n_rpm)

    def positive_cycle_at(self, n_rpm: float, g=None):
        """None when speed n fits; else a positive cycle as [(kind, index)] in order around it,
        kind "op" (operation k), "back" (window or sync arc j) or "cycle"."""
        lb, net, back = self.bounds(n_rpm, g), self.net, self.back
        self.passes += 1
        if len(back) and self.levels.has_positive_cycle(lb, back):
            return self._windows_cycle(lb)
        dist = self.levels.longest_from(net.first, lb, back)
        if not np.isfinite(dist[net.last]) or dist[net.last] - self.cycle <= self.tol:
            return None
        m = len(lb)
        tails, heads = np.r_[net.tails, back.tails], np.r_[net.heads, back.heads]
        tight = tight_arcs(tails, heads, np.r_[lb, back.weights], dist, 1e-2 * self.tol)
        path = a_path(len(net.names), tails[tight], heads[tight], net.first, net.last)
        arcs = tight[np.asarray(path, dtype=np.int64)]
        return [("op", int(k)) if k < m else ("back", int(k - m)) for k in arcs] + [("cycle", 0)]

    def _windows_cycle(self, lb):
        """A positive cycle without the machine cycle (windows, syncs): conflicts.positive_cycle's own
        Bellman-Ford, which returns the cycle (the numpy pass only proves one exists)."""
        names, net, back = self.net.names, self.net, self.back
        arcs = [(x, y, float(lb[k]), ("op", k)) for k, (x, y) in enumerate(net.arcs)]
        arcs += [(names[u], names[v], float(w), ("back", j))
                 for j, (u, v, w) in enumerate(zip(back.tails.tolist(), back.heads.tolist(), back.weights.tolist()))]
        return [label for *_, label in positive_cycle(arcs)]

    def root(self, cycle, n_rpm: float, g=None) -> float:
        """The speed at which `cycle` (positive at n) closes exactly: sum max(phi, g n) + the back
        arcs' weights = 0, found piece by piece going down from n (convex: each piece's line
        meets 0 at or above the root; the piece that holds its own root is exact)."""
        g = self.g if g is None else g
        ops = np.array([k for kind, k in cycle if kind == "op"], dtype=np.int64)
        c = math.fsum(self.back.weights[k] for kind, k in cycle if kind == "back") \
            - (self.cycle if ("cycle", 0) in cycle else 0.0)
        phi, g = self.phi[ops], g[ops]
        for _ in range(len(ops) + 2):
            active = g * n_rpm > phi
            slope = math.fsum(g[active])
            if slope <= 0:
                return 0.0                  # positive at rest: the n = 0 test says so first
            new = -(c + math.fsum(phi[~active])) / slope
            # the piece's line lies under the convex sum, so the sum at `new` is >= 0; where it is 0
            # (to tol) `new` is the root, also when it falls on a kink g n = phi (an operation of a
            # fixed angle, min_deg = max_deg, with a time floor: the next piece has no slope)
            closes = c + math.fsum(np.maximum(phi, g * new)) <= self.tol
            if new >= n_rpm or closes or np.array_equal(g * new > phi, active):
                return min(new, n_rpm)
            n_rpm = new
        return n_rpm

    def highest_speed(self, g=None):
        """(n*, the limiting cycle, Newton steps); n* None: no limit grows with n (UNBOUNDED)."""
        n, steps = UNBOUNDED_RPM, 0
        cycle = self.positive_cycle_at(n, g)
        if cycle is None:
            return None, [], 0
        while steps < NEWTON_MAX_STEPS:
            if not cycle:
                raise Undecided(f"graph: a positive cycle at n = {n:.12g} rpm that Bellman-Ford cannot name "
                                 f"(round-off at the answer)")
            root = self.root(cycle, n, g)
            steps += 1
            if not root < n:
                raise Undecided(f"graph: the cycle found at n = {n:.12g} rpm does not close below it "
                                 f"(round-off at the answer)")
            following = self.positive_cycle_at(root, g)
            n = root
            if following is None:
                return n, cycle, steps
            cycle = following
        raise Undecided(f"graph: no answer after {NEWTON_MAX_STEPS} steps")

    def describe(self, cycle, n_rpm: float, why) -> list[str]:
        """The cycle in the designer's words: each operation with the law that sets it at n."""
        net, names, group = self.net, self.net.names, dict(self.task.graph.nodes(data="group"))
        out = []
        for kind, k in cycle:
            if kind == "op":
                x, y = net.arcs[k]
                speed_set = self.g[k] * n_rpm > self.phi[k]
                law = why[k] if speed_set else "min_angle"
                own = self.task.graph.edges[x, y].get("group")      # the operation's own, else its events'
                out.append(f"{law}[{x}->{y}] t >= {max(self.phi[k], self.g[k] * n_rpm):.6g} deg "
                           f"({own or group[x] or group[y] or '-'}"
                           + (f", {self.g[k]:.6g} deg/rpm)" if speed_set else ")")
                           + self.task.operation_names.get((x, y), ""))
            elif kind == "back":
                u, v, w = names[self.back.tails[k]], names[self.back.heads[k]], self.back.weights[k]
                out.append(f"sync p({u}) = p({v})" if self.kinds[k] == "sync"
                           else f"window p({u}) - p({v}) <= {-w:.6g} deg")
            else:
                out.append(f"cycle p({names[net.last]}) - p({names[net.first]}) <= {self.cycle:.6g} deg")
        return out

    def ranging(self, cycle, n_rpm: float, why) -> list[dict]:
        """Which limit to relax for the next rpm: per speed-set operation on the limiting cycle,
        d n / d g (rpm per deg/rpm of its slope), and the speed with that limit gone (the next
        cycle's root, one Newton solve) and the limit that then binds: the range over which
        relaxing it pays."""
        ops = [k for kind, k in cycle if kind == "op" and self.g[k] * n_rpm > self.phi[k]]
        slope = math.fsum(self.g[k] for k in ops)
        rows = []
        for k in ops[:RANGING_MAX_LIMITS]:
            x, y = self.net.arcs[k]
            g = self.g.copy()
            g[k] = 0.0
            n_next, nxt, _ = self.highest_speed(g)
            limits = [f"{why[j]}[{self.net.arcs[j][0]}->{self.net.arcs[j][1]}]" for kind, j in nxt
                      if kind == "op" and g[j] * n_next > self.phi[j]] if n_next is not None else []
            rows.append({"constraint": f"{why[k]}[{x}->{y}]", "deg_per_rpm": float(self.g[k]),
                         "rpm_per_deg_per_rpm": -n_rpm / slope if slope > 0 else -math.inf,
                         "rpm_without_it": n_next if n_next is not None else math.inf,
                         "then_limited_by": limits or ["cycle" if n_next is not None else "nothing: unbounded"]})
        return rows


def speed_on_graph(task, net, phi, g, why):
    """maximise n on the graph (SpeedGraph): INFEASIBLE when n = 0 does not fit."""
    clock = Clock()
    sg = SpeedGraph(task, net, phi, g)
    build_s = clock.elapsed()
    if sg.positive_cycle_at(0.0) is not None:
        return None, Status.INFEASIBLE, "", build_s, {"graph": sg}
    try:
        n_max, cycle, steps = sg.highest_speed()
    except Undecided as exc:
        return None, Status.FAILED, str(exc), build_s, {"graph": sg}
    if n_max is None:
        return None, Status.UNBOUNDED, f"graph: n = {UNBOUNDED_RPM:g} rpm still fits", build_s, {"graph": sg}
    extra = {"graph": sg, "newton_steps": steps, "limiting_cycle": sg.describe(cycle, n_max, why),
             "limiting_cycle_arcs": cycle}
    return n_max, Status.SOLVED, "", build_s, extra


def certify_on_graph(sg, n_max, tol):
    """'' when the graph says n_max (1 - tol) fits and n_max (1 + tol) does not; else why not."""
    if sg.positive_cycle_at(n_max * (1 - tol)) is not None:
        return f"certificate failed: n = {n_max * (1 - tol):.9g} rpm (just under the answer) does not fit the cycle"
    if sg.positive_cycle_at(n_max * (1 + tol)) is None:
        return f"certificate failed: n = {n_max * (1 + tol):.9g} rpm (just over the answer) still fits the cycle"
    return ""
