"""Accuracy costs time: one revolution of the crank press (paper 001) by every integrator.

Each method integrates the paper's press (scene press/kd2322) from the nominal state for one
revolution's time (`DURATION_S`) at a range of its accuracy knob; the error is the larger of the
crank angle's and crank speed's deviation at the end from a tight independent reference
(scipy's DOP853 at rtol 1e-13 with its own event location: no CVODES, no CasADi integrator).
Wall time is measured around the call (`time.perf_counter`), median of `repeats`, with the
build cached (a first warm-up call builds it). Methods:

* ``rk4 (paper)``       fixed-step RK4 on the switched equations, step 1 ms ... 15.6 us: it steps
                         across the jump at the end of the cut, so its error falls only as O(h);
* ``cvodes events``     `press.events`, tolerance 1e-4 ... 1e-12;
* ``Radau events``, ``LSODA events``  scipy's solve_ivp with terminal events and restarts.

`at_accuracy` interpolates each method's time to reach 1e-8 on phi (log-log); for RK4 it
extrapolates along its measured first-order line (said so in the table). Timings live here
only; tests never assert them.

The design problem (`design_rows`): `press.design` (the shooting NLP, IPOPT with
exact first derivatives) against a derivative-free peer, scipy's Nelder-Mead over the same
simulation (a `steady_state` periodic solve per evaluation, the limits as an exact penalty), each
to its own tolerance; the peer's objective is compared with the NLP's. Targets: the NLP >= 20x
faster, and the whole design (a cold build included) under 2 s.
"""
import statistics
import sys
import time

import numpy as np
from scipy.optimize import minimize

import mechopt
from mechopt import registry
from mechopt.figures import save_figure
from mechopt.kit import cache
from mechopt.solvers import press as pd

__all__ = ["DESIGN_SCENES", "DURATION_S", "PAPER_TASK", "at_accuracy", "catalogue_rows", "cli", "cycle_timing",
           "design_rows", "design_table", "observed_order", "peer_design", "plot", "run", "secant_rows", "secant_table",
           "sweep_rows", "table", "walk", "whatif_rows", "whatif_table"]

PAPER_TASK, _ = registry.find("press/kd2322").build()
DURATION_S = 0.25           # about one revolution at 25 rad/s, with one cut
TARGET_ERROR = 1e-8
METHODS = {
    "rk4 (paper)": ([1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5, 3.125e-5, 1.5625e-5],
                    lambda task, k: pd.rk4(task, step_s=k, duration_s=DURATION_S, refine_tol_rad=0.0)),
    "cvodes events": ([1e-4, 1e-6, 1e-8, 1e-10, 1e-12],
                      lambda task, k: pd.events(task, tol=k, duration_s=DURATION_S)),
    "Radau events": ([1e-4, 1e-6, 1e-8, 1e-10],
                     lambda task, k: pd.ivp(task, method="Radau", rtol=k, atol=k * 1e-2, duration_s=DURATION_S)),
    "LSODA events": ([1e-4, 1e-6, 1e-8, 1e-10],
                     lambda task, k: pd.ivp(task, method="LSODA", rtol=k, atol=k * 1e-2, duration_s=DURATION_S)),
}


def reference(task=PAPER_TASK):
    r = pd.ivp(task, method="DOP853", rtol=1e-13, atol=1e-13, duration_s=DURATION_S)
    return r.values["final_phi_rad"], r.values["final_omega_rad_s"]


def run(repeats=5, *, task=PAPER_TASK, methods=METHODS, progress=None):
    """One row per method and knob: median wall time and the end-of-revolution errors."""
    phi_ref, w_ref = reference(task)
    rows = []
    for name, (knobs, call) in methods.items():
        call(task, knobs[0])                       # warm-up: builds and caches
        for knob in knobs:
            walls, result = [], None
            for k in range(repeats):
                start = time.perf_counter()
                result = call(task, knob)
                walls.append(time.perf_counter() - start)
            row = {"method": name, "knob": knob, "wall_s_median": statistics.median(walls),
                   "phi_error_rad": abs(result.values["final_phi_rad"] - phi_ref),
                   "omega_error_rad_s": abs(result.values["final_omega_rad_s"] - w_ref),
                   "status": result.status.value, "cuts": result.values.get("cuts", float("nan"))}
            rows.append(row)
            if progress:
                progress(f"{name:<14} knob={knob:<9g} {row['wall_s_median']:.4g} s  "
                         f"phi error {row['phi_error_rad']:.3g}")
    return rows


