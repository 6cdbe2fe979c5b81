"""A readjustable torch-guiding linkage: one frame distance H for a family of
cardioid cams, the wing length L set per cam.

`readjustable` solves

    minimise delta over H, L_1 .. L_M, delta, s_ik   subject to, for member i and node k,
        (R(s_ik; H, L_i) - P_ik) . R'(s_ik) = 0                          foot point on limaçon i
        -delta <= (R - P_ik) x R' / |R'| <= delta                         signed distance to it

as one NLP with an exchange of nodes per member, as `fit.minimax` does for one cam (same
constraints, same SQP/IPOPT back ends): each member keeps its own working set, and a round
adds every member's worst node until no member has a node worse than its working set.

`served_range` then asks the converse: for one fixed H, how far can a go (below and above the
family) before the best L for some nozzle h leaves the band? Each trial a is a small family NLP
with H fixed, its deviation verified densely; the ends are bracketed outwards and bisected.
"""
from typing import Literal

import casadi as ca
import numpy as np

from mechopt.kit.cache import BuildCache
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, check_settings
from mechopt.models.cam_cutter import (
    PAPER_A_MM,
    ToolFamily,
    finish_angle,
    ideal_point,
    matched_linkage,
    real_point,
)
from mechopt.solvers.cam_cutter.deviation import foot_points, verified_deviation
from mechopt.solvers.cam_cutter.problem import NLP_OPTIONS, ROUND_VERTICES, foot_and_band, pad_nodes, solve_round

__all__ = ["readjustable", "family_minimax", "served_range", "fixed_H_deviation", "evolve_family"]

BOX_PAD_PER_A = 0.5          # default box: the members' matched linkages +- a/2
BOX_WIDEN_FACTOR = 4.0
SEARCH_FACTOR = 4.0          # served_range looks for the ends within a_min / 4 .. a_max * 4
_BUILDS = BuildCache("cam_cutter.family_nlp", maxsize=32, per_thread=True)    # CasADi solvers: see BuildCache
# fit.minimax's back ends; qrqp's own iterations capped: on a family's first, cold round an
# uncapped active-set QP can cycle for minutes (15 cams: 36 s) where IPOPT takes 0.2 s
_OPTIONS = {"ipopt": NLP_OPTIONS["ipopt"],
            "sqp": NLP_OPTIONS["sqp"] | {"qpsol_options": NLP_OPTIONS["sqp"]["qpsol_options"] | {"max_iter": 50}}}


def _build(members, k, method):
    """The family NLP with `members` limaçons sharing H, k node slots each."""
    n = members * k
    H, L, delta, s = ca.SX.sym("H"), ca.SX.sym("L", members), ca.SX.sym("delta"), ca.SX.sym("s", n)
    p = ca.SX.sym("p", 2 * n + 1)
    L_slot = ca.vertcat(*[L[i] for i in range(members) for _ in range(k)])
    g = foot_and_band(s, H, L_slot, p[:n], p[n:2 * n], p[2 * n], delta)
    nlp = {"x": ca.vertcat(H, L, delta, s), "p": p, "f": delta, "g": g}
    return ca.nlpsol("cam_family", "sqpmethod" if method == "sqp" else "ipopt", nlp, _OPTIONS[method])


def _family_nlp(shape, method):
    """The built family NLP for shape (members, k) and the seconds its build took now (0 cached)."""
    return _BUILDS.get((*shape, method), lambda: _build(*shape, method))


