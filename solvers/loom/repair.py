"""Check and repair after the LP: the optimum evaluated on the exact rebound and
contact stress, re-cut and re-solved until they hold; `exact_amplitude_bound` where the wavy
rebound's tangent cannot be trusted."""
import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
from scipy.optimize import brentq

from mechopt.kit import store
from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Interval, Tolerance
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.loom_limits import stress_bound_deg, stress_MPa
from mechopt.solvers.cyclogram.plan import plan_cyclogram
from mechopt.solvers.stop_impact.law import chain_rebounds_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox

# the exact law a(t, n) the loom's solvers evaluate: the chain by its batch path (one name, where a
# test puts another law in its place)
rebound_amplitude_mm = chain_rebounds_mm


def exact_amplitude_mm(task: Cyclogram, t_deg, speed_rpm=None, lost=None):
    """The lever's exact first rebound a(t, n) [mm] (the chain cam -> approach velocity -> impact
    -> eq. (2), solvers/stop_impact/law.py) at `speed_rpm`, by default the task's speed;
    vectorised over t and n, the rises by the chain's batch path (`chain_rebounds_mm`: exact,
    CVODES' per-point rise agrees to its own error, ~1e-10). Where the roller leaves its cam:
    RollerLeftCam, or `lost`."""
    speed = task.speed_rpm if speed_rpm is None else speed_rpm
    if speed is None:
        raise ModelError("speed_rpm: the exact rebound law needs the main shaft's speed", key="speed_rpm")
    return rebound_amplitude_mm(task.lever_model, speed, t_deg, lost=lost)


@dataclass(frozen=True)
class AmplitudeBound:
    """Where the exact rebound keeps its limit at one speed, on the stated range [lo_deg, to_deg]
    of t: a(t) <= limit for every t in [from_deg, to_deg] (on the scan's grid of step_deg, the
    crossing polished by brentq). `why`: "crossing" (a crosses the limit at from_deg),
    "roller_left" (the roller leaves its cam below from_deg), "range" (a holds on the whole
    range: from_deg = lo_deg) or "none" (a exceeds the limit already at to_deg: from_deg None)."""
    speed_rpm: float
    from_deg: float | None
    lo_deg: float
    to_deg: float
    step_deg: float
    amplitude_mm: float       # a at from_deg (at to_deg when none holds)
    why: str
    evaluations: int
    lever: tuple | None = None      # the box's lever (frequency factor, zeta) it binds on (`box_amplitude_bound`)

    def statement(self) -> str:
        if self.from_deg is None:
            return (f"a({self.to_deg:.6g} deg, {self.speed_rpm:.6g} rpm) = {self.amplitude_mm:.6g} mm exceeds the limit "
                    f"at the top of the stated range [{self.lo_deg:.6g}, {self.to_deg:.6g}] deg: no t there keeps it")
        return (f"a <= limit for every t in [{self.from_deg:.9g}, {self.to_deg:.6g}] deg at {self.speed_rpm:.6g} rpm "
                f"(scan step {self.step_deg:g} deg from {self.to_deg:.6g} down, {self.why}"
                f"{', brentq' if self.why == 'crossing' else ''}; {self.evaluations} evaluations"
                f"{self._on_lever()})")

    def _on_lever(self) -> str:
        if self.lever is None:
            return ""
        return f"; the box's binding lever: frequency x{self.lever[0]:.6g}, zeta {self.lever[1]:.6g}"