def at_accuracy(rows, target=TARGET_ERROR):
    """Seconds each method needs for `target` on phi: log-log interpolation between the two
    knobs around it; beyond the finest knob, extrapolation along the last two (marked)."""
    out = {}
    for name in dict.fromkeys(r["method"] for r in rows):
        pts = sorted(((r["phi_error_rad"], r["wall_s_median"]) for r in rows
                      if r["method"] == name and r["phi_error_rad"] > 0), reverse=True)
        if len(pts) < 2:
            continue
        err, wall = np.log(np.array(pts)).T
        reached = np.flatnonzero(err <= np.log(target))
        if reached.size:
            i = max(1, reached[0])
            slope = (wall[i] - wall[i - 1]) / (err[i] - err[i - 1])
            out[name] = (float(np.exp(wall[i] + slope * (np.log(target) - err[i]))), False)
        else:       # a least-squares line through all knobs: RK4's error wanders with where the jump falls
            slope, intercept = np.polyfit(wall, err, 1)        # the error is the noisy one; time is set by the knob
            out[name] = (float(np.exp((np.log(target) - intercept) / slope)), True)
    return out


def observed_order(rows, method="rk4 (paper)"):
    """Least-squares slope of log(phi error) against log(step): 4 for smooth RK4, ~1 across a jump."""
    pts = [(r["knob"], r["phi_error_rad"]) for r in rows if r["method"] == method and r["phi_error_rad"] > 0]
    return float(np.polyfit(*np.log(np.array(pts)).T, 1)[0]) if len(pts) >= 2 else float("nan")


def cycle_timing(repeats=21, task=PAPER_TASK, tol=1e-10):
    """Median wall seconds of one revolution by `events` after the build (the 10 ms target)."""
    pd.events(task, tol=tol, duration_s=DURATION_S)
    walls = []
    for _ in range(repeats):
        start = time.perf_counter()
        pd.events(task, tol=tol, duration_s=DURATION_S)
        walls.append(time.perf_counter() - start)
    return statistics.median(walls)


def table(rows, reached=None, cycle_s=None):
    lines = [f"{'method':<14} {'knob':>10} {'wall [s]':>10} {'phi err':>10} {'omega err':>10} {'cuts':>8} status"]
    for r in rows:
        lines.append(f"{r['method']:<14} {r['knob']:>10.3g} {r['wall_s_median']:>10.4g} {r['phi_error_rad']:>10.3g} "
                     f"{r['omega_error_rad_s']:>10.3g} {r['cuts']:>8.5f} {r['status']}")
    if reached:
        lines.append(f"\ntime to {TARGET_ERROR:g} on phi (one revolution):")
        base = reached.get("cvodes events", (np.nan,))[0]
        for name, (seconds, extrapolated) in reached.items():
            lines.append(f"  {name:<14} {seconds:10.4g} s  ratio to cvodes events {seconds / base:8.3g}"
                         + ("  (extrapolated)" if extrapolated else ""))
        ivp_best = min((v[0] for k, v in reached.items() if k.endswith("events") and k != "cvodes events"),
                       default=np.nan)
        rk4 = reached.get("rk4 (paper)", (np.nan,))[0]
        lines.append(f"targets: rk4 / cvodes = {rk4 / base:.3g} (>= 100), best solve_ivp / cvodes = "
                     f"{ivp_best / base:.3g} (>= 3)")
    if any(r["method"] == "rk4 (paper)" for r in rows):
        lines.append(f"rk4 (paper) observed order on phi: {observed_order(rows):.2f} (4 without the jump)")
    if cycle_s is not None:
        lines.append(f"one revolution by events after build: {cycle_s * 1e3:.3g} ms (target < 10 ms)")
    return "\n".join(lines)


def plot(rows, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    from pathlib import Path

    import matplotlib.pyplot as plt
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 5))
    for name in dict.fromkeys(r["method"] for r in rows):
        pts = [(r["wall_s_median"], max(r["phi_error_rad"], 1e-16)) for r in rows if r["method"] == name]
        ax.loglog(*zip(*pts), "o-", label=name)
    ax.axhline(TARGET_ERROR, color="grey", ls=":", lw=1)
    ax.set_xlabel("wall time, one revolution [s]")
    ax.set_ylabel("error of phi_k at the end [rad]")
    ax.set_title("crank press (paper 001): work-precision")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    path = out_dir / "press_work_precision.png"
    save_figure(fig, path, dpi=110)
    return [path]


