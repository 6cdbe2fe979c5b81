"""Scale and what-if speed of the event-time LP (paper 004, problem (1)).

Random layered networks of 10^3, 10^4 and 10^5 events (about three arcs each; event 0 first,
the last event last) are solved by

* ``networkx longest path``  graph build + dag_longest_path_length: the floor (the LP's answer
  when only precedence and lower bounds act);
* ``cvxpy + HiGHS``          `build_event_time_lp` (incidence matrix, DPP) compiled, then solved;
* ``cvxpy + Clarabel``       the same problem through an interior-point conic solver;
* ``scipy linprog``          HiGHS through scipy with the sparse constraint matrix built directly.

Build (construction and cvxpy compilation) and solve are timed apart; every span is compared
with the networkx floor (agreement to 1e-6 deg is required).

The machine-speed study (`machine_speed`) times `max_machine_speed` on a machine of 10 groups of
100 events (random layered networks run side by side inside one cycle, contact-stress laws on a
tenth of their arcs, the lever's rebound on one arc each, a timed flight), the graph method
(Newton on the positive cycles) against the LP in (p, n) in the same run. With the
scenes' chain lever (loom/machine-speed's): fresh (caches cleared: the chain's walk for its exact
bound included, the same for both methods) and re-solved (walk, levels and compiled LP kept).
With the earlier fitted lever (a proportional to n / t, closed form; tests/stop_impact_fitted.py):
fresh, and bisection on n, which must agree with the LP to 1e-6 (bisection on the chain walks the chain at every step: about 37 s). The what-if study re-solves after a
parameter change through the compiled problem (DPP) against a fresh build, with cvxpy's warm
start off and on (with HiGHS it can make re-solves slower), and through `HeldLP`: the LP held
in HiGHS with its basis, bounds changed in place (the lever for the group re-solve target: the
cvxpy re-solve spends ~1 ms applying parameters and handing the model over). Timings live here
only; tests never assert them.
"""
import dataclasses
import statistics
import time

import networkx as nx
import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from mechopt import registry
from mechopt.figures import save_figure
from mechopt.kit.cache import clear as clear_caches
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import HeldLP, build_event_time_lp, incidence, max_machine_speed, plan_cyclogram
from mechopt.solvers.cyclogram.graph import NO_BACK_ARCS, BackArcs, HeldSpan, Levels
from mechopt.solvers.cyclogram.graph_method import longest_schedule
from mechopt.solvers.cyclogram.lp_method import set_parameters
from mechopt.solvers.cyclogram.net import Net, back_arcs
from mechopt.solvers.cyclogram.schedule import critical_path, float_array
from mechopt.solvers.cyclogram.speed_graph import SpeedGraph
from mechopt.solvers.cyclogram.speed_laws import speed_coeffs_deg_per_rpm

__all__ = ["TARGETS", "cli", "graph_targets", "layered", "machine", "machine_speed", "random_dag", "scale",
           "sigma_what_if", "speed_verdicts", "what_if"]

SIZES = (1_000, 10_000, 100_000)
CLARABEL_MAX_EVENTS = 10_000      # at 10^5 one Clarabel solve took ~4 min on the 2-core machine
WARM_MAX_EVENTS = 10_000          # at 10^5 one warm-started HiGHS re-solve took ~5 min
TARGETS = {"cvxpy_highs_1e5_s": 1.5, "cvxpy_over_networkx_1e5": 2.0,
           "group1_fresh_over_resolve": 5.0,     # LP only: build + compile + solve against a DPP re-solve
           "machine_speed_10x100_s": 1.0,        # max_machine_speed, fresh (LP built, compiled and solved)
           # the graph's speed, walk held (chain) or no walk (fitted), its speed the LP's
           "what_if_graph_s": 2e-4,               # a what-if: one limit moved on loom/group1, graph pass + certificate
           "what_if_over_plain": 2.0,             # that what-if against a plain-Python pass in topological order
           "machine_speed_graph_s": 0.05, "lp_over_graph_speed": 1.0, "graph_lp_speed_rel": 1e-9,
           # the graph solve with floats, critical chain and duals; against cvxpy + HiGHS in the same run
           "graph_solve_1e5_s": 0.02, "cvxpy_over_graph": 50.0, "graph_solve_1e6_s": 0.3}
QUICK_SIZES = (1_000, 10_000)


def layered(n, per=3, width=100, seed=0):
    """Random layered DAG: event 0 first and n-1 last; each inner event is fed by `per` random
    events of the layer before (layers of `width`); events without a successor feed the last.
    Returns tails, heads (int arrays) and angles U(0, 30) deg."""
    rng = np.random.default_rng(seed)
    inner = np.arange(1, n - 1)
    layer = (inner - 1) // width
    tails = [np.where(layer == 0, 0, (layer - 1) * width + 1 + rng.integers(0, width, inner.size))
             for _ in range(per)]
    pairs = np.unique(np.column_stack([np.concatenate(tails), np.tile(inner, per)]), axis=0)
    leaves = np.setdiff1d(np.arange(n - 1), pairs[:, 0])
    pairs = np.vstack([pairs, np.column_stack([leaves, np.full(leaves.size, n - 1)])])
    return pairs[:, 0], pairs[:, 1], rng.uniform(0, 30, len(pairs))