def exact_amplitude_bound(task: Cyclogram, speed_rpm: float, lo_deg: float, to_deg: float,
                          step_deg: float) -> AmplitudeBound:
    """The smallest t in [lo_deg, to_deg] beyond which the exact rebound stays <= its limit up to
    to_deg, at speed n: a walk down from to_deg in steps of step_deg to the first point over the
    limit (or where the roller leaves its cam), the crossing in that last step by brentq
    (bisection where the roller leaves: no rebound there to take a root of). a(t) is wavy (the
    lever rings during the rise), so no tangent can give this bound; wiggles narrower than the
    step are not resolved (tests/loom/test_loom_repair.py checks the step against a dense scan).
    The walk's points are evaluated WALK_BATCH at a time through the chain's batch path
    (`walk_amplitude_mm`), in the walk's order; the first over the limit ends it as before (the
    batch's points below it are counted in `evaluations`, their values unused)."""
    limit, count = task.amplitude_limit_mm, [0]

    def excesses(t):
        t = np.atleast_1d(np.asarray(t, float))
        count[0] += t.size
        return walk_amplitude_mm(task, t, speed_rpm) - limit

    def excess(t):
        return float(excesses(t)[0])

    def bound(from_deg, amplitude, why):
        return AmplitudeBound(speed_rpm, from_deg, lo_deg, to_deg, step_deg, amplitude, why, count[0])
    hi, first = to_deg, True
    while hi > lo_deg or first:
        tops, los = [], []
        while hi > lo_deg and len(los) < WALK_BATCH:       # the walk's points, stepped as one by one
            tops.append(hi)
            hi = max(hi - step_deg, lo_deg)
            los.append(hi)
        overs = excesses([to_deg, *los] if first else los)
        if first:                               # the top in the first batch: over the limit there, none holds
            top, overs, first = overs[0], overs[1:], False
            if top > 0:
                return bound(None, top + limit, "none")
        for top_deg, lo, over in zip(tops, los, overs):
            if over > 0 and math.isfinite(over):
                root = brentq(excess, lo, top_deg, xtol=1e-12 * top_deg, rtol=4 * np.finfo(float).eps)
                return bound(root, excess(root) + limit, "crossing")
            if over > 0:                            # the roller leaves its cam at lo: its edge by bisection
                while top_deg - lo > 1e-10 * top_deg:
                    mid = 0.5 * (lo + top_deg)
                    lo, top_deg = (mid, top_deg) if excess(mid) > 0 else (lo, mid)
                return bound(top_deg, excess(top_deg) + limit, "roller_left")
    return bound(lo_deg, excess(lo_deg) + limit, "range")


WALK_BATCH = 32                  # the walk's points per call of the chain's batch path


def walk_amplitude_mm(task: Cyclogram, t_deg, speed_rpm: float):
    """`exact_amplitude_mm` at many t for the walk: inf where the roller leaves its cam."""
    return exact_amplitude_mm(task, t_deg, speed_rpm, lost=np.inf)


@dataclass
class _ExactLimit:
    """One exact limit f(t) <= limit on arc k (f falls in t: convex for the stress, possibly wavy
    for the rebound), the tangent the LP takes of it (slope, intercept), the lower bound on t that
    tangent gives, and for the rebound its exact bound on the stated range (found once, on demand)."""
    kind: str                 # "amplitude" [mm] or "contact_stress" [MPa]
    k: int
    limit: float
    exact: object             # t [deg] -> f(t)
    slope: float
    intercept: float
    find_range_bound: object = None     # () -> AmplitudeBound (the rebound only)
    _range_bound: AmplitudeBound | None = None

    def bound_deg(self) -> float:
        return (self.limit - self.intercept) / self.slope if self.slope < 0 else -np.inf

    def relinearise(self, t: float) -> None:
        """The tangent at t; a central difference (the laws are smooth away from the preload's kinks)."""
        h = 1e-6 * max(t, 1e-3)
        lo, mid, hi = (float(v) for v in np.ravel(self.exact(np.array([t - h, t, t + h]))))
        self.slope = (hi - lo) / (2 * h)
        self.intercept = mid - self.slope * t

    def range_bound(self) -> AmplitudeBound:
        if self._range_bound is None:
            self._range_bound = self.find_range_bound()
        return self._range_bound

    def cut(self, t: float) -> tuple[float, str]:
        """The next round's lower bound on t from the tangent at t, and how it was found: "newton"
        (the tangent's root) where that is safe, else "exact" (the range bound). The stress is
        convex: always Newton. The rebound may rise or be flat at t (no root ahead), or its tangent
        may overshoot the range bound (not under a wavy law): then the range bound."""
        newton = self.bound_deg()
        if self.kind == "contact_stress":
            return newton, "newton"
        exact = self.range_bound().from_deg
        if exact is None:
            return math.inf, "exact"
        if math.isfinite(newton) and t < newton <= exact:
            return newton, "newton"
        return exact, "exact"