# --- the design problem: exact derivatives against a derivative-free peer --------------------------

DESIGN_SCENES = ("press/flywheel-design", "press/motor-design")
SPEEDUP_TARGET, DESIGN_TARGET_S = 20.0, 2.0


def _objective(task, run, design):
    """The design objective of `task` from a steady_state run at `design` (the NLP's definitions):
    J [kg m2], RMS motor shaft torque [N m] or air-gap energy per stroke [J] (trapezoid, dense samples)."""
    if task.objective == "least_flywheel_inertia":
        return design["flywheel_inertia_kgm2"]
    a = run.arrays
    shaft = a["motor_torque_Nm"] / task.drive(design).gear_ratio
    if task.objective == "least_motor_rms_torque":
        return float(np.sqrt(np.trapezoid(shaft**2, a["t_s"]) / run.values["period_s"]))
    return float(task.motor_sync_speed_rad_s * np.trapezoid(shaft, a["t_s"]))


def peer_design(task, *, samples=400, xatol=1e-7, weight=1e3):
    """Nelder-Mead over the design variables (scaled by their starting values), each evaluation a
    steady_state solve; limits by an exact penalty (weight x relative violation), the mean speed too
    when the gear ratio is free. Returns (design, objective, evaluations)."""
    names, start = task.variables, task.start()
    scale = task.objective != "least_flywheel_inertia" and 1.0 or start.get("flywheel_inertia_kgm2", 1.0)
    count = [0]

    def cost(x):
        count[0] += 1
        design = {k: v * start[k] for k, v in zip(names, x)}
        if any(not task.bounds(k)[0] <= v <= task.bounds(k)[1] for k, v in design.items()):
            return 1e9
        run = pd.steady_state(task.drive(design), samples=samples)
        if run.status.value != "SOLVED":
            return 1e9
        v = run.values
        shaft = np.abs(run.arrays["motor_torque_Nm"]) / task.drive(design).gear_ratio
        over = [v["speed_fluctuation"] / task.max_speed_fluctuation - 1 if task.max_speed_fluctuation else 0.0,
                v["peak_belt_torque_Nm"] / task.belt_slip_torque_Nm - 1 if task.belt_slip_torque_Nm else 0.0,
                shaft.max() * task.motor_safety_factor / task.drive(design).motor_breakdown_torque_Nm - 1
                if task.motor_safety_factor else 0.0]
        penalty = sum(max(0.0, o) for o in over)
        if "gear_ratio" in names:
            penalty += abs(v["omega_mean_rad_s"] / task.nominal_speed_rad_s - 1)
        return _objective(task, run, design) / scale + weight * penalty

    found = minimize(cost, np.ones(len(names)), method="Nelder-Mead",
                     options={"xatol": xatol, "fatol": 1e-12, "maxfev": 4000})
    design = {k: v * start[k] for k, v in zip(names, found.x)}
    run = pd.steady_state(task.drive(design), samples=samples)
    return design, _objective(task, run, design), count[0]


def design_rows(repeats=3, *, scenes=DESIGN_SCENES, progress=None):
    """Per scene: the NLP's median wall time (warm: builds cached), one cold run (caches cleared),
    the peer's wall time and evaluations, both objectives."""
    rows = []
    for scene in scenes:
        task = registry.find(scene).build()[0]
        cache.clear()
        start = time.perf_counter()
        result = pd.design(task)
        cold = time.perf_counter() - start
        walls = []
        for _ in range(repeats):
            start = time.perf_counter()
            result = pd.design(task)
            walls.append(time.perf_counter() - start)
        start = time.perf_counter()
        _, objective, evaluations = peer_design(task)
        peer_s = time.perf_counter() - start
        name = {"least_flywheel_inertia": "flywheel_inertia_kgm2", "least_motor_rms_torque": "motor_rms_torque_N_m",
                "least_energy_per_stroke": "energy_per_stroke_J"}[task.objective]
        rows.append({"scene": scene, "status": result.status.value, "nlp_s_median": statistics.median(walls),
                     "nlp_cold_s": cold, "nlp_objective": result.values[name], "peer_s": peer_s,
                     "peer_objective": objective, "peer_evaluations": evaluations,
                     "objective_rel_diff": abs(objective - result.values[name]) / abs(result.values[name])})
        if progress:
            r = rows[-1]
            progress(f"{scene:<22} NLP {r['nlp_s_median']:.3g} s (cold {cold:.3g} s), Nelder-Mead {peer_s:.3g} s "
                     f"({evaluations} periodic solves)")
    return rows