def family_minimax(members, box, H0, L0, *, count=400, slots=4, max_rounds=40, nlp="ipopt"):
    """The exchange rounds for cams `members` [(a, h), ...] in the box (H_lo, H_hi, L_lo, L_hi)
    (L bounds per member: arrays) from H0, L0 [mm]. Returns a dict: H, L (array), status, word,
    rounds, build_s, nodes_max (per member), back_ends, box."""
    M = len(members)
    scale = float(np.mean([a for a, _ in members])) / PAPER_A_MM
    paths = []
    for a, h in members:
        t = np.linspace(0.0, finish_angle(a, h), count)
        paths.append([v / scale for v in ideal_point(t, a, h)])
    H, L = H0 / scale, np.asarray(L0, dtype=float) / scale
    H_lo, H_hi = box[0] / scale, box[1] / scale
    L_lo, L_hi = np.asarray(box[2], dtype=float) / scale, np.asarray(box[3], dtype=float) / scale
    kept = [[] for _ in range(M)]
    every = [foot_points(px, py, H, L[i], vertices=ROUND_VERTICES) for i, (px, py) in enumerate(paths)]
    build_s, back_ends, status, word = 0.0, [], Status.FAILED, "not_run"
    for rounds in range(1, max_rounds + 1):
        k = max(slots, max(len(w) for w in kept))
        k = 1 << (k - 1).bit_length()                     # powers of two: few distinct builds
        k = min(k, count)
        chosen = [np.array(pad_nodes(kept[i], k, count)) for i in range(M)]
        px = np.concatenate([paths[i][0][c] for i, c in enumerate(chosen)])
        py = np.concatenate([paths[i][1][c] for i, c in enumerate(chosen)])
        dist = np.concatenate([every[i][0][c] for i, c in enumerate(chosen)])
        s0 = np.concatenate([every[i][1][c] for i, c in enumerate(chosen)])
        n = M * k
        sol, status, word, used, built = solve_round((M, k), nlp, solver_of=_family_nlp, cold=rounds == 1, bounds=dict(
            x0=np.r_[H, L, dist.max(), s0], p=np.r_[px, py, PAPER_A_MM],
            lbx=np.r_[H_lo, L_lo, 0.0, np.full(n, -np.inf)], ubx=np.r_[H_hi, L_hi, np.inf, np.full(n, np.inf)],
            lbg=np.zeros(3 * n), ubg=np.r_[np.zeros(n), np.full(2 * n, np.inf)]))
        build_s += built
        back_ends.append(used)
        x = np.asarray(sol["x"]).ravel()
        if not np.all(np.isfinite(x)):
            status, word = Status.FAILED, f"{word} with a non-finite point"
            break
        H, L = float(x[0]), x[1:1 + M].copy()
        s = x[2 + M:].reshape(M, k)
        done = True
        for i, (qx, qy) in enumerate(paths):
            every[i] = foot_points(qx, qy, H, L[i], vertices=ROUND_VERTICES)
            here = every[i][0][chosen[i]]
            followed = np.hypot(*np.subtract(real_point(s[i], H, L[i]), (qx[chosen[i]], qy[chosen[i]])))
            worst = int(np.argmax(every[i][0]))
            active = chosen[i][here >= here.max() - 1e-7]
            kept[i] = list(dict.fromkeys(kept[i] + [int(j) for j in active] + [worst]))
            if np.any(followed > here + 1e-9 * (1 + followed)) or every[i][0][worst] > here.max() + 1e-9:
                done = False
        if done:
            break
    else:
        status, word = Status.LIMIT, "exchange_round_limit"
    nodes_max = np.array([e[0].max() for e in every]) * scale
    return {"H": H * scale, "L": L * scale, "status": status, "word": word, "rounds": rounds,
            "build_s": build_s, "nodes_max": nodes_max, "back_ends": back_ends, "slots": k}


def _default_box(members, pad_per_a, H_min, H_max):
    """(H_lo, H_hi, L_lo[], L_hi[]) around the members' matched linkages, and the start (H0, L0[])."""
    matched = np.array([matched_linkage(a, h) for a, h in members])
    a = np.array([m[0] for m in members])
    span = matched.sum(axis=1)                        # H + L: the double point, kept at the start
    H0 = float(np.clip(np.mean(matched[:, 0]), H_min or 0.0, H_max or np.inf))
    pad = pad_per_a * a
    H_lo = H_min if H_min is not None else max(float(np.min(matched[:, 0] - pad)), 0.01 * a.min())
    H_hi = H_max if H_max is not None else float(np.max(matched[:, 0] + pad))
    L0 = span - H0
    spread = H_hi - H_lo
    L_lo = np.maximum(L0 - pad - spread, 0.01 * a)
    L_hi = np.maximum(L0 + pad + spread, L_lo + pad)     # an H far from the cam's own leaves L0 <= 0
    return (H_lo, H_hi, L_lo, L_hi), H0, np.clip(L0, L_lo, L_hi)


def _on_sides(H, L, box, scale):
    tol = 1e-7 * scale
    sides = [name for name, hit in (("H_min_mm", H <= box[0] + tol), ("H_max_mm", H >= box[1] - tol)) if hit]
    low, high = np.flatnonzero(L <= box[2] + tol), np.flatnonzero(L >= box[3] - tol)
    return sides + [f"L_min[{i}]" for i in low] + [f"L_max[{i}]" for i in high]