def _exact_limits(task: Cyclogram, stress_form: str, scan_to_deg: float, scan_step_deg: float) -> list[_ExactLimit]:
    """The limits the LP linearised, each with its exact law and the tangent the first LP takes."""
    out = []
    for k in task.stress_arcs():
        sigma_ref, t_ref = task.stress_reference(k)
        exact = functools.partial(stress_MPa, sigma_ref, t_ref)
        at = t_ref if stress_form == "linear" else stress_bound_deg(sigma_ref, t_ref, task.sigma_H_limit_MPa)
        law = _ExactLimit("contact_stress", k, task.sigma_H_limit_MPa, exact, 0.0, 0.0)
        law.relinearise(at)
        if stress_form == "linear":     # exactly the model's tangent, not its difference quotient
            law.slope, law.intercept = -sigma_ref / t_ref, 2.0 * sigma_ref
        out.append(law)
    phi = task.min_angles_deg()
    for k in task.amplitude_arcs():
        find = functools.partial(cached_amplitude_bound, task, task.speed_rpm, float(phi[k]), scan_to_deg, scan_step_deg)
        law = _ExactLimit("amplitude", k, task.amplitude_limit_mm,
                          functools.partial(exact_amplitude_mm, task, lost=np.inf), 0.0, 0.0, find)
        if task.has_linear_amplitude:
            law.slope, law.intercept = task.amplitude_slope_mm_per_deg, task.amplitude_intercept_mm
        else:       # the lever alone: the tangent at the exact bound (a tangent elsewhere may overshoot it)
            at = law.range_bound().from_deg
            law.relinearise(at if at is not None else scan_to_deg)
            if at is not None and not law.slope < 0:     # flat or rising there: a line whose bound is it
                law.slope, law.intercept = -1.0, law.limit + at
        out.append(law)
    return out