def design_table(rows):
    header = (f"\n{'design scene':<22} {'NLP [s]':>8} {'cold [s]':>8} {'peer [s]':>9} {'evals':>6} {'ratio':>7} "
              f"{'objective NLP':>14} {'peer':>14} {'rel diff':>9} status")
    lines = [header]
    for r in rows:
        ratio = r["peer_s"] / r["nlp_s_median"]
        lines.append(f"{r['scene']:<22} {r['nlp_s_median']:>8.3g} {r['nlp_cold_s']:>8.3g} {r['peer_s']:>9.3g} "
                     f"{r['peer_evaluations']:>6d} {ratio:>7.3g} {r['nlp_objective']:>14.8g} {r['peer_objective']:>14.8g} "
                     f"{r['objective_rel_diff']:>9.2g} {r['status']}")
        met = {True: "met", False: "MISSED"}
        lines.append(f"  targets: NLP / Nelder-Mead speed-up {ratio:.3g} (>= {SPEEDUP_TARGET:g}: {met[ratio >= SPEEDUP_TARGET]}),"
                     f" whole design cold {r['nlp_cold_s']:.3g} s (< {DESIGN_TARGET_S:g} s: "
                     f"{met[r['nlp_cold_s'] < DESIGN_TARGET_S]})")
    return "\n".join(lines)


SECANT_SCENE, SECANT_TARGET = "press/flywheel-design-newton", 10.0