def _fit_family(members, err_width, H_min, H_max, count, slots, max_rounds, nlp, widen):
    """Exchange rounds in the default box, widened while the optimum lies on a derived side."""
    scale = float(np.mean([a for a, _ in members])) / PAPER_A_MM
    pad, widened, build_s, back_ends, rounds = BOX_PAD_PER_A, 0, 0.0, [], 0
    box, H0, L0 = _default_box(members, pad, H_min, H_max)
    while True:
        got = family_minimax(members, box, H0, L0, count=count, slots=slots, max_rounds=max_rounds, nlp=nlp)
        build_s += got["build_s"]
        back_ends += got["back_ends"]
        rounds += got["rounds"]
        if got["status"] is Status.FAILED:
            break
        sides = _on_sides(got["H"], got["L"], box, scale)
        derived = [s for s in sides if not ((s == "H_min_mm" and H_min is not None)
                                            or (s == "H_max_mm" and H_max is not None))]
        got["sides"], got["derived_sides"] = sides, derived
        if not derived or widened == widen or got["status"] is not Status.SOLVED:
            break
        pad, widened = pad * BOX_WIDEN_FACTOR, widened + 1
        box, _, _ = _default_box(members, pad, H_min, H_max)
        H0, L0 = got["H"], np.clip(got["L"], box[2], box[3])
    got |= {"build_s": build_s, "back_ends": back_ends, "rounds": rounds, "widened": widened, "box": box}
    return got


