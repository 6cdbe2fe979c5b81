"""Link lengths H, L for the torch-guiding linkage (paper 000): the paper's grid scan and ours.

* `grid_scan`: the published algorithm (Sec. IV), answer unchanged, made fast by filtering.
* `minimax`:   the exact criterion the paper called too laborious, as a CasADi NLP (SQP, IPOPT).
* `robust`:    the grid point whose worst deviation over the manufacturing box is smallest.
* `evolve`:    scipy's differential evolution on the minimax objective: the peer a user would try.
* `check`:     a given (H, L) measured both ways, for what-if maps over the link lengths.

Every answer's `max_deviation_mm` is the independent Euclidean check of `deviation`, and every
fitting solver's status follows one rule (`_verdict`, `_on_edge`): outside err_width_mm is
INFEASIBLE with the best values kept, on a side of the default box LIMIT naming it. Lengths are
solved in units of the cam (`_scale`), so one set of tolerances serves a 1 um and a 1 m cam.
"""
import math
from typing import Literal

import casadi as ca
import numpy as np
from scipy.optimize import differential_evolution

from mechopt.kit import warm
from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Ge, Interval, Tolerance, check_settings
from mechopt.models.cam_cutter import (
    PAPER_A_MM,
    LinkageCheck,
    LinkageFit,
    ideal_normal,
    ideal_point,
    limacon_implicit,
    real_point,
)
from mechopt.models.cam_profile import MIN_LINK_PER_SIZE, ProfileFit
from mechopt.solvers.cam_cutter.certificate import box_lower_bound, grid_starts, warm_cells
from mechopt.solvers.cam_cutter.deviation import (
    deviation_arrays,
    foot_points,
    nodes_and_normals,
    normal_crossings,
    normal_deviation,
    normal_quartic,
    path_distance,
    verified_deviation,
    verified_deviation_on,
)
from mechopt.solvers.cam_cutter.problem import NLP_OPTIONS, ROUND_VERTICES, foot_and_band, pad_nodes, solve_round

Nodes = Annotated[int, Interval(ge=2, le=1_000_000)]      # COUNT: nodes on the ideal path

__all__ = ["grid_scan", "minimax", "robust", "evolve", "check"]

NODE_RULES = {
    # name: (first index, last index + 1) of t_i = i * t_FINISH / COUNT
    "half_open": (0, 0),    # i = 0 .. COUNT-1: t_FINISH itself is no node; reproduces the paper
    "closed": (0, 1),       # i = 0 .. COUNT
    "open_start": (1, 1),   # i = 1 .. COUNT
}
GRID_POINT_LIMIT = 50_000_000
BOX_PAD_PER_A = 0.5        # the default box: matched linkage +- a/2 (`LinkageFit.bounds`)
BOX_WIDEN_FACTOR = 4.0     # each widening of a default side the optimum lies on


def grid_scan(task: LinkageFit, *, count: Nodes = 1000,
              nodes: Literal["half_open", "closed", "open_start"] = "half_open") -> Result:
    """The paper's grid scan (Sec. IV): the first (H, L), H ascending then L ascending, on the
    STEP lattice of the box, at which every node's error segment is crossed by the limaçon.

    At node t_i the segment runs +-err_width_mm along the ideal path's normal; an end below the
    x axis is pulled back to the axis; the node passes when exactly one end lies inside the closed
    limaçon (`limacon_implicit` < 0). Where that fails every lattice point, the scan is repeated
    with segments crossed twice passing too (`_crossed_twice`: a band wider than the limaçon spans
    it, which the paper's test cannot see: at err_width_mm = 100 it failed every point where 75
    passed all); `diagnostics["segments_probed"]` says so. Nodes
    t_i = i t_FINISH / COUNT with t_FINISH read to
    y_tol_mm as the paper read it (`t_finish_read_rad`); `nodes` picks which i (see NODE_RULES).

    Exact and fast: a point must pass every node, so the nodes are applied one at a time, in an
    order spread over the path, to the points that survived the previous ones; after a few nodes
    only the neighbourhood of the answer is left. The answer is the scan's, order and all.

    Near t_FINISH the limaçon passes its double point, and its crossing with the normal drops
    below the axis just before the ideal path does: the node at t = t_FINISH ("closed",
    "open_start") then fails everywhere at the paper's width. `diagnostics` reports this.
    """
    _cardioid_only(task, "grid_scan")
    clock = Clock()
    H_grid, L_grid = _lattice(task)             # first: a lattice too large is refused before any work
    t_finish = task.t_finish_read_rad
    t = _node_times(task, count, nodes)
    ends = _segment_ends(t, task)
    clock.built()

    # golden-ratio spread from the far end: early nodes pass nearly every point, late ones ~3 %
    order = np.argsort((np.arange(t.size)[::-1] * 0.6180339887498949) % 1.0)
    passing = _scan(H_grid, L_grid, ends, order)
    probed = len(passing) == 0      # every point failed: tell segments crossed twice from none
    if probed:
        passing = _scan(H_grid, L_grid, ends, order, crossed=_crossed_twice(t, task, ends))

    diagnostics = {"nodes": int(t.size), "node_rule": nodes, "t_finish_exact_rad": task.t_finish_rad,
                   "grid_points": int(H_grid.size * L_grid.size), "segments_probed": probed}
    values = {"t_finish_rad": t_finish, "n_passing": float(len(passing))}
    if len(passing) == 0:
        best = minimax(task, count=count)      # the grid has no answer: say what is achievable
        if "max_deviation_mm" in best.values:
            values["best_deviation_mm"] = best.values["max_deviation_mm"]
            diagnostics |= {"best_H_mm": best.values["H_mm"], "best_L_mm": best.values["L_mm"]}
        return clock.result(Status.INFEASIBLE, values,
                            message=f"no grid point keeps every node within err_width_mm={task.err_width_mm}; best "
                                    f"achievable (minimax NLP, {best.status.value}): "
                                    f"{best.values.get('max_deviation_mm', float('nan')):.4g} mm",
                            violated=("err_width",), diagnostics=diagnostics,
                            arrays=best.arrays)           # the best achievable linkage along the path
    H, L = (float(v) for v in passing[0])
    deviation, where = verified_deviation(task.a_mm, task.h_mm, H, L, task.t_finish_rad)
    diagnostics |= {
        "passing_box_mm": [float(passing[:, 0].min()), float(passing[:, 0].max()),
                           float(passing[:, 1].min()), float(passing[:, 1].max())],
        "finish_node": _finish_node_report(task, H, L, t_finish),
        "segments_crossed_twice": _even_crossings(t, task, H, L),
        "max_deviation_at_rad": where,
    }
    values |= {"H_mm": H, "L_mm": L, "max_deviation_mm": deviation}
    status, violated = Status.SOLVED, ()
    message = f"first of {len(passing)} passing grid points, H ascending then L ascending"
    if probed:
        message += " (the paper's one-end-in test failed every point; a segment crossed twice passes)"
    if deviation > task.err_width_mm:       # every node passes, yet the path leaves the band between them
        status, violated = Status.INACCURATE, ("err_width",)
        message += f"; between the {t.size} nodes the path is {deviation:.4g} mm off: raise count"
    # the first passing point on a side of the box: the passing set may go on past it
    status, message = _on_edge(task, status, message, H, L, (H_grid[0], H_grid[-1], L_grid[0], L_grid[-1]))
    return clock.result(status, values, message=message, violated=violated,
                        diagnostics=diagnostics, arrays=deviation_arrays(task, H, L))