def _networkx(n, tails, heads, w):
    start = time.perf_counter()
    g = nx.DiGraph()
    g.add_weighted_edges_from(zip(tails.tolist(), heads.tolist(), w.tolist()))
    build = time.perf_counter() - start
    span = nx.dag_longest_path_length(g)
    return build, time.perf_counter() - start - build, span


def _cvxpy(backend):
    def run(n, tails, heads, w):
        start = time.perf_counter()
        lp = build_event_time_lp(n, tails, heads, first=0, last=n - 1)
        lp.params["min_deg"].value = w
        lp.problem.get_problem_data(backend)
        build = time.perf_counter() - start
        lp.problem.solve(solver=backend, warm_start=False)
        if lp.problem.status != "optimal":
            raise RuntimeError(f"{backend}: {lp.problem.status}")
        return build, time.perf_counter() - start - build, float(lp.p.value[n - 1] - lp.p.value[0])
    return run


def _linprog(n, tails, heads, w):
    start = time.perf_counter()
    D = incidence(n, tails, heads)
    c = np.zeros(n)
    c[n - 1], c[0] = 1.0, -1.0
    a_eq = sp.csr_matrix(([1.0], ([0], [0])), shape=(1, n))       # anchor p(first) = 0
    build = time.perf_counter() - start
    res = linprog(c, A_ub=-D, b_ub=-w, A_eq=a_eq, b_eq=[0.0], bounds=(None, None), method="highs")
    if res.status != 0:
        raise RuntimeError(f"linprog: {res.message}")
    return build, time.perf_counter() - start - build, float(res.x[n - 1] - res.x[0])


def _graph(n, tails, heads, w, back=NO_BACK_ARCS, tol=1e-6):
    """The graph method as plan_cyclogram runs it (its own functions, solvers/cyclogram/graph_method.py
    and schedule.py): levels (build), then the earliest times with the duals (the arcs' uses on a
    longest path), the latest times and floats, one critical chain; without the per-name report. From
    2 x 10^4 arcs the passes are the compiled ones when numba is installed (solvers/cyclogram/kernel.py;
    MECHOPT_NO_NUMBA=1: the numpy levels), taken at once as by a process that solves many times."""
    start = time.perf_counter()
    levels = Levels(n, tails, heads, compiled=True)    # a solving process's steady state (a one-off: cyclogram_cli.py)
    net = Net.of_arrays(n, tails, heads, w)
    build = time.perf_counter() - start
    early, span, uses, _, _ = longest_schedule(net, levels, back, tol)
    floats = float_array(net, levels, back, w, span, early=early)
    critical_path(net, floats, tol)
    assert uses.max() >= 1
    return build, time.perf_counter() - start - build, float(span)


METHODS = {"graph (longest paths)": _graph, "networkx longest path": _networkx, "cvxpy + HiGHS": _cvxpy("HIGHS"),
           "cvxpy + Clarabel": _cvxpy("CLARABEL"), "scipy linprog (HiGHS)": _linprog}


def scale(sizes=SIZES, repeats=3, progress=None, clarabel_max=CLARABEL_MAX_EVENTS):
    """Median build, solve and total seconds of every method at every size, and the span error
    against the networkx floor [deg]."""
    rows = []
    for n in sizes:
        tails, heads, w = layered(n)
        floor = None
        for method, call in METHODS.items():
            if method == "cvxpy + Clarabel" and n > clarabel_max:
                continue
            runs = []
            for k in range(repeats):
                runs.append(call(n, tails, heads, w))
                if progress:
                    progress(f"{method:<24} n={n:<7} run {k + 1}/{repeats}: {sum(runs[-1][:2]):.3f} s")
            floor = runs[0][2] if floor is None else floor
            rows.append({"method": method, "events": n, "arcs": len(tails),
                         "build_s": statistics.median(r[0] for r in runs),
                         "solve_s": statistics.median(r[1] for r in runs),
                         "total_s": statistics.median(r[0] + r[1] for r in runs),
                         "span_deg": runs[-1][2], "span_error_deg": abs(runs[-1][2] - floor)})
    return rows