def readjustable(task: ToolFamily, *, count: Annotated[int, Interval(ge=20, le=100_000)] = 400,
                 slots: Annotated[int, Interval(ge=1, le=256)] = 4,
                 max_rounds: Annotated[int, Interval(ge=1, le=1000)] = 40,
                 widen: Annotated[int, Interval(ge=0, le=10)] = 3,
                 nlp: Literal["ipopt", "sqp"] = "ipopt", served: bool = True) -> Result:
    """One H for the whole family, L per cam, minimising the family's worst deviation.

    Values: `H_mm`; `worst_deviation_mm` (the dense Euclidean check of `deviation`, the largest
    over the members); `worst_member_a_mm`, `worst_member_h_mm` and `worst_at_rad` (the member
    and the t that set it); with `served`, `a_served_min_mm` .. `a_served_max_mm`, the widest
    range of a around the family that this H serves within err_width_mm for every h
    (`served_range`). Arrays: the setting table `a_mm`, `h_mm`, `L_mm`, `deviation_mm` per member.

    Status: on a side of the default box after `widen` widenings LIMIT (naming it); nodes outside
    the band INFEASIBLE with the best band kept and where it is set; nodes within but the dense
    path outside INACCURATE; a served range that reaches its search limit LIMIT.

    Global? Not certified: the exchange rounds start once, from the members' matched linkages
    (`diagnostics["global_certified"]` is False); tests compare the answer with a brute-force
    search over H (each cam's L gridded) for the shipped scenes.

    `nlp`: IPOPT by default. Unlike the one-cam minimax, SQP loses here: its dense active-set QP
    grows with the members (20 cams x 4 slots: ~1 s a round against IPOPT's ~0.02 s).
    """
    check_settings(readjustable, count=count, slots=slots, max_rounds=max_rounds, widen=widen, nlp=nlp)
    clock = Clock()
    members = task.members
    got = _fit_family(members, task.err_width_mm, task.H_min_mm, task.H_max_mm, count, slots, max_rounds, nlp, widen)
    clock.build_s = got["build_s"]
    if got["status"] is Status.FAILED:
        return clock.result(Status.FAILED, {},
                            message=f"{got['back_ends'][-1]} failed ({got['word']}) after {got['rounds']} round(s)")
    H, L = got["H"], got["L"]
    checks = [verified_deviation(a, h, H, L_i, finish_angle(a, h)) for (a, h), L_i in zip(members, L)]
    deviation = np.array([c[0] for c in checks])
    worst = int(np.argmax(deviation))
    nodes_max = float(got["nodes_max"].max())
    values = {"H_mm": H, "worst_deviation_mm": float(deviation[worst]),
              "worst_member_a_mm": members[worst][0], "worst_member_h_mm": members[worst][1],
              "worst_at_rad": float(checks[worst][1])}
    status, violated = got["status"], ()
    where = (f"member a = {members[worst][0]:.6g} mm, h = {members[worst][1]:g} mm at t = {checks[worst][1]:.5g} rad")
    message = (f"{got['word']} after {got['rounds']} exchange round(s), {len(members)} cams x {got['slots']} node slots"
               + (f", default box widened {got['widened']} time(s)" if got["widened"] else ""))
    if status is Status.SOLVED and got.get("derived_sides"):
        status = Status.LIMIT
        message = (f"the optimum lies on the default box ({', '.join(got['derived_sides'])}) after "
                   f"{got['widened']} widening(s): the box, not the band, stopped it")
    elif status is Status.SOLVED and nodes_max > task.err_width_mm:
        status, violated = Status.INFEASIBLE, ("err_width",)
        message = (f"no single H keeps every cam within err_width_mm={task.err_width_mm}; best achievable "
                   f"family band {deviation[worst]:.4g} mm, set by {where}")
    elif status is Status.SOLVED and deviation[worst] > task.err_width_mm:
        status, violated = Status.INACCURATE, ("err_width",)
        message += f"; within the band at the {count} nodes but {deviation[worst]:.4g} mm between them: raise count"
    else:
        message += f"; worst {deviation[worst]:.4g} mm at {where}"
    given = [side for side in got.get("sides", []) if side not in got.get("derived_sides", [])]
    if given:               # a bound the user gave is a constraint: the answer stands, named
        message += "; " + ", ".join(f"H at its given bound {side} = {getattr(task, side):g}" for side in given)
    diagnostics = {"exchange_rounds": got["rounds"], "nlp_back_ends": got["back_ends"],
                   "nodes_max_deviation_mm": nodes_max, "active_sides": got.get("sides", []),
                   "box_widenings": got["widened"], "members": len(members),
                   # one start (the members' matched linkages); a brute-force search over H agrees (tests)
                   "global_certified": False, "global_note": "local: no lower bound over the box is computed"}
    if served and status is Status.SOLVED:
        low, high, info = served_range(task, H, count=count, slots=slots, max_rounds=max_rounds)
        diagnostics["served_range"] = info
        if low is None or high is None:
            status = Status.LIMIT
            message += f"; served range not determined: {info['note']} (search limit a_min / {SEARCH_FACTOR:g} .. " \
                       f"a_max x {SEARCH_FACTOR:g})"
        else:
            values |= {"a_served_min_mm": low, "a_served_max_mm": high}
    return clock.result(status, values, message=message, violated=violated, diagnostics=diagnostics,
                        arrays={"a_mm": [m[0] for m in members], "h_mm": [m[1] for m in members], "L_mm": L,
                                "deviation_mm": deviation})


def fixed_H_deviation(a, h_values, H, *, count=400, slots=4, max_rounds=40):
    """The worst deviation [mm] over the nozzles h of cam size a when H is fixed and each L is
    best for its h (a family NLP with H's bounds pinned), verified densely; and the L per h."""
    members = tuple((float(a), h) for h in h_values)
    box, _, L0 = _default_box(members, BOX_PAD_PER_A * BOX_WIDEN_FACTOR, H, H)
    got = family_minimax(members, box, H, L0, count=count, slots=slots, max_rounds=max_rounds)
    if got["status"] is not Status.SOLVED:
        return None, got["L"]
    return max(verified_deviation(a, h, H, L_i, finish_angle(a, h))[0] for (a, h), L_i in zip(members, got["L"])), got["L"]


