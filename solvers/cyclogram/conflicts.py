"""An infeasible cyclogram named: a positive cycle of its difference constraints (operations with
their bounds, windows, syncs, the machine cycle), found by Bellman-Ford on the labelled
constraints, and up to MAX_CONFLICTS independent ones in one INFEASIBLE result."""
import math
from collections import deque

from mechopt.kit.errors import NAMED, some_of
from mechopt.kit.result import Result, Status

MAX_CONFLICTS = 4          # independent conflicting chains named in one INFEASIBLE result


def infeasible_result(chain, clock, diagnostics, note="") -> Result:
    """INFEASIBLE, naming the conflicting chain (a positive cycle of the constraints): its first
    NAMED constraints and events, and its length (a chain of 10^6 operations is counted, not listed)."""
    excess = math.fsum(w for _, _, w in chain)
    diagnostics = diagnostics | {"conflict_events": [v for v, _, _ in chain[:NAMED]], "conflict_length": len(chain),
                                 "conflict_excess_deg": excess}
    message = "infeasible: conflicting chain " + some_of(label for _, label, _ in chain)
    message += f" (needs {excess:.6g} deg more than its limits allow){note}"
    return clock.result(Status.INFEASIBLE, {}, message=message,
                        violated=tuple(label for _, label, _ in chain[:NAMED]), diagnostics=diagnostics)


def constraint_arcs(net, lb):
    """Every difference constraint as (u, v, w): p(v) - p(u) >= w [deg]."""
    arcs = [(x, y, float(lb[k])) for k, (x, y) in enumerate(net.arcs)]
    arcs += [(b, a, -w) for a, b, w in net.task.window_arcs()]
    arcs += [arc for a, b in net.task.sync_pairs() for arc in ((a, b, 0.0), (b, a, 0.0))]
    return arcs


def conflict_chain(net, max_conflicts: int = 1) -> list:
    """A positive cycle of the difference constraints (operations with their bounds, windows,
    syncs and the machine cycle), as [(event, label and bound [deg] of the arc leaving it)]: the
    bounds sum to more than 0 (a cycle cannot hold them, p(v) - p(u) >= w all round); empty when there is
    none. With max_conflicts > 1: a list of up to that many such chains, each sharing no
    constraint with those before (independent conflicts, every one named). Our own Bellman-Ford: networkx's find_negative_cycle can detect a cycle and then fail
    to extract it ("Negative cycle is detected but not found", networkx issue #5916)."""
    tight: dict = {}                       # (u, v) -> (w, label): the tightest constraint per pair

    def add(u, v, w, label):               # p(v) - p(u) >= w
        if (u, v) not in tight or w > tight[u, v][0]:
            tight[u, v] = (w, label)

    for k, (x, y) in enumerate(net.arcs):
        add(x, y, float(net.lb[k]), net.arc_label(k))
    for a, b, w in net.task.window_arcs():
        add(b, a, -w, f"window p({b}) - p({a}) <= {w:.6g} deg")
    for a, b in net.task.sync_pairs():
        add(a, b, 0.0, f"sync p({a}) = p({b})")
        add(b, a, 0.0, f"sync p({b}) = p({a})")
    if net.task.cycle_deg is not None:
        first, last = net.names[net.first], net.names[net.last]
        add(last, first, -net.task.cycle_deg, f"cycle p({last}) - p({first}) <= {net.task.cycle_deg:.6g} deg")
    arcs = [(u, v, w, label) for (u, v), (w, label) in tight.items()]
    chains = []
    for _ in range(max_conflicts):
        cycle = positive_cycle(arcs)
        if not cycle:
            break
        chains.append([(u, label, w) for u, _, w, label in cycle])
        used = {label for *_, label in cycle}
        arcs = [a for a in arcs if a[3] not in used]       # the next conflict shares no constraint
    return chains if max_conflicts > 1 else (chains[0] if chains else [])


def positive_cycle(arcs) -> list[tuple]:
    """A cycle of difference constraints (u, v, w, label), p(v) - p(u) >= w, whose w sum to more
    than 0, in order around the cycle; [] when there is none.

    Longest-path Bellman-Ford from a virtual root (every distance starts at 0), queue order; a
    relaxation counts only when it gains more than 1e-12 of the largest |w| (round-off, so a
    zero cycle of windows or syncs is not taken for a positive one): cycles above that are
    found. Every n relaxations the predecessor arcs are searched for a cycle, which (all
    relaxations strict) is a positive one; its sum is re-checked with math.fsum.
    """
    if not arcs:
        return []
    nodes = list(dict.fromkeys(v for a in arcs for v in a[:2]))
    index = {v: i for i, v in enumerate(nodes)}
    n = len(nodes)
    out = [[] for _ in range(n)]
    for k, (u, v, w, _) in enumerate(arcs):
        out[index[u]].append((index[v], float(w), k))
    eps = 1e-12 * max(1.0, max(abs(float(a[2])) for a in arcs))
    dist, pred = [0.0] * n, [-1] * n
    queue, queued = deque(range(n)), [True] * n
    relaxed, cap = 0, n * len(arcs) + n         # Bellman-Ford's bound: past it a cycle must exist
    while queue:
        u = queue.popleft()
        queued[u] = False
        for v, w, k in out[u]:
            if dist[u] + w > dist[v] + eps:
                dist[v], pred[v] = dist[u] + w, k
                relaxed += 1
                if relaxed % n == 0 or relaxed > cap:
                    cycle = _predecessor_cycle(arcs, index, pred)
                    if cycle:
                        return cycle
                if not queued[v]:
                    queue.append(v)
                    queued[v] = True
    return []


def _predecessor_cycle(arcs, index, pred):
    """A cycle of the predecessor arcs with a positive sum, in forward order, or []."""
    seen = [0] * len(pred)                       # 0 unseen, else the walk that reached it
    for start in range(len(pred)):
        walk, v = start + 1, start
        while v != -1 and not seen[v]:
            seen[v] = walk
            v = -1 if pred[v] < 0 else index[arcs[pred[v]][0]]
        if v == -1 or seen[v] != walk:
            continue
        cycle, u = [], v                         # v lies on a cycle of this walk: unroll it
        while True:
            k = pred[u]
            cycle.append(arcs[k])
            u = index[arcs[k][0]]
            if u == v:
                break
        cycle.reverse()
        if math.fsum(a[2] for a in cycle) > 0:
            return cycle
    return []