def repair_cyclogram(task: Cyclogram, *, backend: Literal["HIGHS", "CLARABEL"] = "HIGHS",
                     stress_form: Literal["exact", "linear"] = "linear",
                     max_rounds: Annotated[int, Interval(ge=1, le=100)] = 20,
                     scan_to_deg: Annotated[float, Interval(gt=0.0, le=360.0)] = 60.0,
                     scan_step_deg: Annotated[float, Interval(ge=1e-3, le=10.0)] = 0.25,
                     tol_mm: Tolerance = 1e-9, tol_MPa: Tolerance = 1e-6, tol_deg: Tolerance = 1e-6,
                     check: bool = False) -> Result:
    """The LP of `plan_cyclogram`, checked against the exact laws at its optimum and repaired by
    sequential LP.

    Round 1 solves the LP with the linear laws the task gives (the amplitude tangent; the stress
    tangent at t_ref when stress_form = "linear"; with the lever alone, the rebound's tangent at
    its exact bound). At its optimum each linearised limit is
    evaluated exactly: the lever's rebound a(t, n) (the chain, `exact_amplitude_mm`), sigma_max =
    sigma_ref t_ref / t. While one exceeds its limit by more than tol_mm / tol_MPa, every limit is
    re-linearised at the current angle and the LP re-solved with a cut (the largest met so far) as
    the arc's lower bound: a DPP re-solve. The stress is convex and falls in t: its tangent lies
    under it and the cuts are Newton steps on its root (quadratic convergence). The chain's a(t)
    is wavy, so a tangent is trusted only where it falls and its root lies between t and the
    exact bound; otherwise the cut is the exact bound itself: the smallest t beyond which a stays
    <= limit up to scan_to_deg (the stated range [phi, scan_to_deg]; `exact_amplitude_bound`: a
    walk down in steps of scan_step_deg and brentq). An LP bound t >= b must hold for every t the
    LP may pick above b, hence a bound on the range and not a root. When the laws hold at t, the
    rebound is also checked on the range: a t below the exact bound (a Newton step that stopped at
    a crossing of a wiggle) is cut there too.

    Returns the last round's event times (p_*, t_*, span_deg ...), rounds, exact_amplitude_*_mm
    (at the final t), amplitude_holds_from_*_deg and amplitude_holds_to_*_deg (a <= limit on that
    range), exact_sigma_*_MPa and linearisation_error_*: exact minus linear at round 1's optimum;
    diagnostics["rounds"]: per round and limit t, exact, linear, error, excess, the cut and how it
    was found ("newton" or "exact"). SOLVED when the exact laws hold to the tolerances; LIMIT after
    max_rounds without it; INFEASIBLE when the rebound exceeds its limit even at scan_to_deg (no
    values; diagnostics best_t_deg and best_amplitude_mm, the least rebound on the range); an
    LP that fails in a round returns its status, with the rounds so far. `check`: every round's
    plan solved by both methods (plan_cyclogram's check); the last round's check_rel is kept.
    """
    clock = Clock()
    laws = _exact_limits(task, stress_form, scan_to_deg, scan_step_deg)
    unit = {"amplitude": "mm", "contact_stress": "MPa"}
    tol = {"amplitude": tol_mm, "contact_stress": tol_MPa}
    op_of = {(str(op["from"]), str(op["to"])): i for i, op in enumerate(task.operations)}
    cuts: dict[int, float] = {}
    history, current = [], task
    amplitude = [law for law in laws if law.kind == "amplitude"]
    if amplitude and not task.has_linear_amplitude:     # the lever alone: round 1 takes its tangent
        current = dataclasses.replace(task, amplitude_slope_mm_per_deg=amplitude[0].slope,
                                      amplitude_intercept_mm=amplitude[0].intercept)
    for round_ in range(1, max_rounds + 1):
        result = plan_cyclogram(current, backend=backend, stress_form=stress_form, tol_deg=tol_deg, check=check)
        if result.status is not Status.SOLVED:
            return dataclasses.replace(result, message=f"round {round_}: {result.message}",
                                       diagnostics=result.diagnostics | {"rounds": history})
        rows = []
        for law in laws:
            x, y = task.arcs[law.k]
            t = result.values[f"t_{x}_{y}_deg"]
            exact, linear = float(np.ravel(law.exact(t))[0]), law.slope * t + law.intercept
            rows.append({"limit": f"{law.kind}[{x}->{y}]", "t_deg": t, f"exact_{unit[law.kind]}": exact,
                         f"linear_{unit[law.kind]}": linear, "error": exact - linear, "excess": exact - law.limit})
        history.append({"round": round_, "span_deg": result.values["span_deg"], "limits": rows})
        over = [r["limit"] for r, law in zip(rows, laws) if r["excess"] > tol[law.kind]]
        # a rebound that holds at t but not on the whole range above it: cut at the range bound
        short = [law for r, law in zip(rows, laws) if law.kind == "amplitude" and r["limit"] not in over
                 and (law.range_bound().from_deg is None or r["t_deg"] < law.range_bound().from_deg - tol_deg)]
        if not over and not short:
            return _repaired(task, result, laws, history, clock, Status.SOLVED,
                             f"exact laws hold after {round_} round(s) (tol {tol_mm:g} mm, {tol_MPa:g} MPa); "
                             + "; ".join(law.range_bound().statement() for law in amplitude))
        if round_ == max_rounds:
            break
        for row, law in zip(rows, laws):
            law.relinearise(row["t_deg"])
            if row["limit"] in over:
                bound, how = law.cut(row["t_deg"])
            elif law in short:
                bound, how = law.range_bound().from_deg, "exact"
            else:
                bound, how = law.bound_deg(), "newton"
            if bound is None or bound == math.inf:      # the rebound exceeds its limit on all the range
                best = law.range_bound()        # the least rebound the range offers: at its top
                clock.build_s = result.timing.build_s
                return clock.result(Status.INFEASIBLE, {}, message=f"round {round_}: {row['limit']}: {best.statement()}",
                                    violated=(row["limit"],), diagnostics={"rounds": history, "best_t_deg": best.to_deg,
                                                                           "best_amplitude_mm": best.amplitude_mm})
            cuts[law.k] = max(cuts.get(law.k, -np.inf), bound)
            row["cut_deg"], row["cut"] = cuts[law.k], how
        ops = [dict(op) for op in task.operations]
        for k, bound in cuts.items():
            op = ops[op_of[task.arcs[k]]]
            op["min_deg"] = max(float(op["min_deg"]), bound)
        current = dataclasses.replace(current, operations=ops)
    worst = max((r for r in history[-1]["limits"]), key=lambda r: r["excess"])
    return _repaired(task, result, laws, history, clock, Status.LIMIT,
                     f"not converged in {max_rounds} round(s): exact {worst['limit']} exceeds its limit by "
                     f"{worst['excess']:.3g} (raise max_rounds or loosen the tolerances)", violated=tuple(over))