def served_range(task: ToolFamily, H, *, count=400, slots=4, max_rounds=40, tol_mm=None):
    """(a_low, a_high, info): the widest interval of a around the family over which the fixed H
    keeps every nozzle h within err_width_mm (each with its best L), ends to `tol_mm` (default
    a_min / 2500, the paper's lattice step scaled). An end not found within the search limit
    (a_min / SEARCH_FACTOR but above the widest kerf, a_max * SEARCH_FACTOR) is None; `info`
    says which; so is a range whose family end is not served itself. The deviation is taken to
    rise monotonically away from the family (a test samples it)."""
    band, tol = task.err_width_mm, tol_mm or task.a_min_mm / 2500
    evaluations = []

    def serves(a):
        d, _ = fixed_H_deviation(a, task.h_values_mm, H, count=count, slots=slots, max_rounds=max_rounds)
        evaluations.append((float(a), d))
        return d is not None and d <= band

    ends, notes = [], []
    for a in dict.fromkeys((task.a_min_mm, task.a_max_mm)):
        if not serves(a):       # the range grows from the family: it must be served itself
            return None, None, {"evaluations": len(evaluations), "tol_mm": tol,
                                "note": f"the family's own cam a = {a:g} mm is not served at H = {H:.6g} mm"}
    lowest = max(task.a_min_mm / SEARCH_FACTOR, 1.01 * max(task.h_values_mm))     # a cam must outgrow its kerf
    for inner, limit in ((task.a_min_mm, lowest), (task.a_max_mm, task.a_max_mm * SEARCH_FACTOR)):
        good, step = inner, 0.05 * inner
        bad = None
        while bad is None:
            trial = good + step if limit > inner else good - step
            if (trial - limit) * (limit - inner) > 0:       # past the limit: try the limit itself
                trial = limit
            if serves(trial):
                if trial == limit:
                    notes.append(f"a = {limit:.6g} mm still served")
                    break
                good, step = trial, step * 2
            else:
                bad = trial
        if bad is None:
            ends.append(None)
            continue
        while abs(bad - good) > tol:
            mid = 0.5 * (good + bad)
            good, bad = (mid, bad) if serves(mid) else (good, mid)
        ends.append(float(good))
    info = {"evaluations": len(evaluations), "tol_mm": tol, "note": "; ".join(notes) or "both ends found"}
    return ends[0], ends[1], info


def evolve_family(task: ToolFamily, *, count: Annotated[int, Interval(ge=20, le=100_000)] = 400,
                  target_mm: float | None = None, popsize: Annotated[int, Interval(ge=5, le=1000)] = 15,
                  maxiter: Annotated[int, Interval(ge=1, le=100_000)] = 3000, seed: int = 1) -> Result:
    """The peer: scipy's differential evolution over (H, L_1 .. L_M) on the family's largest node
    deviation (the batched along-normal quartic of `normal_deviation`, as `fit.evolve` does), in
    the default box. With `target_mm` it stops once the best member of the population is within
    it (to time it to another method's answer); LIMIT if maxiter ends first. Verified densely."""
    from scipy.optimize import differential_evolution

    from mechopt.models.cam_cutter import ideal_normal
    from mechopt.solvers.cam_cutter.deviation import normal_deviation

    clock = Clock()
    members = task.members
    box, _, _ = _default_box(members, BOX_PAD_PER_A, task.H_min_mm, task.H_max_mm)
    nodes = []
    for a, h in members:
        t = np.linspace(0.0, finish_angle(a, h), count)
        nodes.append((*ideal_point(t, a, h), *ideal_normal(t)))
    px, py, nx, ny = (np.stack([n[j] for n in nodes]) for j in range(4))      # (M, count)

    def objective(population):                  # (M + 1, S): every candidate in one call
        H, L = population[0], population[1:]
        d = normal_deviation(px[None], py[None], nx[None], ny[None], H[:, None, None], L.T[:, :, None])
        worst = np.abs(d).max(axis=(1, 2))
        return np.where(np.isfinite(worst), worst, 1e9)

    reached = {}

    def stop(intermediate_result):
        reached["best"] = float(intermediate_result.fun)
        return target_mm is not None and intermediate_result.fun <= target_mm

    found = differential_evolution(objective, [(box[0], box[1])] + list(zip(box[2], box[3])), popsize=popsize,
                                   tol=0.0, atol=0.0, maxiter=maxiter, seed=seed, polish=False, vectorized=True,
                                   updating="deferred", callback=stop)
    H, L = float(found.x[0]), found.x[1:]
    deviation = max(verified_deviation(a, h, H, L_i, finish_angle(a, h))[0] for (a, h), L_i in zip(members, L))
    hit = target_mm is not None and found.fun <= target_mm
    return clock.result(Status.SOLVED if hit or (target_mm is None and found.success) else Status.LIMIT,
                        {"H_mm": H, "worst_deviation_mm": deviation, "nodes_max_deviation_mm": float(found.fun)},
                        message=str(found.message),
                        diagnostics={"generations": int(found.nit), "evaluations": int(found.nfev)},
                        arrays={"L_mm": L})