def random_dag(n, windows=1_000, seed=0):
    """Random DAG with windows: event j > 0 fed by two random events among the 50 before it
    (event 0 feeds the rest; the leaves feed n - 1), angles U(0, 30) deg; windows between random
    pairs a < b, each its pair's longest distance plus U(0, 2) deg (a third exactly tight), so
    the network stays feasible. Returns tails, heads, w, (window from, to, max_deg)."""
    rng = np.random.default_rng(seed)
    j = np.repeat(np.arange(1, n - 1), 2)
    i = np.maximum(0, j - rng.integers(1, 51, j.size))
    pairs = np.unique(np.column_stack([i, j]), axis=0)
    leaves = np.setdiff1d(np.arange(n - 1), pairs[:, 0])
    pairs = np.vstack([pairs, np.column_stack([leaves, np.full(leaves.size, n - 1)])])
    tails, heads, w = pairs[:, 0], pairs[:, 1], rng.uniform(0, 30, len(pairs))
    dist = Levels(n, tails, heads).longest_from(0, w)
    a, b = np.sort(rng.integers(1, n - 1, (2, windows)), axis=0)
    keep = a < b
    a, b = a[keep], b[keep]
    slack = rng.uniform(0, 2, a.size) * (rng.random(a.size) > 1 / 3)
    return tails, heads, w, (a, b, np.maximum(dist[b] - dist[a], 0.0) + slack)


def _cvxpy_windows(n, tails, heads, w, windows):
    start = time.perf_counter()
    a, b, wmax = windows
    lp = build_event_time_lp(n, tails, heads, first=0, last=n - 1, window_arcs=list(zip(a.tolist(), b.tolist())))
    lp.params["min_deg"].value, lp.params["window_deg"].value = w, wmax
    lp.problem.get_problem_data("HIGHS")
    build = time.perf_counter() - start
    lp.problem.solve(solver="HIGHS", warm_start=False)
    if lp.problem.status != "optimal":
        raise RuntimeError(f"HIGHS: {lp.problem.status}")
    return build, time.perf_counter() - start - build, float(lp.p.value[n - 1] - lp.p.value[0])


def graph_targets(repeats=3, progress=None, big=1_000_000):
    """The graph method's rows: a random DAG of 10^5 events with windows, graph against cvxpy + HiGHS
    (the same run), and the graph alone on a layered network of `big` events."""
    rows = []
    tails, heads, w, windows = random_dag(100_000)
    back = BackArcs(windows[1], windows[0], -windows[2])
    for method, call in (("graph (longest paths)", lambda: _graph(100_000, tails, heads, w, back)),
                         ("cvxpy + HiGHS", lambda: _cvxpy_windows(100_000, tails, heads, w, windows))):
        runs = [call() for _ in range(repeats)]
        if progress:
            progress(f"{method} random DAG + windows: {sum(runs[-1][:2]):.3f} s")
        rows.append({"method": method, "events": 100_000, "arcs": len(tails) + len(windows[0]), "case": "random+win",
                     "build_s": statistics.median(r[0] for r in runs), "solve_s": statistics.median(r[1] for r in runs),
                     "total_s": statistics.median(r[0] + r[1] for r in runs), "span_deg": runs[-1][2]})
    tails, heads, w = layered(big)
    runs = [_graph(big, tails, heads, w) for _ in range(repeats)]
    rows.append({"method": "graph (longest paths)", "events": big, "arcs": len(tails), "case": "layered",
                 "build_s": statistics.median(r[0] for r in runs), "solve_s": statistics.median(r[1] for r in runs),
                 "total_s": statistics.median(r[0] + r[1] for r in runs), "span_deg": runs[-1][2]})
    return rows


def graph_table(scale_rows, rows):
    """The graph rows and their verdicts against the targets: solve time (with floats, chain, duals) and its
    ratio to cvxpy + HiGHS (build + solve) in the same run."""
    lines = ["", f"{'graph method':<24}{'case':>12}{'events':>9}{'build s':>10}{'solve s':>10}"
             f"{'span deg':>16}"]
    lines += [f"{r['method']:<24}{r['case']:>12}{r['events']:>9}{r['build_s']:>10.4f}{r['solve_s']:>10.4f}"
              f"{r['span_deg']:>16.6f}" for r in rows]
    by = {(r["method"], r["events"]): r for r in scale_rows}
    verdicts = []
    if ("cvxpy + HiGHS", 100_000) in by:
        g, c = by["graph (longest paths)", 100_000], by["cvxpy + HiGHS", 100_000]
        verdicts += [("graph_solve_1e5_layered_s", g["solve_s"], TARGETS["graph_solve_1e5_s"], "<="),
                     ("cvxpy_over_graph_1e5_layered", c["total_s"] / g["solve_s"], TARGETS["cvxpy_over_graph"], ">=")]
    g, c = rows[0], rows[1]
    verdicts += [("graph_solve_1e5_windows_s", g["solve_s"], TARGETS["graph_solve_1e5_s"], "<="),
                 ("cvxpy_over_graph_1e5_windows", c["total_s"] / g["solve_s"], TARGETS["cvxpy_over_graph"], ">="),
                 (f"graph_solve_{rows[2]['events']:.0e}_s", rows[2]["solve_s"], TARGETS["graph_solve_1e6_s"], "<=")]
    lines.append(f"span graph vs cvxpy (random + windows): {abs(g['span_deg'] - c['span_deg']):.1e} deg")
    for key, got, want, op in verdicts:
        ok = got >= want if op == ">=" else got <= want
        lines.append(f"{key:<32}{got:>10.4g}{op + ' ' + format(want, 'g'):>10}  {'met' if ok else 'MISSED'}")
    return "\n".join(lines)


