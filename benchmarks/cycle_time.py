"""The least cycle time of a large recurrent machine on the graph against its LP certificate.

A random recurrent network (`recurrent_network`): a layered DAG of one cycle's operations
(`loom.layered`, height 0, U(0, 30) deg) and recurrent operations of heights 1 ... 3 from a later
event back to an earlier one (U(0, 30) deg, one per ten events), as a designer's table would give
them (a `Cyclogram` of operation rows). Every circuit holds a recurrent operation, so the least
cycle time is finite and positive.

In one process, interleaved, medians of `repeats` (CPU seconds of the process, time.process_time: the machine is shared):

* ``graph``  `cyclogram.least_cycle_time(task)`: the uniform constraints, Dinkelbach's
             iteration on the graph, the critical circuits (the whole solver, as a scene runs it);
* ``LP``     `cycle_lp.cycle_time_lp(u)`: the LP in (p, T), minimise T, by cvxpy and HiGHS
             (the certificate `check = true` solves beside the graph), on the same constraints.

The issue's target: graph >= 20x faster than the LP, the same T to 1e-9 relative (asserted: a
different answer is an error, not a slower row). Run: `mechopt bench cycle_time` or
`python -m mechopt.benchmarks.cycle_time [events]`. Timings live here only.
"""
import statistics
import sys
import time

import numpy as np

from mechopt.benchmarks.loom import layered

__all__ = ["cli", "compare", "recurrent_network"]

EVENTS = 100_000
QUICK_EVENTS = 10_000
RATIO_TARGET = 20.0          # graph at least this many times faster than the LP certificate
SAME_RTOL = 1e-9             # the two least cycle times, relative
RECURRENT_PER_EVENT = 0.1    # recurrent operations per event
LP_ONCE_EVENTS = 100_000     # from here the LP is solved once (minutes of CPU each; the graph still 3x)
MAX_HEIGHT = 3


def recurrent_network(n: int, seed: int = 0):
    """A `Cyclogram` of about n events: the layered DAG's operations (min_deg) and n / 10 recurrent
    ones, each from an event back to one at most five layers (of 100) earlier, cycles 1 ... 3.
    Short back reaches keep the critical circuit local, as in a machine's stations."""
    from mechopt.models.cyclogram import Cyclogram
    tails, heads, angles = layered(n, seed=seed)
    n = int(heads.max()) + 1
    rng = np.random.default_rng(seed + 1)
    m = int(RECURRENT_PER_EVENT * n)
    later = rng.integers(1, n, m)
    earlier = np.maximum(later - rng.integers(1, 500, m), 0)
    cycles = rng.integers(1, MAX_HEIGHT + 1, m)
    rec = rng.uniform(0.0, 30.0, m)
    names = [f"e{i}" for i in range(n)]
    ops = [{"from": names[a], "to": names[b], "min_deg": w}
           for a, b, w in zip(tails.tolist(), heads.tolist(), angles.tolist())]
    seen = set()
    for a, b, k, w in zip(later.tolist(), earlier.tolist(), cycles.tolist(), rec.tolist()):
        if (a, b, k) not in seen:             # one recurrent row per (from, to, cycles)
            seen.add((a, b, k))
            ops.append({"from": names[a], "to": names[b], "min_deg": w, "cycles": k})
    return Cyclogram(operations=ops)


def _timed(call):
    start = time.process_time()
    out = call()
    return time.process_time() - start, out


def compare(n: int = EVENTS, repeats: int = 3, progress=None, lp_repeats: int | None = None) -> dict:
    """{"graph_s", "lp_s" (medians), "T_graph", "T_lp", "rel", "ratio", "steps", ...}; RuntimeError
    when the graph and the LP disagree (status or T past SAME_RTOL). The LP is solved `lp_repeats`
    times (default: once from LP_ONCE_EVENTS events, where one solve takes minutes, else `repeats`)."""
    lp_repeats = (1 if n >= LP_ONCE_EVENTS else repeats) if lp_repeats is None else lp_repeats
    from mechopt.solvers.cyclogram import least_cycle_time
    from mechopt.solvers.cyclogram.cycle_lp import cycle_time_lp
    from mechopt.solvers.cyclogram.cycle_uniform import uniform_constraints
    build_s, task = _timed(lambda: recurrent_network(n))
    u = uniform_constraints(task)
    graph, lp = [], []
    for i in range(repeats):
        g_s, r = _timed(lambda: least_cycle_time(task))
        graph.append(g_s)
        if i >= lp_repeats:
            continue
        l_s, (status, T_lp, said) = _timed(lambda: cycle_time_lp(u))
        lp.append(l_s)
        if r.status.value != "SOLVED" or status.value != "SOLVED":
            raise RuntimeError(f"cycle time, {n} events: graph {r.status.value} ({r.message}), LP {status.value} ({said})")
        T = r.values["cycle_deg"]
        rel = abs(T - T_lp) / max(1.0, abs(T_lp))
        if not rel <= SAME_RTOL:
            raise RuntimeError(f"cycle time, {n} events: graph {T!r} deg against the LP's {T_lp!r} ({rel:.1e} relative)")
        if progress:
            progress(f"cycle time {n:,} events, repeat {i + 1}: graph {g_s:.3f} s, LP {l_s:.2f} s CPU")
    out = {"events": len(u.names), "arcs": len(u.tails), "recurrent": len(task.recurrences), "build_s": build_s,
           "graph_runs": len(graph), "lp_runs": len(lp),
           "graph_s": statistics.median(graph), "lp_s": statistics.median(lp), "T_graph": T, "T_lp": T_lp,
           "rel": rel, "steps": r.diagnostics["dinkelbach_steps"], "passes": r.diagnostics["passes"],
           "circuit_arcs": r.diagnostics["critical_circuit"]["arcs"]}
    out["ratio"] = out["lp_s"] / out["graph_s"]
    return out


def table(row) -> str:
    verdict = "met" if row["ratio"] >= RATIO_TARGET else "MISSED"
    return "\n".join([
        f"least cycle time, {row['events']:,} events, {row['arcs']:,} arcs ({row['recurrent']:,} recurrent, "
        f"heights 1-{MAX_HEIGHT}); task built in {row['build_s']:.2f} s (not timed below)",
        f"  graph (least_cycle_time)   {row['graph_s']:.4f} s CPU, median of {row['graph_runs']}  ({row['steps']} "
        f"Dinkelbach steps, {row['passes']} passes; critical circuit of {row['circuit_arcs']} arcs)",
        f"  LP in (p, T) (certificate) {row['lp_s']:.4f} s CPU, median of {row['lp_runs']}",
        f"  LP / graph                 {row['ratio']:.1f}x  (>= {RATIO_TARGET:g}x: {verdict})",
        f"  T: graph {row['T_graph']:.12g} deg, LP {row['T_lp']:.12g} deg ({row['rel']:.1e} relative, <= {SAME_RTOL:g})"])


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """The table alone (no figure): `mechopt bench cycle_time`; `quick`: 10^4 events."""
    return table(compare(QUICK_EVENTS if quick else EVENTS, repeats=max(3, repeats), progress=progress))


if __name__ == "__main__":
    print(table(compare(int(sys.argv[1]) if len(sys.argv) > 1 else EVENTS, progress=print)))