def _repaired(task, result, laws, history, clock, status, message, violated=()):
    """The last LP round's values with the linear-law readings replaced by the exact ones."""
    values = {k: v for k, v in result.values.items() if not k.startswith(("amplitude_", "sigma_", "sens_"))}
    values["rounds"] = float(len(history))
    for law, first, last in zip(laws, history[0]["limits"], history[-1]["limits"]):
        x, y = task.arcs[law.k]
        name, unit = ("amplitude", "mm") if law.kind == "amplitude" else ("sigma", "MPa")
        values[f"exact_{name}_{x}_{y}_{unit}"] = last[f"exact_{unit}"]
        if law.kind == "amplitude" and law._range_bound is not None and law._range_bound.from_deg is not None:
            values[f"amplitude_holds_from_{x}_{y}_deg"] = law._range_bound.from_deg
            values[f"amplitude_holds_to_{x}_{y}_deg"] = law._range_bound.to_deg
        values[f"linearisation_error_{name}_{x}_{y}_{unit}"] = first["error"]
    diagnostics = {k: v for k, v in result.diagnostics.items() if k not in ("binding", "sens_min_deg",
                                                                            "sensitivity_convention")}
    diagnostics["rounds"] = history
    clock.build_s = result.timing.build_s           # the last round's LP construction
    return clock.result(status, values, message=message, violated=violated, diagnostics=diagnostics,
                        arrays=result.arrays)   # the last plan's table


_AMPLITUDE_BOUNDS = BuildCache("loom.amplitude_bound", maxsize=64)
# the code a stored walk or n / t probe depends on (kit.store's fingerprint): the models, the
# lever's chain, the walk, the probe's module, and the kit (results, caches, settings)
WALK_SOURCES = ("mechopt.models", "mechopt.solvers.stop_impact", "mechopt.solvers.loom",
                "mechopt.solvers.cyclogram.speed_laws", "mechopt.kit")


def cached_amplitude_bound(task: Cyclogram, speed_rpm: float, lo_deg: float, to_deg: float,
                           step_deg: float) -> AmplitudeBound:
    """`exact_amplitude_bound` on [lo_deg, to_deg] at speed n, from one walk per lever, limit, n,
    to_deg and step_deg (kept, and on disk when the store is on). The walk goes down to
    WALK_FLOOR_DEG; an arc whose [phi] lies above its crossing is shown to hold from [phi] on (the
    walk saw a <= limit on all of [phi, to_deg]), so arcs with different [phi] share it, as do
    machines (or scenes) with one lever (`walk_lever`: the chain's inputs, not the angle, speeds or
    limit a scene reports at).

    The walk is the one at n itself, whatever ran before (in the process, another thread, or the
    store): not a walk at another speed rescaled. The rebound is a function of n / t alone (the
    chain's rise depends on lambda = omega t / (6 n) and T = t / (6 n) only, eq. (2) on v0 = X' H / T:
    models/cam_follower.py, models/stop_impact.py) except where the cycle cuts the dwell after the
    rise (360 / t - 1 below the dwell's periods: t and n apart), so a walk at n1 would give the walk
    at n2 = c n1 on the range and step scaled by c -- but only to the root's tolerance (brentq's
    last bits), and not where the floor (an angle) ends it; a result would then depend on which
    speed walked first (tests/loom/test_walk.py). No scene shares a walk across speeds: at fixed
    scan_to_deg each speed is another grid of n / t anyway."""
    if speed_rpm is None:
        raise ModelError("speed_rpm: the exact rebound law needs the main shaft's speed", key="speed_rpm")
    check_walk(to_deg, step_deg)
    n, to, step = float(speed_rpm), float(to_deg), float(step_deg)
    key = (walk_lever(task), task.amplitude_limit_mm, n, to, step)
    walk, _ = _AMPLITUDE_BOUNDS.get(key, lambda: store.stored(          # on disk too, when on
        "walk", key, lambda: exact_amplitude_bound(task, n, min(WALK_FLOOR_DEG, to), to, step), _encode_walk,
        _decode_walk, sources=WALK_SOURCES, enabled=rebound_amplitude_mm is chain_rebounds_mm))
    if walk.from_deg is not None and walk.from_deg <= lo_deg:
        return dataclasses.replace(walk, from_deg=lo_deg, lo_deg=lo_deg, why="range",
                                   amplitude_mm=float(np.ravel(exact_amplitude_mm(task, lo_deg, speed_rpm))[0]))
    return dataclasses.replace(walk, lo_deg=lo_deg)