def minimax(task: LinkageFit | ProfileFit, *, count: Nodes = 1000, slots: Annotated[int, Interval(ge=1, le=4096)] = 8,
            max_rounds: Annotated[int, Interval(ge=1, le=10_000)] = 40,
            nlp: Literal["sqp", "ipopt"] = "sqp", widen: Annotated[int, Interval(ge=0, le=10)] = 3,
            starts: Annotated[int, Interval(ge=0, le=64)] = 4, certify: Literal["auto", "on", "off"] = "auto",
            gap_per_size: Annotated[float, Interval(gt=0, le=0.1)] = 4e-5,
            max_cells: Annotated[int, Interval(ge=64, le=10_000_000)] = 20_000) -> Result:
    """(H, L) in the box minimising the largest distance from COUNT nodes of the ideal path to
    the limaçon, as a CasADi NLP:

        minimise delta over H, L, delta, s_k   subject to, for each node P_k in the working set,
            (R(s_k) - P_k) . R'(s_k) = 0                     s_k is a foot point on the limaçon (10)
            -delta <= (R(s_k) - P_k) x R'(s_k) / |R'(s_k)| <= delta    signed distance to it

    The signed distance along the limaçon's own normal is exact at a foot point and smooth; the
    squared distance misleads IPOPT, and a distance measured along the ideal path's normal jumps
    where that normal grazes the limaçon near its double point (it pinned IPOPT at 0.073 mm).

    Only a handful of nodes are active at a minimax optimum, so the NLP carries `slots` nodes
    (built once per slot count and cached; the nodes are parameters). After each solve every node
    is measured by `foot_points`; the worst joins the kept set, and the round repeats, each s_k
    restarted on its nearest foot point, until the worst node is kept and no foot point the NLP
    followed has stopped being the nearest. The start matches the limaçon's double point and
    vertex curvature to the ideal path (`matched_linkage`), exact for h = 0. A cam of any shape
    (`ProfileFit`) is solved the same way on its own path, from a brute-force start.

    Lengths are solved in units of a / 25 mm (`_scale`), so the tolerances tuned on the paper's
    cam hold at every size. A side of the default box (not given) that the optimum lies on is
    widened BOX_WIDEN_FACTOR-fold and the NLP re-solved, up to `widen` times; an optimum still on
    one is LIMIT, naming the side. A side the user gave is a constraint: the message names it.

    `nlp` picks the back end of each round: "sqp" (CasADi's sqpmethod with qrqp, exact Hessian;
    a round it does not converge is re-solved by IPOPT) or "ipopt" only. Both reach the same
    (H, L) to ~1e-9 mm; SQP is ~7x faster per round (`mechopt bench cam-cutter`).

    Global over the box. A cam of any shape has no closed-form start, and its deviation has
    several basins (H > 0 and the mirrored crank H < 0, `models.cam_profile`): its box is the
    declared one (not widened), and the exchange rounds run from the brute-force start and from
    up to `starts` grid cells that are lower than their neighbours (`certificate.grid_starts`);
    the best dense deviation is kept. Then the certificate: a branch and bound on cells of
    (H, L) with first-order bounds (`certificate.box_lower_bound`, `bound.cell_bounds`) gives a
    lower bound on the deviation over the whole box at nodes of the path (CERTIFY_SPREAD spread,
    the answer's CERTIFY_WORST highest peaks). It stops as soon as every cell is within
    `gap_per_size` cam sizes (1e-3 mm on the paper's cam) of the answer; a gap above that after
    `max_cells` cells is not certified: a SOLVED or INFEASIBLE answer is then INACCURATE ("not
    certified global"). Inside a sweep it starts from the previous variant's cells where the path
    moved little (`_certify`). `diagnostics`: `global_gap_mm` (the answer's deviation less the
    bound), `global_lower_bound_mm`, `global_cells` (cells measured), `global_certified`,
    `global_warm_started`, `global_warm_moved_mm` (how far the earlier nodes were from this
    path's), `global_warm_reused_cells`, `global_warm_coarsened_mm`.

    `certify`: "on" certifies every answer; "off" none; "auto" (the default) a cam of any shape
    (`ProfileFit`: several basins, searched from several starts) and not the cardioid
    (`LinkageFit`: one start from its matched linkage, exact for h = 0), whose answer then says
    `global_certified` False, "not checked" (`cam-cutter/minimax` asks "on": the certificate
    costs less than two of its solves, `mechopt bench cam-cutter`).
    """
    _check_count(count)
    check_settings(minimax, slots=slots, max_rounds=max_rounds, nlp=nlp, widen=widen, starts=starts, certify=certify,
                   gap_per_size=gap_per_size, max_cells=max_cells)
    clock = Clock()
    t_start, t_end = task.t_start_rad, task.t_end_rad
    scale = _scale(task)
    t = np.linspace(t_start, t_end, count)
    px, py = (v / scale for v in task.path_point(t))
    pad, widened = BOX_PAD_PER_A, 0
    H, L = task.matched
    back_ends, unsolved, rounds_in_all = [], {}, 0
    general = isinstance(task, ProfileFit)        # a declared box, searched from several starts
    while True:
        box = task.bounds() if general else task.bounds(pad)
        seeds = [(H, L)] + (grid_starts(px[::max(1, count // 64)] * scale, py[::max(1, count // 64)] * scale,
                                        box, count=starts) if general else [])
        got = _best_of(px, py, task, box, seeds, count, slots, max_rounds, nlp)
        clock.build_s += got["build_s"]
        back_ends += got["back_ends"]
        unsolved |= {r + rounds_in_all: w for r, w in got["unsolved"].items()}     # rounds of the kept start
        rounds_in_all += got["rounds"]
        status, status_word = got["status"], got["status_word"]
        if status is Status.FAILED:
            break
        H, L = got["H"], got["L"]
        on_bounds = _bounds_hit(task, H, L, box)
        derived = [name for name in on_bounds if getattr(task, name) is None]
        if general or not derived or widened == widen or status is not Status.SOLVED:
            break
        pad, widened = pad * BOX_WIDEN_FACTOR, widened + 1     # the default box cut it short: widen, re-solve
    rounds = rounds_in_all
    if status is Status.FAILED:
        return clock.result(Status.FAILED, task.path_values(),
                            message=f"{back_ends[-1] if back_ends else nlp} failed ({status_word}) after {rounds} round(s)")
    deviation, where = got["deviation"], got["where"]
    where_xy = [float(v[0]) for v in task.path_point(np.array([where]))]
    certify = certify == "on" or (certify == "auto" and general)
    certificate = _certify(task, px * scale, py * scale, got["node_distances"] * scale, box, deviation, gap_per_size,
                           max_cells) \
        if certify else {"global_certified": False, "global_note": "not checked (certify = \"on\" checks it)"}
    nodes_max = got["nodes_max"] * scale
    message = (f"{status_word} after {rounds} exchange round(s) ({', '.join(back_ends)}), "
               f"{got['nlp_nodes']} nodes in the NLP" + (f", default box widened {widened} time(s)" if widened else ""))
    earlier = [f"round {r}: {word}" for r, word in unsolved.items() if r < rounds]
    if earlier:             # a later round started from it; only the last round's answer counts
        message += f"; earlier rounds not solved ({', '.join(earlier)})"
    if general and got["starts"] > 1:
        message += f", best of {got['starts']} starts"
    status, violated, message = _verdict(task, status, message, nodes_max, deviation, count, H, L, box, on_bounds)
    if violated:            # where the band is set: the path's point farthest from the best limaçon
        message += f"; set at t = {where:.6g} rad, (x, y) = ({where_xy[0]:.6g}, {where_xy[1]:.6g}) mm"
    if general and abs(H) < MIN_LINK_PER_SIZE * task.size_mm and status is Status.SOLVED:
        status = Status.LIMIT           # the circle about a fixed pivot: no crank, no mechanism
        message += f"; H = {H:.3g} mm: no crank (H = 0 is no mechanism), give a box that excludes it"
    if certify and not certificate["global_certified"] and status in (Status.SOLVED, Status.INFEASIBLE):
        status = Status.INACCURATE
        message += (f"; not certified global over the box: lower bound {certificate['global_lower_bound_mm']:.6g} mm, "
                    f"gap {certificate['global_gap_mm']:.3g} mm after {certificate['global_cells']} cells")
    elif certify:
        message += f"; global over the box to {certificate['global_gap_mm']:.2g} mm"
    return clock.result(status, {"H_mm": H, "L_mm": L, "max_deviation_mm": deviation, **task.path_values()},
                        message=message, violated=violated,
                        diagnostics={"nodes_max_deviation_mm": nodes_max, "nlp_nodes": got["nlp_nodes"],
                                     "kept_nodes": got["kept_nodes"], "exchange_rounds": rounds,
                                     "nlp_status": status_word, "nlp_back_ends": back_ends,
                                     "nlp_unsolved_rounds": {str(r): w for r, w in unsolved.items()},
                                     "active_bounds": on_bounds, "box_mm": [float(b) for b in box],
                                     "box_widenings": widened,
                                     "max_deviation_at_rad": where, "max_deviation_at_mm": where_xy,
                                     "t_finish_exact_rad": t_end, "starts": got["starts"]} | certificate,
                        arrays=deviation_arrays(task, H, L))


def _best_of(px, py, task, box, seeds, count, slots, max_rounds, nlp):
    """`_exchange_rounds` in the box [mm] from each seed (H, L) [mm]: the answer with the smallest
    dense deviation (`verified_deviation_on`), in mm, with that deviation and where it is; its
    rounds and unsolved rounds are its own, build time and back ends those of every start."""
    scale, best, build_s, back_ends = _scale(task), None, 0.0, []
    for H, L in seeds:
        H, L = (float(v) for v in np.clip((H, L), box[::2], box[1::2]))
        got = _exchange_rounds(px, py, task.size_mm / scale, np.divide(box, scale), H / scale, L / scale,
                               count, slots, max_rounds, nlp)
        build_s, back_ends = build_s + got["build_s"], back_ends + got["back_ends"]
        if got["status"] is Status.FAILED:
            best = best or got
            continue
        got["H"], got["L"] = got["H"] * scale, got["L"] * scale
        got["deviation"], got["where"] = verified_deviation_on(task.path_point, task.t_start_rad, task.t_end_rad,
                                                               got["H"], got["L"])
        if best is None or best["status"] is Status.FAILED or got["deviation"] < best["deviation"]:
            best = got
    return best | {"starts": len(seeds), "build_s": build_s, "back_ends": back_ends}


CERTIFY_SPREAD = 24     # nodes spread over the path in the bound's node set (48 cost 10-20 % more, the same verdicts)
CERTIFY_WORST = 16      # plus the answer's highest peaks, where the bound is tight
WARM_KEY = "cam_cutter.minimax.certificate"
WARM_COARSEN = 2.0         # earlier leaves narrower than this many node moves give way to cells that wide
WARM_KEEP_PER_GAP = 10.0   # a warm start only when the nodes moved at most this many gap targets


def _certify(task, px, py, dist, box, deviation, gap_per_size, max_cells):
    """The certificate of `minimax`'s answer: a lower bound on the deviation over the box from a
    node set (`certificate.box_lower_bound`), the gap, and whether it is within gap_per_size cam
    sizes. Node coordinates and `dist`, every node's distance to the answer's limaçon (the last
    exchange round's), in mm. In a sweep (`kit.warm`) it starts from the
    previous variant's leaves (`certificate.warm_cells`), their bounds less how far its nodes are
    from this path's nearest nodes, which join this node set; only where that move is at most
    WARM_KEEP_PER_GAP gap targets. The leaves narrower than WARM_COARSEN times that move (the fine
    ones about the earlier answer, all below the lowered target) give way to unmeasured cells that
    wide over their span (`warm_cells`). A farther move starts cold: the earlier partition alone
    (every cell measured again on this path's nodes, its fine leaves coarsened to the move) cost
    more than the cold grid on a what-if map of the cardioid (`mechopt bench cam-cutter`: 8 x 8,
    neighbours 0.1 mm apart, 24 821 cells against 16 120). `global_warm_reused_cells` counts the
    cells a warm start starts from, `global_warm_coarsened_mm` is that width."""
    padded = np.r_[-np.inf, dist, -np.inf]        # the answer's peaks, one node each: its active nodes
    peaks = np.flatnonzero((dist >= padded[:-2]) & (dist >= padded[2:]))
    worst = peaks[np.argsort(dist[peaks])[::-1][:CERTIFY_WORST]]
    nodes = np.unique(np.r_[np.linspace(0, px.size - 1, CERTIFY_SPREAD).round().astype(int), worst])
    target = gap_per_size * task.size_mm
    store, start, moved, reused = warm.store(), None, 0.0, 0
    before = store.get(WARM_KEY) if store is not None else None
    if before is not None:
        # each earlier node's nearest node of this path joins the set: the earlier bounds, less the
        # farthest of those moves, bound the largest distance over them (distance is 1-Lipschitz)
        apart = np.hypot(before["px"][:, None] - px[None, :], before["py"][:, None] - py[None, :])
        nearest = apart.argmin(axis=1)
        moved = float(apart[np.arange(nearest.size), nearest].max())
        if moved <= WARM_KEEP_PER_GAP * target:       # farther: a cold start costs less (module docstring)
            nodes = np.union1d(nodes, nearest)
            start = warm_cells(before["leaves"], moved, box, finest=WARM_COARSEN * moved)
            reused = int(start.H.size)
    got = box_lower_bound(px[nodes], py[nodes], box, deviation, gap=target, max_cells=max_cells, start=start)
    if store is not None:
        store[WARM_KEY] = {"px": px[nodes], "py": py[nodes], "leaves": got.leaves}
    gap = max(deviation - got.lower, 0.0)
    return {"global_lower_bound_mm": got.lower, "global_gap_mm": gap, "global_cells": got.cells,
            "global_certified": bool(got.complete or gap <= target), "global_gap_target_mm": target,
            "global_warm_started": got.warm_started, "global_warm_moved_mm": moved,
            "global_warm_reused_cells": reused, "global_warm_coarsened_mm": WARM_COARSEN * moved if reused else 0.0}


def _exchange_rounds(px, py, a, box, H, L, count, slots, max_rounds, nlp):
    """The exchange rounds of `minimax` in the box (H_lo, H_hi, L_lo, L_hi) from (H, L), every
    length in units of the cam scale (`_scale`), so its absolute tolerances hold at every size."""
    H_lo, H_hi, L_lo, L_hi = box
    kept: list[int] = []           # nodes that were ever active or worst: they never leave
    back_ends: list[str] = []      # which NLP back end answered each round
    unsolved: dict[int, str] = {}  # rounds whose NLP was not solved (the next one starts from it)
    build_s, status, status_word = 0.0, Status.FAILED, "not_run"
    every = feet = None            # every node's distance and foot point at the last round's (H, L)
    for rounds in range(1, max_rounds + 1):
        k = min(_slot_count(len(kept), slots), count)
        chosen = np.array(pad_nodes(kept, k, count))
        if rounds == 1:
            dist, s0 = foot_points(px[chosen], py[chosen], H, L, vertices=ROUND_VERTICES)
        else:                      # the last round measured every node at this (H, L)
            dist, s0 = every[chosen], feet[chosen]
        sol, status, status_word, used, built_s = solve_round(k, nlp, solver_of=_minimax_nlp, bounds=dict(
            x0=np.r_[H, L, dist.max(), s0], p=np.r_[px[chosen], py[chosen], a],
            lbx=np.r_[H_lo, L_lo, 0.0, np.full(k, -np.inf)], ubx=np.r_[H_hi, L_hi, np.inf, np.full(k, np.inf)],
            lbg=np.zeros(3 * k), ubg=np.r_[np.zeros(k), np.full(2 * k, np.inf)]))
        build_s += built_s
        back_ends.append(used)
        if status is not Status.SOLVED:
            unsolved[rounds] = f"{used} {status_word}"
        x = np.asarray(sol["x"]).ravel()
        if not np.all(np.isfinite(x)):         # whatever the back end said, no answer
            status, status_word = Status.FAILED, f"{status_word} with a non-finite point"
            break
        H, L = float(x[0]), float(x[1])
        followed = np.hypot(*(np.subtract(real_point(x[3:], H, L), (px[chosen], py[chosen]))))
        every, feet = foot_points(px, py, H, L, vertices=ROUND_VERTICES)
        worst = int(np.argmax(every))
        stale = followed > every[chosen] + 1e-9 * (1 + followed)
        active = chosen[every[chosen] >= every[chosen].max() - 1e-7]
        kept = list(dict.fromkeys(kept + [int(i) for i in active] + [worst]))
        if not stale.any() and every[worst] <= every[chosen].max() + 1e-9:
            break
    else:
        status, status_word = Status.LIMIT, "exchange_round_limit"
    return {"H": H, "L": L, "status": status, "status_word": status_word, "rounds": rounds,
            "back_ends": back_ends, "unsolved": unsolved, "build_s": build_s,
            "nodes_max": float(every.max()) if status is not Status.FAILED else float("nan"),
            "node_distances": every,
            "nlp_nodes": len(chosen), "kept_nodes": len(kept)}


def _scale(task):
    """The cam's size in units of the paper's (a / 25 mm, exactly 1 there): the solvers measure
    lengths in it, so tolerances tuned on the paper's cam hold for a 1 um and a 1 m cam alike."""
    return task.size_mm / PAPER_A_MM


def _bounds_hit(task, H, L, box):
    """Names of the box sides (H, L) lies on, to 1e-7 of the cam scale."""
    tol = 1e-7 * _scale(task)
    H_lo, H_hi, L_lo, L_hi = box
    return [name for name, hit in (("H_min_mm", H <= H_lo + tol), ("H_max_mm", H >= H_hi - tol),
                                   ("L_min_mm", L <= L_lo + tol), ("L_max_mm", L >= L_hi - tol)) if hit]


def _describe_bounds(task, H, L, box, names):
    """'H at its upper bound H_max_mm = 58 (given)' for each side in names."""
    value = dict(zip(("H_min_mm", "H_max_mm", "L_min_mm", "L_max_mm"), box))
    return ", ".join(f"{name[0]} at its {'lower' if 'min' in name else 'upper'} bound {name} = {value[name]:.6g} "
                     f"({'given' if getattr(task, name) is not None else 'the default box'})" for name in names)


def _on_edge(task, status, message, H, L, edges):
    """The lattice solvers' share of `_verdict`: an answer on a side of the box's lattice is named;
    on a side of the default box (not given) a SOLVED becomes LIMIT."""
    on_bounds = _bounds_hit(task, H, L, edges)
    if not on_bounds:
        return status, message
    message += f" ({_describe_bounds(task, H, L, task.bounds(), on_bounds)})"
    if status is Status.SOLVED and any(getattr(task, n) is None for n in on_bounds):
        status = Status.LIMIT
        message += ": the box, not the band, stopped it; give a wider box"
    return status, message


def _verdict(task, status, message, nodes_max, deviation, count, H, L, box, on_bounds):
    """The one status rule every fitting solver applies to its answer (H, L) in `box`:
    the back end's status stands unless it is SOLVED; then, in this order, an answer on a side
    of the default box is LIMIT (the box, not the physics, stopped it), nodes outside the band
    are INFEASIBLE, nodes within it but the dense path outside are INACCURATE. A side the user
    gave is a constraint: its answer keeps its status, and the message names it. Returns
    (status, violated, message)."""
    violated = ("err_width",) if max(nodes_max, deviation) > task.err_width_mm else ()
    derived = [n for n in on_bounds if getattr(task, n) is None]
    where = f" ({_describe_bounds(task, H, L, box, on_bounds)})" if on_bounds else ""
    if status is not Status.SOLVED:
        return status, violated, message + where
    if derived:
        return (Status.LIMIT, violated, f"{_describe_bounds(task, H, L, box, derived)}: the optimum may lie "
                f"outside; give a wider box (deviation there {deviation:.4g} mm)")
    if nodes_max > task.err_width_mm:
        return (Status.INFEASIBLE, violated, f"no linkage in the box keeps the path within err_width_mm="
                f"{task.err_width_mm}; best achievable {deviation:.4g} mm"
                + (f" (on {', '.join(on_bounds)}: {_describe_bounds(task, H, L, box, on_bounds)})" if on_bounds else ""))
    if deviation > task.err_width_mm:
        # within the band at every node, outside it between them: the nodes are too sparse
        return (Status.INACCURATE, violated, f"within err_width_mm={task.err_width_mm} at the {count} nodes "
                f"({nodes_max:.4g} mm) but {deviation:.4g} mm between them: raise count" + where)
    return status, violated, message + where


def robust(task: LinkageFit, *, count: Nodes = 1000, max_moves: Annotated[int, Interval(ge=1, le=100_000)] = 200) -> Result:
    """The STEP-lattice point whose worst node deviation over its manufacturing box
    (H +- STEP, L +- STEP) is smallest; reports that worst case, Euclidean-verified.

    The box is checked at its 3 x 3 lattice points (corners, edge midpoints, centre): on a box
    this small each node's deviation is close to linear in H and L, so its extremes sit at the
    corners (a test bounds what a finer box sampling adds). The search is a descent over lattice
    points from the minimax optimum; lattice deviations are memoised, neighbours share them.
    Global? Not certified (`diagnostics["global_certified"]` False): a descent stops at a local
    minimum of the worst case; a test compares it with every lattice point around the optimum.
    """
    _cardioid_only(task, "robust")
    _check_count(count)
    check_settings(robust, max_moves=max_moves)
    lattice = _lattice_indices(task)            # a box with no lattice point is refused before any work
    clock = Clock()
    best = minimax(task, count=count)
    if best.status not in (Status.SOLVED, Status.INFEASIBLE):
        return best
    step = task.step_mm
    t = np.linspace(0.0, task.t_finish_rad, count)
    px, py = ideal_point(t, task.a_mm, task.h_mm)
    memo = {}

    def deviation(i, j):
        if (i, j) not in memo:
            memo[i, j] = float(path_distance(px, py, i * step, j * step).max())
        return memo[i, j]

    def worst_case(i, j):
        return max(deviation(i + di, j + dj) for di in (-1, 0, 1) for dj in (-1, 0, 1))

    def inside(i, j):
        return lattice[0] <= i <= lattice[1] and lattice[2] <= j <= lattice[3]

    here = (int(np.clip(round(best.values["H_mm"] / step), lattice[0], lattice[1])),
            int(np.clip(round(best.values["L_mm"] / step), lattice[2], lattice[3])))
    for _ in range(max_moves):
        around = [(here[0] + di, here[1] + dj) for di in (-1, 0, 1) for dj in (-1, 0, 1)
                  if inside(here[0] + di, here[1] + dj)]
        step_to = min(around, key=lambda g: worst_case(*g))
        if step_to == here:
            break
        here = step_to
    H, L = here[0] * step, here[1] * step
    verified = max(verified_deviation(task.a_mm, task.h_mm, (here[0] + di) * step, (here[1] + dj) * step,
                                      task.t_finish_rad)[0] for di in (-1, 0, 1) for dj in (-1, 0, 1))
    nominal = verified_deviation(task.a_mm, task.h_mm, H, L, task.t_finish_rad)[0]
    status, violated, message = Status.SOLVED, (), f"lattice descent from the minimax optimum, {len(memo)} lattice points measured"
    if verified > task.err_width_mm:
        status, violated = Status.INFEASIBLE, ("err_width",)
        message = f"worst case over the manufacturing box {verified:.4g} mm exceeds err_width_mm={task.err_width_mm}"
    status, message = _on_edge(task, status, message, H, L, tuple(k * step for k in lattice))
    clock.build_s = best.timing.build_s
    return clock.result(status, {"H_mm": H, "L_mm": L, "max_deviation_mm": nominal, "worst_deviation_mm": verified,
                                 "t_finish_rad": task.t_finish_read_rad},
                        message=message, violated=violated,
                        diagnostics={"minimax_H_mm": best.values["H_mm"], "minimax_L_mm": best.values["L_mm"],
                                     "minimax_deviation_mm": best.values["max_deviation_mm"],
                                     "lattice_points": len(memo), "global_certified": False,
                                     "global_note": "a lattice descent: a local minimum of the worst case"},
                        arrays=deviation_arrays(task, H, L))


def evolve(task: LinkageFit, *, count: Nodes = 1000, popsize: Annotated[int, Interval(ge=5, le=1000)] = 15,
           tol: Tolerance = 1e-8, maxiter: Annotated[int, Interval(ge=1, le=100_000)] = 1000,
           seed: Annotated[int, Ge(0)] = 1) -> Result:
    """scipy's differential evolution on the largest node deviation, the peer a user would try.

    The whole population is measured per call through the batched quartic of `normal_deviation`
    (the paper's along-normal distance: a foot-point search would need a KD-tree per candidate
    and does not batch); at the optimum it agrees with the minimax NLP's foot-point distance to
    about 1e-5 mm. No polish: the objective is a maximum with kinks, where L-BFGS-B stalls.
    Its answer gets the status rule of `minimax` (`_verdict`): outside err_width_mm is INFEASIBLE
    with the best values kept, on a side of the default box LIMIT (no widening here)."""
    _cardioid_only(task, "evolve")
    _check_count(count)
    check_settings(evolve, popsize=popsize, tol=tol, maxiter=maxiter, seed=seed)
    clock = Clock()
    scale = _scale(task)
    t = np.linspace(0.0, task.t_finish_rad, count)
    px, py, nx, ny = nodes_and_normals(t, task.a_mm, task.h_mm)
    px, py = px / scale, py / scale                # in units of the cam scale, like minimax
    box = task.bounds()
    H_lo, H_hi, L_lo, L_hi = np.divide(box, scale)

    def objective(population):                 # shape (2, S): every candidate in one call
        H, L = population
        worst = np.abs(normal_deviation(px, py, nx, ny, H[:, None], L[:, None])).max(axis=-1)
        return np.where(np.isfinite(worst), worst, 1e9)    # a normal that misses the limaçon

    found = differential_evolution(objective, [(H_lo, H_hi), (L_lo, L_hi)],
                                   popsize=popsize, tol=tol, atol=0.0, maxiter=maxiter, seed=seed,
                                   polish=False, vectorized=True, updating="deferred")
    H, L = (float(v) * scale for v in found.x)
    deviation, where = verified_deviation(task.a_mm, task.h_mm, H, L, task.t_finish_rad)
    nodes_max = float(found.fun) * scale        # the along-normal node measure DE minimised
    status = Status.SOLVED if found.success else Status.LIMIT
    on_bounds = _bounds_hit(task, H, L, box)
    status, violated, message = _verdict(task, status, str(found.message), nodes_max, deviation, count,
                                         H, L, box, on_bounds)
    return clock.result(status, {"H_mm": H, "L_mm": L, "max_deviation_mm": deviation,
                                 "t_finish_rad": task.t_finish_read_rad},
                        message=message, violated=violated,
                        diagnostics={"generations": int(found.nit), "evaluations": int(found.nfev),
                                     "nodes_max_deviation_mm": nodes_max, "active_bounds": on_bounds,
                                     "max_deviation_at_rad": where}, arrays=deviation_arrays(task, H, L))


def check(task: LinkageCheck, *, count: Nodes = 1000,
          nodes: Literal["half_open", "closed", "open_start"] = "half_open") -> Result:
    """A given linkage (H, L) measured both ways: the dense Euclidean deviation over the
    continuous path (`max_deviation_mm`, the verdict) and the paper's segment test at COUNT nodes
    (`nodes_failing`, as `grid_scan` applies it). SOLVED when the deviation is within
    err_width_mm, INFEASIBLE (violated err_width) otherwise; `margin_mm` is the band left over
    (negative when exceeded). Swept over H_mm x L_mm it maps where a linkage meets the band."""
    t = _node_times(task, count, nodes)
    clock = Clock()
    H, L = task.H_mm, task.L_mm
    deviation, where = verified_deviation(task.a_mm, task.h_mm, H, L, task.t_finish_rad)
    ends = _segment_ends(t, task)
    passing = (limacon_implicit(ends[0], ends[1], H, L) < 0) != (limacon_implicit(ends[2], ends[3], H, L) < 0)
    failing = int(np.count_nonzero(~passing))
    within = deviation <= task.err_width_mm
    message = (f"{'within' if within else 'outside'} err_width_mm={task.err_width_mm}: {deviation:.4g} mm "
               f"at t = {where:.4f} rad; the paper's test fails at {failing} of {t.size} nodes")
    if within != (failing == 0):
        message += (" (its segment test is stricter than the distance near the double point)" if failing
                    else f" (the path leaves the band past the last node, t = {t[-1]:.4f} rad: nodes='{nodes}' "
                         "leaves t_FINISH out)" if where > t[-1]
                    else " (the path leaves the band between the nodes: raise count)")
    return clock.result(Status.SOLVED if within else Status.INFEASIBLE,
                        {"max_deviation_mm": deviation, "margin_mm": task.err_width_mm - deviation,
                         "nodes_failing": float(failing)},
                        message=message, violated=() if within else ("err_width",),
                        diagnostics={"max_deviation_at_rad": where, "nodes": int(t.size), "node_rule": nodes},
                        arrays=deviation_arrays(task, H, L))


_NLP_BUILDS = BuildCache("cam_cutter.minimax_nlp", maxsize=64, per_thread=True)    # CasADi solvers: see BuildCache


def _minimax_nlp(k: int, method: str):
    """The minimax NLP with k node slots for `method` ("ipopt" or "sqp") and the seconds its
    build took now (0 when cached): nodes are parameters, so each is built once per process."""
    return _NLP_BUILDS.get((k, method), lambda: _build_minimax_nlp(k, method))


def _build_minimax_nlp(k, method):
    H, L, delta, s = ca.SX.sym("H"), ca.SX.sym("L"), ca.SX.sym("delta"), ca.SX.sym("s", k)
    p = ca.SX.sym("p", 2 * k + 1)
    g = foot_and_band(s, H, L, p[:k], p[k:2 * k], p[2 * k], delta)
    nlp = {"x": ca.vertcat(H, L, delta, s), "p": p, "f": delta, "g": g}
    return ca.nlpsol("cam_minimax", "sqpmethod" if method == "sqp" else "ipopt", nlp, NLP_OPTIONS[method])








def _slot_count(needed, minimum):
    k = max(minimum, 1)
    while k < needed:
        k *= 2
    return k





def _node_times(task, count, nodes):
    """The paper's nodes t_i = i t_FINISH / COUNT, t_FINISH as read (`t_finish_read_rad`), for
    the i that the rule `nodes` names (NODE_RULES)."""
    _check_count(count)
    if nodes not in NODE_RULES:
        raise SettingError(f"nodes={nodes!r}: allowed {', '.join(NODE_RULES)}", key="nodes")
    first, extra = NODE_RULES[nodes]
    return np.arange(first, count + extra) * (task.t_finish_read_rad / count)


def _cardioid_only(task, name):
    """The lattice and the along-normal solvers know the cardioid's closed forms only."""
    if isinstance(task, ProfileFit):
        raise ModelError(f"{name} solves the cardioid (LinkageFit) only; a cam of any shape (ProfileFit) is "
                         "solved by cam_cutter.minimax", key="solver")


def _check_count(count):
    if not isinstance(count, (int, np.integer)) or count < 1:
        raise SettingError(f"count={count!r} must be a whole number >= 1 (nodes on the ideal path)", key="count")


def _lattice_indices(task):
    """(i_lo, i_hi, j_lo, j_hi): the box's STEP lattice as integer multiples H = i STEP, L = j STEP,
    counted without allocating anything; a box holding no lattice point is an error."""
    H_lo, H_hi, L_lo, L_hi = task.bounds()
    step = task.step_mm
    index = (math.ceil(H_lo / step - 1e-9), math.floor(H_hi / step + 1e-9),
             math.ceil(L_lo / step - 1e-9), math.floor(L_hi / step + 1e-9))
    if index[0] > index[1] or index[2] > index[3]:
        raise ModelError(f"the box H {H_lo:g}..{H_hi:g}, L {L_lo:g}..{L_hi:g} mm holds no multiple of "
                         f"step_mm={step}", key="step_mm")
    return index


def _lattice(task):
    """H and L on the STEP lattice of the box, as integer multiples so no rounding drifts [mm].
    Its size is counted first: a lattice past GRID_POINT_LIMIT is refused before any allocation."""
    H_lo, H_hi, L_lo, L_hi = task.bounds()
    step = task.step_mm
    i_lo, i_hi, j_lo, j_hi = _lattice_indices(task)
    points = (i_hi - i_lo + 1) * (j_hi - j_lo + 1)            # Python ints: no overflow
    if points > GRID_POINT_LIMIT:
        raise ModelError(f"the box H {H_lo:g}..{H_hi:g} mm, L {L_lo:g}..{L_hi:g} mm has {points:,} "
                         f"points at step_mm={step} ({points * 16 / 2**30:,.3g} GiB as float64 (H, L) pairs); "
                         f"the scan allows {GRID_POINT_LIMIT:,}: narrow H_min_mm .. L_max_mm or coarsen step_mm",
                         key="step_mm")
    H = np.arange(i_lo, i_hi + 1) * step
    L = np.arange(j_lo, j_hi + 1) * step
    return np.round(H, 9), np.round(L, 9)


def _segment_ends(t, task):
    """(x_in, y_in, x_out, y_out) of each node's error segment, ends below the x axis pulled back
    along the segment to the axis (the paper's trimming)."""
    px, py = ideal_point(t, task.a_mm, task.h_mm)
    nx, ny = ideal_normal(t)
    ends = []
    for side in (-1.0, 1.0):
        reach = np.full(t.shape, task.err_width_mm)
        down = py + side * reach * ny < 0
        reach = np.where(down, -py / np.where(down, side * ny, 1.0), reach)
        ends += [px + side * reach * nx, py + side * reach * ny]
    ends[1], ends[3] = np.maximum(ends[1], 0.0), np.maximum(ends[3], 0.0)
    return ends


PROBE_LEVELS = 12      # probes at err_width / 2^k, k = 0 .. 11, either side of the node


def _scan(H_grid, L_grid, ends, order, crossed=None):
    """The lattice points (H, L) whose every node passes: one end of its segment inside the
    limaçon, one outside (the paper's test); with `crossed(i, H, L, inside)`, a segment whose
    ends lie on one side passes where that says it is crossed (twice). Nodes in `order`."""
    passing = []
    for rows in np.array_split(np.arange(H_grid.size), max(1, H_grid.size * L_grid.size // 2_000_000)):
        H, L = (g.ravel() for g in np.meshgrid(H_grid[rows], L_grid, indexing="ij"))
        for i in order:
            inner = limacon_implicit(ends[0][i], ends[1][i], H, L) < 0
            keep = inner != (limacon_implicit(ends[2][i], ends[3][i], H, L) < 0)
            blind = np.flatnonzero(~keep)
            if crossed is not None and blind.size:
                keep[blind] = crossed(i, H[blind], L[blind], inner[blind])
            H, L = H[keep], L[keep]
            if H.size == 0:
                break
        passing.append(np.column_stack([H, L]))
    return np.concatenate(passing)


def _crossed_twice(t, task, ends):
    """`crossed` for `_scan`: whether node i's segment, both ends on one side of the limaçons
    (H, L), meets them: not where `_clear_of_segment` rules it out, else where a probe of
    `_segment_probes` lies on the other side."""
    normals = nodes_and_normals(t, task.a_mm, task.h_mm)
    reach = np.maximum(np.hypot(ends[0] - normals[0], ends[1] - normals[1]),
                       np.hypot(ends[2] - normals[0], ends[3] - normals[1]))
    px, py = _segment_probes(t, task, ends)

    def crossed(i, H, L, inside):
        near = np.flatnonzero(~_clear_of_segment(i, normals, reach, H, L, inside))
        out = np.zeros(H.shape, dtype=bool)
        probe = limacon_implicit(px[i][:, None], py[i][:, None], H[near], L[near]) < 0
        out[near] = np.any(probe != inside[near], axis=0)
        return out
    return crossed


def _clear_of_segment(i, nodes, reach, H, L, inside):
    """True where node i's segment surely does not meet the limaçon (H, L): along the normal,
    F(P + d n) = d^4 + c3 d^3 + c2 d^2 + c1 d + c0 (`normal_quartic`) keeps the sign of its ends
    (`inside`: negative) for every |d| <= reach, bounded term by term. Settles cheaply the points
    far from the curve, so only those near it are probed."""
    c0, c1, c2, c3 = normal_quartic(nodes[0][i], nodes[1][i], nodes[2][i], nodes[3][i], H, L)
    r = reach[i]
    spread = np.abs(c1) * r + np.abs(c2) * r * r + np.abs(c3) * r ** 3
    return np.where(inside, c0 + spread + r ** 4 < 0, c0 - spread > 0)


def _segment_probes(t, task, ends):
    """Points of each node's error segment between its ends, for the segments whose two ends lie
    on one side of the limaçon: the node itself and the points at err_width / 2^k along either
    half (k = 1 .. PROBE_LEVELS - 1, within the trimmed segment). A segment wider than the
    limaçon spans it and is crossed twice, which the paper's one-end-in test cannot see (issue
    21: every point failed at err_width_mm = 100); a probe on the other side shows the crossing.
    Returns (x, y), each of shape (nodes, probes)."""
    px, py = ideal_point(t, task.a_mm, task.h_mm)
    f = 0.5 ** np.arange(1, PROBE_LEVELS)
    xs = [px[:, None]] + [px[:, None] + f * (end[:, None] - px[:, None]) for end in (ends[0], ends[2])]
    ys = [py[:, None]] + [py[:, None] + f * (end[:, None] - py[:, None]) for end in (ends[1], ends[3])]
    return np.hstack(xs), np.hstack(ys)


def _finish_node_report(task, H, L, t_finish):
    """Whether the node at t_FINISH itself would pass for (H, L), and the nearest crossing of its
    normal above and below the axis: the reason the node rule matters."""
    px, py, nx, ny = nodes_and_normals(np.array([t_finish]), task.a_mm, task.h_mm)
    roots = normal_crossings(px, py, nx, ny, H, L)[0]
    d = roots.real[np.abs(roots.imag) < 1e-7 * _scale(task)]
    above = d[py[0] + d * ny[0] >= 0]
    ends = _segment_ends(np.array([t_finish]), task)
    passes = bool((limacon_implicit(ends[0], ends[1], H, L) < 0) != (limacon_implicit(ends[2], ends[3], H, L) < 0))
    return {"passes": passes,
            "nearest_crossing_mm": float(d[np.argmin(np.abs(d))]) if d.size else None,
            "nearest_crossing_above_axis_mm": float(above[np.argmin(np.abs(above))]) if above.size else None}


def _even_crossings(t, task, H, L):
    """Nodes whose (untrimmed) error segment the limaçon crosses twice or more: there the
    paper's one-end-in, one-end-out test is blind (wide error widths, Sec. IV)."""
    px, py, nx, ny = nodes_and_normals(t, task.a_mm, task.h_mm)
    roots = normal_crossings(px, py, nx, ny, H, L)
    inside = (np.abs(roots.imag) < 1e-7 * _scale(task)) & (np.abs(roots.real) <= task.err_width_mm)
    return int(np.count_nonzero(inside.sum(axis=-1) >= 2))