def _time(call):
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def _median_time(call, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def what_if(repeats=5, progress=None, warm_max=WARM_MAX_EVENTS):
    """Median seconds: a fresh build+solve against a DPP re-solve after a parameter change, for
    loom/group1 (amplitude limit) and random networks (every [phi] scaled), warm start off / on."""
    out = []
    task, _ = registry.find("loom/group1").build()
    limits = iter(np.linspace(0.08, 0.12, 10_000))

    def fresh():
        clear_caches()
        plan_cyclogram(task)

    def resolve(warm):
        return lambda: plan_cyclogram(dataclasses.replace(task, amplitude_limit_mm=float(next(limits))),
                                      warm_start=warm)
    plan_cyclogram(task)
    row = {"case": "loom/group1 (plan_cyclogram, full report)", "fresh_s": _median_time(fresh, repeats)}
    plan_cyclogram(task)
    row["resolve_cold_s"] = _median_time(resolve(False), repeats)
    row["resolve_warm_s"] = _median_time(resolve(True), repeats)
    out.append(row)
    net = Net(task, "exact")

    def build_group1():
        lp = build_event_time_lp(len(net.names), net.tails, net.heads, first=net.first, last=net.last,
                                 stress_rows=net.stress_rows, stress_ref=net.stress_ref,
                                 amplitude_rows=net.amp_rows)
        set_parameters(lp, task, net)
        lp.problem.solve(solver="HIGHS", warm_start=False)
        return lp
    lp = build_group1()

    def resolve_group1(warm):
        def call():
            lp.params["amplitude_limit_mm"].value = float(next(limits))
            lp.problem.solve(solver="HIGHS", warm_start=warm)
        return call
    out.append({"case": "loom/group1 (LP only)", "fresh_s": _median_time(build_group1, repeats),
                "resolve_cold_s": _median_time(resolve_group1(False), repeats),
                "resolve_warm_s": _median_time(resolve_group1(True), repeats)})
    held = HeldLP(len(net.names), net.tails, net.heads, first=net.first, last=net.last)
    bounds = iter(np.linspace(0.9, 1.1, 10_000))

    def resolve_held():                   # the same change: the amplitude bound of (3,7) moves
        status, _ = held.solve(net.lb * np.where(np.isin(np.arange(net.lb.size), net.amp_rows), next(bounds), 1.0))
        if status.value != "SOLVED":
            raise RuntimeError(f"held HiGHS model: {status.value}")
    out.append({"case": "loom/group1 (held HiGHS model)", "fresh_s": out[-1]["fresh_s"],
                "resolve_cold_s": _median_time(resolve_held, repeats), "resolve_warm_s": float("nan")})
    out.append(sigma_what_if(task, out[1]["fresh_s"], repeats))
    if progress:
        progress(f"what-if loom/group1: {out[-3:]}")
    for n in (1_000, 10_000):
        tails, heads, w = layered(n)
        scales = iter(np.linspace(0.9, 1.1, 1000))

        def build():
            lp = build_event_time_lp(n, tails, heads, first=0, last=n - 1)
            lp.params["min_deg"].value = w
            lp.problem.solve(solver="HIGHS", warm_start=False)
            return lp
        lp = build()

        def resolve_lp(warm):
            def call():
                lp.params["min_deg"].value = w * next(scales)
                lp.problem.solve(solver="HIGHS", warm_start=warm)
            return call
        row = {"case": f"layered n={n} (LP only)", "fresh_s": _median_time(build, repeats),
               "resolve_cold_s": _median_time(resolve_lp(False), repeats)}
        row["resolve_warm_s"] = _median_time(resolve_lp(True), repeats) if n <= warm_max else float("nan")
        out.append(row)
        if progress:
            progress(f"what-if n={n}: {row}")
    return out


def sigma_what_if(task, fresh_lp_s, repeats):
    """A what-if on loom/group1: [sigma_H] moved, the stress rows' bounds recomputed as a
    vector and the span re-solved by a fresh graph pass certified by LP duality (`HeldSpan.solve`:
    the times feasible, a tight chain of the same value), and the held HiGHS model re-solved and
    certified by a pass; against the fresh LP build + solve (`fresh_lp_s`)."""
    net = Net(task, "exact")
    rows = np.asarray(net.stress_rows, dtype=np.int64)
    floor, k_ref = task.min_angles_deg()[rows], net.stress_ref[0] * net.stress_ref[1]
    back = back_arcs(net, with_cycle=False)[0]
    graph = HeldSpan(len(net.names), net.tails, net.heads, net.first, net.last, back)
    held = HeldLP(len(net.names), net.tails, net.heads, first=net.first, last=net.last,
                  window_arcs=net.window_idx, sync_arcs=net.sync_idx)
    windows = [w for _, _, w in task.window_arcs()]
    sigmas = iter(np.linspace(600.0, 1000.0, 100_000))
    lb = net.lb.copy()

    def bounds(sigma):                    # only the stress rows move (t >= sigma_ref t_ref / [sigma_H])
        lb[rows] = np.maximum(floor, k_ref / sigma)
        return lb
    check = Net(dataclasses.replace(task, sigma_H_limit_MPa=700.0), "exact").lb
    if not np.allclose(bounds(700.0), check, rtol=1e-15, atol=0.0):
        raise RuntimeError("the what-if's bounds are not the model's")

    def graph_pass():                     # the fresh pass with its own certificate (primal and dual)
        status, span, _ = graph.solve(bounds(next(sigmas)))
        if status.value != "SOLVED":
            raise RuntimeError(f"graph what-if: {status.value}")
        return span

    def certified_resolve():
        new = bounds(next(sigmas))
        status, p = held.solve(new, windows)
        verdict, _ = graph.certify(new, None if p is None else float(p[net.last] - p[net.first]))
        if verdict.value != "SOLVED":
            raise RuntimeError(f"held HiGHS re-solve: {status.value}, certificate {verdict.value}")
    plain = _plain_pass(net)

    def plain_pass():                     # the floor: the same bounds, one loop over the arcs, no certificate
        p, span = plain(bounds(next(sigmas)))
        return span
    sigma = 777.0
    if plain(bounds(sigma))[1] != graph.solve(bounds(sigma))[1]:
        raise RuntimeError("the plain-Python pass and the held graph give different spans")
    runs = max(repeats, 2000)             # microseconds: many single-call timings for a stable median
    graph_s, plain_s = [], []
    for _ in range(5):                    # interleaved blocks: the load of the shared machine hits both
        graph_s.append(_median_time(graph_pass, runs // 5))
        plain_s.append(_median_time(plain_pass, runs // 5))
    return {"case": "loom/group1 [sigma_H] (graph + cert. | held + cert.)", "fresh_s": fresh_lp_s,
            "resolve_cold_s": statistics.median(graph_s), "resolve_warm_s": _median_time(certified_resolve, runs // 10),
            "plain_pass_s": statistics.median(plain_s)}


def _plain_pass(net):
    """A plain-Python longest-path pass a designer would write for a small DAG (the issue's
    floor for a what-if): events in topological order (graphlib), each arc relaxed once from the
    bounds as a list; returns (the event times as an array, the span). No back arcs."""
    import graphlib
    if net.window_idx or net.sync_idx:
        raise ValueError("the plain reference pass takes a DAG (no windows, no syncs)")
    tails, heads = net.tails.tolist(), net.heads.tolist()
    sorter = graphlib.TopologicalSorter({h: set() for h in range(len(net.names))})
    for t, h in zip(tails, heads):
        sorter.add(h, t)
    rank = {v: i for i, v in enumerate(sorter.static_order())}
    arcs = sorted(zip(tails, heads, range(len(tails))), key=lambda a: rank[a[0]])
    n, first, last = len(net.names), net.first, net.last

    def run(lb):
        w, dist = lb.tolist(), [-np.inf] * n
        dist[first] = 0.0
        for t, h, k in arcs:
            c = dist[t] + w[k]
            if c > dist[h]:
                dist[h] = c
        return np.array(dist), dist[last] - dist[first]
    return run


FITTED_LEVER = {"E_GPa": 210.0, "J_x_mm4": 13020.8, "a_mm": 80.0, "b_mm": 120.0, "a_stop_mm": 80.0,
                "b_stop_mm": 56.2286, "mass_kg": 0.81792, "stroke_mm": 20.0, "velocity_factor": 0.379503,
                "inertia_A_kgm2": 1.90100e-4, "restitution": 5 / 9, "damping_ratio": 0.05,
                "effects": ["initial_velocity", "impact_pulse", "damping"]}    # tests/stop_impact_fitted.py's


def machine(groups=10, per_group=100, seed=0, lever=None):
    """A machine of `groups` random layered groups (`layered`, layers of 10) side by side between
    a start and an end event, then a timed flight (100 deg, 60 ms), in a 360 deg cycle: contact
    stress on a tenth of the arcs (sigma_ref 500-900 MPa at their angle, [sigma_H] 800 MPa at
    420 rpm) and the lever's rebound (`lever`, by default loom/machine-speed's) on each group's first arc."""
    rng = np.random.default_rng(seed)
    lever = registry.find("loom/machine-speed").build()[0].lever if lever is None else lever
    events = {"start": {}, "end": {}, "flight.end": {"group": "flight"}}
    ops, stress = [], {}
    for g in range(groups):
        tails, heads, w = layered(per_group, width=10, seed=seed + g)

        def name(i, g=g):
            return f"g{g}.{i}"
        events |= {name(i): {"group": f"group{g}"} for i in range(per_group)}
        ops += [{"from": "start", "to": name(0), "min_deg": 0.0}, {"from": name(per_group - 1), "to": "end", "min_deg": 0.0}]
        for k, (x, y, angle) in enumerate(zip(tails.tolist(), heads.tolist(), (0.4 * w).tolist())):
            op = {"from": name(x), "to": name(y), "min_deg": angle}
            if k == 0:
                op["amplitude"] = "linear"
            elif rng.random() < 0.1:
                stress[f"cam{len(stress)}"] = {"sigma_ref_MPa": float(rng.uniform(500, 900)), "t_ref_deg": max(angle, 5.0)}
                op["stress"] = f"cam{len(stress) - 1}"
            ops.append(op)
    ops.append({"from": "end", "to": "flight.end", "min_deg": 100.0, "min_ms": 60.0})
    return Cyclogram(events=events, operations=ops, stress_models=stress, cycle_deg=360.0, sigma_H_limit_MPa=800.0,
                     amplitude_limit_mm=0.1, speed_rpm=420.0, lever=lever)


SPEED_CASES = (("graph, chain, fresh", "chain", "graph", True), ("LP (p, n), chain, fresh", "chain", "lp", True),
               ("graph, chain, re-solve", "chain", "graph", False), ("LP (p, n), chain, re-solve", "chain", "lp", False),
               ("graph, fitted, fresh", "fitted", "graph", True), ("LP (p, n), fitted, fresh", "fitted", "lp", True),
               ("bisection on n, fitted", "fitted", "bisection", True))


def machine_speed(repeats=3, progress=None):
    """Median seconds of `max_machine_speed` on `machine()`, the graph against the LP in (p, n)
    in the same run: with the chain lever fresh (caches cleared: the chain's walk for its exact
    bound, the same for both, dominates) and re-solved (walk, levels and compiled LP kept); with
    the fitted lever (closed form, no walk) fresh, and bisection on n once. Speeds: graph against
    LP to 1e-9, LP against bisection to 1e-6."""
    tasks = {"chain": machine(), "fitted": machine(lever=FITTED_LEVER)}
    rows = []
    for label, lever, method, fresh in SPEED_CASES:
        task = tasks[lever]

        def call(task=task, method=method, fresh=fresh, lever=lever):
            if fresh:
                clear_caches()
            return max_machine_speed(task, method=method, scan_step_deg=0.25 if lever == "chain" else 2.0)
        if method != "bisection":
            call()                        # imports and the structure's first compilation
        start = time.perf_counter()
        result = call()
        first_s = time.perf_counter() - start
        seconds = (statistics.median([first_s] + [_time(call) for _ in range(repeats - 1)])
                   if method != "bisection" else first_s)
        rows.append({"case": label, "seconds": seconds, "speed_rpm": result.values["max_speed_rpm"],
                     "status": result.status.value, "steps": result.diagnostics.get("newton_steps")})
        if progress:
            progress(f"machine speed {label}: {rows[-1]}")
    chain = max_machine_speed(tasks["chain"])
    task = tasks["chain"]                 # the parametric solve alone: Newton's passes, no report
    g, _, _ = speed_coeffs_deg_per_rpm(task)
    phi = np.fromiter((d for *_, d in task.graph.edges(data="min_deg")), dtype=float, count=len(task.arcs))
    solver = SpeedGraph(task, Net.structure(task), phi, g)
    seconds = statistics.median(_time(solver.highest_speed) for _ in range(max(repeats, 5)))
    n_core, _, steps = solver.highest_speed()
    rows.append({"case": "graph solve alone, chain", "seconds": seconds, "speed_rpm": n_core, "status": "SOLVED",
                 "steps": steps})
    return {"events": len(tasks["chain"].graph), "arcs": len(tasks["chain"].arcs), "rows": rows,
            "limiting": chain.diagnostics["limiting_constraint"],
            "limiting_cycle_ops": len(chain.diagnostics["limiting_cycle"]) - 1}


def speed_verdicts(speed):
    """(target, measured, want, met) rows of the machine-speed study; ratios in the same run."""
    by = {r["case"]: r for r in speed["rows"]}
    graph_s = max(by["graph, chain, re-solve"]["seconds"], by["graph, fitted, fresh"]["seconds"])
    agree = max(abs(by[f"graph, {c}"]["speed_rpm"] / by[f"LP (p, n), {c}"]["speed_rpm"] - 1)
                for c in ("chain, fresh", "chain, re-solve", "fitted, fresh"))
    ratio = min(by["LP (p, n), chain, re-solve"]["seconds"] / by["graph, chain, re-solve"]["seconds"],
                by["LP (p, n), fitted, fresh"]["seconds"] / by["graph, fitted, fresh"]["seconds"])
    lp_fresh = by["LP (p, n), chain, fresh"]["seconds"]
    return [("machine_speed_10x100_s", lp_fresh, TARGETS["machine_speed_10x100_s"], lp_fresh <= TARGETS["machine_speed_10x100_s"]),
            ("machine_speed_graph_s", graph_s, TARGETS["machine_speed_graph_s"], graph_s <= TARGETS["machine_speed_graph_s"]),
            ("lp_over_graph_speed", ratio, TARGETS["lp_over_graph_speed"], ratio >= TARGETS["lp_over_graph_speed"]),
            ("graph_lp_speed_rel", agree, TARGETS["graph_lp_speed_rel"], agree <= TARGETS["graph_lp_speed_rel"])]


def table(rows, whatif, speed=None):
    """The scale rows, the what-if rows and the targets as fixed-width text."""
    head = (f"{'method':<24}{'events':>8}{'arcs':>8}{'build s':>10}{'solve s':>10}{'total s':>10}"
            f"{'span deg':>14}{'|err| deg':>11}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['method']:<24}{r['events']:>8}{r['arcs']:>8}{r['build_s']:>10.4f}{r['solve_s']:>10.4f}"
                     f"{r['total_s']:>10.4f}{r['span_deg']:>14.6f}{r['span_error_deg']:>11.1e}")
    lines += ["", f"{'what-if':<44}{'fresh s':>10}{'re-solve s':>12}{'warm s':>10}{'fresh/re-solve':>16}"]
    for r in whatif:
        lines.append(f"{r['case']:<44}{r['fresh_s']:>10.4f}{r['resolve_cold_s']:>12.4f}{r['resolve_warm_s']:>10.4f}"
                     f"{r['fresh_s'] / r['resolve_cold_s']:>16.1f}")
    by = {(r["method"], r["events"]): r for r in rows}
    verdicts = []
    big = max(r["events"] for r in rows)
    if ("cvxpy + HiGHS", big) in by and big >= 100_000:
        cv, nxr = by["cvxpy + HiGHS", big]["total_s"], by["networkx longest path", big]["total_s"]
        verdicts += [("cvxpy_highs_1e5_s", cv), ("cvxpy_over_networkx_1e5", cv / nxr)]
    # the lever: a held HiGHS model re-solved on changed bounds (row 3), against the cvxpy fresh build
    verdicts.append(("group1_fresh_over_resolve", whatif[2]["fresh_s"] / whatif[2]["resolve_cold_s"]))
    verdicts.append(("what_if_graph_s", whatif[3]["resolve_cold_s"]))      # fresh LP / it: the row's last column
    verdicts.append(("what_if_over_plain", whatif[3]["resolve_cold_s"] / whatif[3]["plain_pass_s"]))
    lines += ["", f"{'target':<28}{'measured':>10}{'target':>10}  verdict"]
    for key, got in verdicts:
        want = TARGETS[key]
        ok = got >= want if key.endswith("resolve") else got <= want
        lines.append(f"{key:<28}{got:>10.3f}{('>= ' if key.endswith('resolve') else '<= ') + format(want, 'g'):>10}  "
                     f"{'met' if ok else 'MISSED'}" + ("" if key.startswith(("group1", "what_if")) else f" (n={big})"))
    if speed:
        for key, got, want, ok in speed_verdicts(speed):
            lines.append(f"{key:<28}{got:>10.3g}{('>= ' if key.startswith('lp_over') else '<= ') + format(want, 'g'):>10}  "
                         f"{'met' if ok else 'MISSED'}")
    worst = max(r["span_error_deg"] for r in rows)
    lines.append(f"largest span disagreement with networkx: {worst:.2e} deg ({'ok' if worst <= 1e-6 else 'OVER 1e-6'})")
    if speed:
        lines += ["", f"machine speed, {speed['events']} events, {speed['arcs']} arcs (limiting: {speed['limiting']}; "
                  f"limiting cycle of {speed['limiting_cycle_ops']} operations)",
                  f"{'method':<28}{'median s':>10}{'speed rpm':>20}  status"]
        lines += [f"{r['case']:<28}{r['seconds']:>10.4f}{r['speed_rpm']:>20.13g}  {r['status']}"
                  + (f" ({r['steps']} Newton steps)" if r["steps"] else "") for r in speed["rows"]]
        fitted = [r["speed_rpm"] for r in speed["rows"] if "fitted" in r["case"]]
        spread = max(fitted) / min(fitted) - 1
        lines.append(f"graph, LP and bisection (fitted lever): {spread:.1e} relative "
                     f"({'ok' if spread <= 1e-6 else 'OVER 1e-6'})")
    return "\n".join(lines)


def plot(rows, out_dir):
    """Write "loom_scale.png": total seconds against events per method. Returns [path]."""
    import pathlib

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 5))
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        ax.plot([r["events"] for r in mine], [r["total_s"] for r in mine], marker="o", label=method)
    ax.set(xscale="log", yscale="log", xlabel="events (about 3 arcs each)", ylabel="build + solve, median [s]",
           title="Event-time LP on random layered networks")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return [str(save_figure(fig, out / "loom_scale.png"))]


CSV_MACHINE_RATIO = 30.0        # the target: graph >= 30x faster than the LP on a 10^5-event CSV scene


def csv_machine(n=100_000, repeats=3, progress=None):
    """The large-scene target: a generated scene of `n` events (`layered`, four groups) read from a
    CSV timing table beside it, solved by plan_cyclogram with method "graph" and "lp" (each its
    problem's build and solve from the same task; medians, the LP once at 10^5: ~15 s) to the
    same span. The scene's read (CSV and network checks), common to both, is timed apart."""
    import pathlib
    import tempfile

    from mechopt.scene import load
    tails, heads, angles = layered(n)
    with tempfile.TemporaryDirectory() as folder:
        folder = pathlib.Path(folder)
        with open(folder / "ops.csv", "w", encoding="utf-8") as f:
            f.write("from,to,min_deg,group\n")
            f.writelines(f"e{a},e{b},{w:.9f},g{a * 4 // n}\n" for a, b, w in zip(tails.tolist(), heads.tolist(),
                                                                              angles.tolist()))
        (folder / "machine.toml").write_text(
            'id = "bench/csv-machine"\ntitle = "generated"\nsource = "benchmarks/loom.py"\ntask = "loom.Cyclogram"\n'
            'solver = "loom.plan_cyclogram"\n[params]\n[structure]\n'
            'operations = { csv = "ops.csv", columns = ["from", "to", "min_deg"] }\n', encoding="utf-8")
        start = time.perf_counter()
        task = load(folder / "machine.toml").build()[0]
        read_s = time.perf_counter() - start
    out = {"events": n, "arcs": len(tails), "read_s": read_s}
    for method, times in (("graph", repeats), ("lp", 1 if n >= 100_000 else repeats)):
        if progress:
            progress(f"csv machine {n:,} events: {method}")
        durations = []
        for _ in range(times):
            start = time.perf_counter()
            result = plan_cyclogram(task, method=method)
            durations.append(time.perf_counter() - start)
        if result.status.value != "SOLVED":
            raise RuntimeError(f"csv machine, method {method}: {result.status.value}: {result.message}")
        out[f"{method}_span_deg"], out[f"{method}_s"] = result.values["span_deg"], statistics.median(durations)
    out["ratio"] = out["lp_s"] / out["graph_s"]
    out["same_span"] = abs(out["graph_span_deg"] - out["lp_span_deg"]) <= 1e-9 * abs(out["lp_span_deg"])
    return out


def csv_machine_table(row) -> str:
    """The done-when line: times, the ratio against the target, the spans."""
    verdict = "met" if row["ratio"] >= CSV_MACHINE_RATIO and row["same_span"] else "NOT met"
    return (f"CSV machine, {row['events']:,} events / {row['arcs']:,} operations read from a CSV in "
            f"{row['read_s']:.2f} s: graph {row['graph_s']:.3f} s, lp {row['lp_s']:.2f} s (build + solve), "
            f"lp / graph = {row['ratio']:.1f}x (target >= {CSV_MACHINE_RATIO:g}x: {verdict}); span "
            f"{row['graph_span_deg']:.9g} vs {row['lp_span_deg']:.9g} deg" + ("" if row["same_span"] else " DIFFER"))


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """What `mechopt bench loom` prints: the scale table, the what-if table, the machine speed,
    the targets. `quick`: networks up to 10^4 events (the 10^5 target is then not judged),
    Clarabel and warm-started re-solves up to 10^3, bisection on the machine once (about 15 s)."""
    rows = scale(sizes=QUICK_SIZES if quick else SIZES, repeats=repeats, progress=progress,
                 clarabel_max=1_000 if quick else CLARABEL_MAX_EVENTS)
    whatif = what_if(repeats=max(repeats, 5), progress=progress, warm_max=1_000 if quick else WARM_MAX_EVENTS)
    speed = machine_speed(repeats=repeats, progress=progress)
    graph = graph_targets(repeats=repeats, progress=progress, big=100_000 if quick else 1_000_000)
    return "\n".join([table(rows, whatif, speed), graph_table(rows, graph),
                      csv_machine_table(csv_machine(10_000 if quick else 100_000, repeats, progress)),
                      *(f"plot: {p}" for p in plot(rows, out_dir))])