def _encode_walk(walk):
    return {"walk": dataclasses.asdict(walk)}


def _decode_walk(data):
    walk = dict(data["walk"])
    walk["lever"] = None if walk["lever"] is None else tuple(walk["lever"])
    return AmplitudeBound(**walk)


# the lever's inputs the rebound a(t, n) does not read (the angle and speeds a scene reports at,
# its limit: the walk's key holds the limit it is walked against)
_NOT_READ_BY_THE_CHAIN = ("t_deg", "speed_nominal_rpm", "amplitude_limit_mm", "speeds_rpm")


def walk_lever(task: Cyclogram) -> tuple:
    """The task's lever as the walk's key, its inputs the chain reads (name, value): two machines
    (or scenes) with one lever share its walk."""
    lever = task.lever_model
    return tuple((f.name, getattr(lever, f.name)) for f in dataclasses.fields(lever)
                 if f.name not in _NOT_READ_BY_THE_CHAIN)


def box_amplitude_bound(task: Cyclogram, box: LeverBox | None, speed_rpm: float, lo_deg: float, to_deg: float,
                        step_deg: float) -> AmplitudeBound:
    """The rebound's exact bound on [lo_deg, to_deg] holding on every lever of the box's grid
    (`LeverBox.grid_keys`: the nominal lever, the corners and the dense grid) at the speed raised by
    the box's margin, speed_rpm (1 + margin): the largest of the levers' `cached_amplitude_bound`
    (None, no t holds, counts as the largest), `lever` naming the one that binds. A law of fixed
    shape makes each lever's rebound a function h_k(n / t), so its bound is t >= c_k n, the margin
    multiplies it by (1 + margin), and the bound under the largest c_k holds every lever. Its
    `speed_rpm` is the raised speed: the bound at the machine's speed n is from_deg n / speed_rpm
    (1 + margin). Without a box (or a trivial one): `cached_amplitude_bound` at speed_rpm."""
    if box is None or box.trivial:
        return cached_amplitude_bound(task, speed_rpm, lo_deg, to_deg, step_deg)
    nominal, worst = task.lever_model, None
    for key in box.grid_keys(nominal):
        each = LeverBox.lever(nominal, key)
        on = task if each is nominal else dataclasses.replace(
            task, lever={**task.lever, "E_GPa": each.E_GPa, "damping_ratio": each.damping_ratio})
        bound = dataclasses.replace(cached_amplitude_bound(on, speed_rpm * (1.0 + box.speed_margin), lo_deg, to_deg,
                                                           step_deg), lever=key)
        if worst is None or _rank(bound) > _rank(worst):
            worst = bound
    return worst


def _rank(bound: AmplitudeBound) -> float:
    return math.inf if bound.from_deg is None else bound.from_deg


WALK_FLOOR_DEG = 1.0             # the walk's lowest t: below it no cam rise of a loom
# the walk's work, counted before it starts: each point is one rise of the chain (in the batch path
# about 0.4 ms on the 2-core machine, a CVODES rise ~30 ms), so that a mistyped step is refused
MAX_WALK_POINTS = 1000


def check_walk(to_deg: float, step_deg: float) -> None:
    """Refuse a walk of more than MAX_WALK_POINTS rebounds, naming the keys and the limit."""
    points = math.ceil((to_deg - min(WALK_FLOOR_DEG, to_deg)) / step_deg)
    if points > MAX_WALK_POINTS:
        raise SettingError(f"scan_to_deg={to_deg:g}, scan_step_deg={step_deg:g}: the walk for the rebound's exact "
                           f"bound would take {points} rebounds, the limit is "
                           f"{MAX_WALK_POINTS}: raise scan_step_deg to >= "
                           f"{(to_deg - WALK_FLOOR_DEG) / MAX_WALK_POINTS:.3g} deg or lower scan_to_deg to <= "
                           f"{WALK_FLOOR_DEG + MAX_WALK_POINTS * step_deg:.3g} deg", key="scan_step_deg")