def secant_rows(repeats=5, scene=SECANT_SCENE):
    """The one-variable flywheel design by CPU time in this process (`time.process_time`, medians,
    builds cached by a first call of each): `press.flywheel` (safeguarded secant, a handful of
    periodic solves) against Nelder-Mead over the same periodic simulation (`peer_design`) and the
    NLP (`press.design`); the ratio Nelder-Mead / secant is the claim (target >= `SECANT_TARGET`)."""
    task = registry.find(scene).build()[0]
    calls = {"secant": lambda: pd.flywheel(task), "nlp": lambda: pd.design(task),
             "nelder_mead": lambda: peer_design(task)}
    out = {}
    for name, call in calls.items():
        found = call()                                 # warm-up: builds cached
        cpu = []
        for _ in range(repeats if name != "nelder_mead" else max(1, repeats // 2)):
            start = time.process_time()
            found = call()
            cpu.append(time.process_time() - start)
        out[name] = (statistics.median(cpu), found)
    secant = out["secant"][1]
    design, objective, evaluations = out["nelder_mead"][1]
    return {"secant_cpu_s": out["secant"][0], "nlp_cpu_s": out["nlp"][0], "nelder_mead_cpu_s": out["nelder_mead"][0],
            "secant_J": secant.values["flywheel_inertia_kgm2"], "secant_solves": secant.values["periodic_solves"],
            "nlp_J": out["nlp"][1].values["flywheel_inertia_kgm2"], "nelder_mead_J": objective,
            "nelder_mead_solves": evaluations, "ratio": out["nelder_mead"][0] / out["secant"][0]}


def secant_table(r):
    met = {True: "met", False: "MISSED"}
    return (f"\none-variable flywheel design ({SECANT_SCENE}), CPU seconds in one process (medians):\n"
            f"  secant {r['secant_cpu_s']:.3g} s ({r['secant_solves']} periodic solves, J = {r['secant_J']:.8g}); "
            f"NLP {r['nlp_cpu_s']:.3g} s (J = {r['nlp_J']:.8g}); Nelder-Mead {r['nelder_mead_cpu_s']:.3g} s "
            f"({r['nelder_mead_solves']} periodic solves, J = {r['nelder_mead_J']:.8g})\n"
            f"  target: Nelder-Mead / secant {r['ratio']:.3g} (>= {SECANT_TARGET:g}: {met[r['ratio'] >= SECANT_TARGET]})")


def cli(repeats, out_dir, progress=None) -> str:
    """What `mechopt bench press` prints: the work-precision table, the targets, the plot, the
    design problem against its derivative-free peer (NLP: median of max(repeats, 3); peer: one run),
    and the what-if, sweep, walk and catalogue figures (alone, about two minutes:
    `whatif_table(whatif_rows(), sweep_rows(), walk(), catalogue_rows())`)."""
    whatif = whatif_table(whatif_rows(max(repeats, 7)), sweep_rows(), walk(), catalogue_rows())
    rows = run(repeats=repeats, progress=progress)
    paths = plot(rows, out_dir)
    design = design_table(design_rows(repeats=max(repeats, 3), progress=progress)) + secant_table(secant_rows())
    return "\n".join([table(rows, at_accuracy(rows), cycle_timing()), design, whatif,
                      *(f"plot: {p}" for p in paths)])


# --- what-ifs that re-solve on the structure's build ------------------------------------

WHATIF = {"belt_stiffness_Nm_rad": 6e4}
WHATIF_FAR = {"flywheel_inertia_kgm2": 7.5}     # 50 % off the last orbit: the Broyden steps' case
SWEEP_SCENE = "press/kd2322"
WHATIF_TARGETS = {"build_share": 0.10, "orbit_s": 0.050, "speedup": 5.0, "sweep_speedup": 5.0}


def _solve(overrides=None):
    start = time.perf_counter()
    result = mechopt.solve(SWEEP_SCENE, overrides or {}).result
    return time.perf_counter() - start, result


def whatif_rows(repeats=7):
    """Fresh solves (every cache cleared first) against what-ifs (`WHATIF` after a solve of the scene
    as it is, same process): medians of wall time, build_s and the periodic orbit's solve_s; and the
    orbit's solve_s of the far what-if `WHATIF_FAR` after a solve of the scene, with its steps."""
    fresh, whatif, far = [], [], []
    for _ in range(repeats):
        cache.clear()
        wall, result = _solve()
        fresh.append((wall, result.timing.build_s, result.timing.solve_s, result.status.value))
        _solve()                                  # back on the scene's own orbit
        wall, result = _solve(WHATIF)
        whatif.append((wall, result.timing.build_s, result.timing.solve_s, result.status.value,
                       result.diagnostics["newton_iterations"], result.values["periodicity_residual"]))
        _solve()
        _, result = _solve(WHATIF_FAR)
        far.append((result.timing.solve_s, result.status.value, result.diagnostics["newton_iterations"],
                    result.diagnostics["warm_start"]))
    med = lambda rows, i: statistics.median(r[i] for r in rows)
    return {"fresh_wall_s": med(fresh, 0), "fresh_build_s": med(fresh, 1), "whatif_wall_s": med(whatif, 0),
            "whatif_build_s": med(whatif, 1), "whatif_orbit_s": med(whatif, 2),
            "whatif_chord_steps": med(whatif, 4), "whatif_residual": max(r[5] for r in whatif),
            "far_orbit_s": med(far, 0), "far_steps": med(far, 2), "far_warm": all(r[3] for r in far),
            "statuses": sorted({r[3] for r in fresh + whatif} | {r[1] for r in far})}


def sweep_rows(variants=1000, baseline_variants=40):
    """Throughput of a sweep of `variants` of one structure (flywheel inertia x belt stiffness, the
    order a grid takes) against the same variants solved the way every variant was before builds were held:
    every build made afresh and the orbit found from the cold guess (caches cleared per variant; a
    `baseline_variants` prefix of the grid). Variants per second, and the statuses seen."""
    side = int(round(np.sqrt(variants)))
    grid = [{"flywheel_inertia_kgm2": float(J), "belt_stiffness_Nm_rad": float(C)}
            for J in np.linspace(4.0, 6.0, side) for C in np.linspace(4e4, 6e4, variants // side)]
    statuses = {}
    start = time.perf_counter()
    for overrides in grid[:baseline_variants]:
        cache.clear()
        _, result = _solve(overrides)
        statuses[result.status.value] = statuses.get(result.status.value, 0) + 1
    before = baseline_variants / (time.perf_counter() - start)
    _solve()
    start = time.perf_counter()
    warm = 0
    for overrides in grid:
        _, result = _solve(overrides)
        warm += bool(result.diagnostics.get("warm_start"))
        statuses[result.status.value] = statuses.get(result.status.value, 0) + 1
    after = len(grid) / (time.perf_counter() - start)
    return {"variants": len(grid), "rebuild_per_s": before, "structure_per_s": after, "warm_started": warm,
            "statuses": statuses}


def walk(scene="press/kd2322"):
    """The walk of a task through `steady_state` (a cold solve): the press's files (models/, solvers/)
    the call enters in order, `stops` the changes of file and `returns` the changes back to a file
    already visited (sys.setprofile; the spine and CasADi not counted)."""
    task = registry.find(scene).build()[0]
    cache.clear()
    sequence = []

    def enter(frame, event, arg):
        name = frame.f_code.co_filename
        if event == "call" and ("/models/" in name or "/solvers/" in name) and "site-packages" not in name:
            short = "/".join(name.split("/")[-2:])
            if not sequence or sequence[-1] != short:
                sequence.append(short)
    sys.setprofile(enter)
    try:
        pd.steady_state(task)
    finally:
        sys.setprofile(None)
    seen, returns = set(), 0
    for short in sequence:
        returns += short in seen
        seen.add(short)
    return {"stops": len(sequence), "returns": returns, "files": sorted(seen)}


CATALOGUE_SCENE, CATALOGUE_TARGET_S = "press/motor-catalogue", 10.0


def catalogue_rows(repeats=3):
    """The catalogue design (10 motor rows x 6 ratios, the NLP inside): one cold run (caches
    cleared) and the median of `repeats` warm ones; the row chosen and the NLPs it took."""
    cache.clear()
    start = time.perf_counter()
    result = mechopt.solve(CATALOGUE_SCENE).result
    cold = time.perf_counter() - start
    walls = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = mechopt.solve(CATALOGUE_SCENE).result
        walls.append(time.perf_counter() - start)
    return {"cold_s": cold, "warm_s": statistics.median(walls), "status": result.status.value,
            "row": result.values.get("motor_row"), "designs": result.values.get("designs_solved"),
            "message": result.message}


def whatif_table(w, s, path, c=None):
    met = {True: "met", False: "MISSED"}
    share, speedup = w["whatif_build_s"] / w["fresh_build_s"], w["fresh_wall_s"] / w["whatif_wall_s"]
    ratio = s["structure_per_s"] / s["rebuild_per_s"]
    t = WHATIF_TARGETS
    return "\n".join([
        f"\nwhat-if {WHATIF} after a solve of {SWEEP_SCENE} (medians, same process):",
        f"  fresh: {w['fresh_wall_s'] * 1e3:.4g} ms (build {w['fresh_build_s'] * 1e3:.3g} ms); what-if: "
        f"{w['whatif_wall_s'] * 1e3:.4g} ms (build {w['whatif_build_s'] * 1e3:.3g} ms, periodic orbit "
        f"{w['whatif_orbit_s'] * 1e3:.3g} ms, {w['whatif_chord_steps']:g} chord steps, residual <= "
        f"{w['whatif_residual']:.2g}); statuses {', '.join(w['statuses'])}",
        f"  targets: build share {share:.3g} (< {t['build_share']:g}: {met[share < t['build_share']]}), orbit "
        f"{w['whatif_orbit_s'] * 1e3:.3g} ms (< {t['orbit_s'] * 1e3:g} ms: {met[w['whatif_orbit_s'] < t['orbit_s']]}),"
        f" fresh / what-if {speedup:.3g} (>= {t['speedup']:g}: {met[speedup >= t['speedup']]})",
        f"  what-if {WHATIF_FAR}: periodic orbit {w['far_orbit_s'] * 1e3:.3g} ms, {w['far_steps']:g} "
        f"{'Broyden steps from the last orbit' if w['far_warm'] else 'Newton steps (a cold solve)'}",
        f"sweep of {s['variants']} variants of one structure: {s['structure_per_s']:.4g} variants/s "
        f"({s['warm_started']} warm-started) against {s['rebuild_per_s']:.4g}/s rebuilding each; ratio "
        f"{ratio:.3g} (>= {t['sweep_speedup']:g}: {met[ratio >= t['sweep_speedup']]}); statuses {s['statuses']}",
        f"walk of a task through steady_state: {path['stops']} stops, {path['returns']} returns over "
        f"{len(path['files'])} files ({', '.join(path['files'])})",
        *([] if c is None else [
            f"catalogue design ({CATALOGUE_SCENE}, 10 rows x 6 ratios): cold {c['cold_s']:.3g} s, warm "
            f"{c['warm_s']:.3g} s (< {CATALOGUE_TARGET_S:g} s: {met[c['cold_s'] < CATALOGUE_TARGET_S]}), "
            f"{c['designs']:g} NLPs, {c['status']}: {c['message']}"])])
