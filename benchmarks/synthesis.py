"""The synthesis' window LP through the package against raw HiGHS on the same rows (the same process).

Per case (coefficients, speeds, phase angle), the window LP is assembled once (`WindowLP`:
solvers/stop_impact/window_rows.py) and solved at the scan's windows xi_a:

* ``package``           `WindowLP.solve(xi_a)`: bounds changed in place, a cold dual simplex, the
                        solution mapped back (what the synthesis pays per LP);
* ``raw HiGHS``         a fresh `highspy.Highs` given the same scaled rows with that window's bounds
                        (passModel), the same options, run (the interior point where the dual
                        simplex gives no status, as the package), the solution read: the floor;
* ``IPM cold``          the same held model by HiGHS' interior point + crossover (the old choice);
* ``dual warm``         the dual simplex from the previous window's basis (not cleared).

CPU seconds per LP (time.process_time, medians over repeats); the target is package / raw <= 1.3
(issue: the LP within 1.3x raw HiGHS on the same rows). Warm against cold: the largest change of
a coefficient over the windows (another vertex of the same optimum can differ).

A dense-check round (`rounds_row`): the window scan of a round with a sample added, from scratch
and bounded by the round before (synthesis_search.scan_windows's floors): its LPs and CPU seconds, and
whether both end on the same coefficients.
"""
import statistics
import time

import numpy as np

from mechopt import registry
from mechopt.kit.highs import RealHighs, quiet_banner, status_of
from mechopt.kit.result import Status

__all__ = ["CASES", "cli", "lp_rows", "lp_table", "rounds_row"]

# (label, coefficients, speeds [rpm], phase angle [deg]; None: the lever's own t)
CASES = (("law-synthesis: 24 coefficients x 5 speeds", 24, (280.0, 315.0, 350.0, 385.0, 420.0), 31.0),
         ("issue's: 100 coefficients, 420 rpm", 100, (420.0,), None),
         ("states: 1000 coefficients, 420 rpm", 1000, (420.0,), None))
WINDOWS = (0.7, 0.8, 0.9, 0.75, 0.85)          # the scan's candidates and one refinement
RAW_OVER_PACKAGE_TARGET = 1.3
ACCEL = 570.0                                   # mm/rad^2, the scenes' bound


def _window_lp(task, coefficients, speeds, t_deg):
    from mechopt.solvers.stop_impact import window_lp
    lever = window_lp.linear_lever(coefficients, 2)
    responses = [window_lp.speed_response(task, lever, n, t_deg) for n in speeds]
    lines = window_lp.rebound_envelope(task, 4 * window_lp.v0_limit_m_s(task, task.amplitude_limit_mm))
    return window_lp.WindowLP(task, lever, responses, t_deg, objective="least_rebound", limit_mm=task.amplitude_limit_mm,
                       bounds={"max_acceleration_mm_per_rad2": ACCEL}, lines=lines)


def _uppers(lp):
    return [lp.upper_at(xa) for xa in WINDOWS]


def _per_lp(calls, repeats):
    """{name: (median CPU seconds per window, the last run's [(status, x)] per window)}: the calls
    interleaved in every repeat, so that a change of the machine's load falls on all of them."""
    times, out = {name: [] for name in calls}, {}
    for _ in range(repeats):
        for name, call in calls.items():
            start = time.process_time()
            out[name] = call()
            times[name].append((time.process_time() - start) / len(WINDOWS))
    return {name: (statistics.median(times[name]), out[name]) for name in calls}


def _held_runs(lp, options, cold=True):
    held, out = lp.held, []
    for upper in _uppers(lp):
        held.set_upper(upper)
        if cold:
            held.highs.clearSolver()
        for name, value in options.items():
            held.highs.setOptionValue(name, value)
        held.highs.run()
        status = status_of(held.highs)
        out.append((status, np.asarray(held.highs.getSolution().col_value) * held.s if status is Status.SOLVED
                    else None))
    return out


def _raw_runs(lp, first, retry):
    """Fresh Highs objects on the same scaled rows, as the package solves: `first`, then `retry`
    where `first` ends at its limit or with no status."""
    out = []
    for upper in _uppers(lp):
        lp.held.set_upper(upper)
        model = lp.held.model()
        for options in (first, retry):
            highs = RealHighs()
            for name, value in options.items():
                highs.setOptionValue(name, value)
            highs.passModel(model)
            highs.run()
            status = status_of(highs)
            if status not in (Status.LIMIT, Status.FAILED):
                break
        out.append((status, np.asarray(highs.getSolution().col_value) if status is Status.SOLVED else None))
    return out


def lp_rows(repeats=5, progress=None, quick=False):
    """One row per case: rows x columns, the assembly's CPU seconds, CPU seconds per LP of each way,
    package / raw, and the largest coefficient change of the warm dual simplex against the cold."""
    from mechopt.solvers.stop_impact.window_rows import IPM_OPTIONS, SIMPLEX_OPTIONS
    quiet_banner()
    task = registry.find("stop-impact/amplitude-law").build()[0]
    rows = []
    for label, k, speeds, t_deg in CASES[:2] if quick else CASES:
        t_deg = task.t_deg if t_deg is None else t_deg
        start = time.process_time()
        lp = _window_lp(task, k, speeds, t_deg)
        build = time.process_time() - start
        ways = _per_lp({"package": lambda: [lp.solve(xa)[:2] for xa in WINDOWS],
                        "raw": lambda: _raw_runs(lp, SIMPLEX_OPTIONS, IPM_OPTIONS),
                        "ipm": lambda: _held_runs(lp, IPM_OPTIONS),
                        "warm": lambda: _held_runs(lp, SIMPLEX_OPTIONS, cold=False)}, repeats)
        (package, solved), (raw, _), (ipm, _), (warm, warm_out) = (ways[k] for k in ("package", "raw", "ipm", "warm"))
        start_c, size_c = lp.held.columns["c"]
        change = max((float(np.abs(w[1][start_c:start_c + size_c] - s[1]).max())
                      for w, s in zip(warm_out, solved) if w[1] is not None and s[1] is not None), default=np.nan)
        rows.append({"case": label, "shape": lp.held.A.shape, "build_s": build, "package_s": package, "raw_s": raw,
                     "ipm_s": ipm, "warm_s": warm, "ratio": package / raw, "warm_change": change,
                     "statuses": [s[0].value for s in solved]})
        if progress:
            progress(f"{label}: package {package:.4f} s, raw {raw:.4f} s per LP")
    return rows


def lp_table(rows):
    lines = ["window LP per solve (CPU s, medians; windows xi_a " + ", ".join(f"{w:g}" for w in WINDOWS) + ")",
             f"{'case':44s} {'rows x cols':>12s} {'build':>7s} {'package':>8s} {'raw':>8s} {'pkg/raw':>8s} "
             f"{'IPM cold':>9s} {'dual warm':>9s} {'warm |dc|':>10s}"]
    for r in rows:
        shape = f"{r['shape'][0]}x{r['shape'][1]}"
        lines.append(f"{r['case']:44s} {shape:>12s} {r['build_s']:7.3f} {r['package_s']:8.4f} {r['raw_s']:8.4f} "
                     f"{r['ratio']:8.3f} {r['ipm_s']:9.4f} {r['warm_s']:9.4f} {r['warm_change']:10.2e}  "
                     + " ".join(r["statuses"]))
    worst = max(r["ratio"] for r in rows)
    verdict = "met" if worst <= RAW_OVER_PACKAGE_TARGET else "MISSED"
    lines.append(f"package / raw HiGHS per LP, worst case: {worst:.3f} (<= {RAW_OVER_PACKAGE_TARGET:g}: {verdict})")
    return "\n".join(lines)


def rounds_row(repeats=3):
    """{"from_scratch": (LPs, CPU s), "bounded": (LPs, CPU s), "same_law": bool}: the scan of a
    round (law-synthesis' 24 coefficients, five speeds and 300 rpm added, t = 31 deg) without and
    with the round before's windows as floors; CPU medians over repeats, interleaved."""
    from mechopt.solvers.stop_impact.synthesis_search import scan_windows
    task = registry.find("stop-impact/amplitude-law").build()[0]
    first = list(CASES[0][2])
    _, _, floors = scan_windows(_window_lp(task, 24, first, 31.0), around=0.85)
    lp = _window_lp(task, 24, sorted(first + [300.0]), 31.0)
    times, out = {"from_scratch": [], "bounded": []}, {}
    for _ in range(repeats):
        for name, given in (("from_scratch", None), ("bounded", floors)):
            start = time.process_time()
            out[name] = scan_windows(lp, 0.85, given)
            times[name].append(time.process_time() - start)
    same = np.array_equal(out["from_scratch"][0][1], out["bounded"][0][1])
    return {name: (out[name][1], statistics.median(times[name])) for name in times} | {"same_law": same}


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """The table alone (no figure); part of `mechopt bench stop-impact`."""
    table = lp_table(lp_rows(repeats=1 if quick else repeats, progress=progress, quick=quick))
    got = rounds_row(repeats=1 if quick else min(repeats, 5))
    (n_full, s_full), (n_bound, s_bound) = got["from_scratch"], got["bounded"]
    return table + (f"\na dense-check round (a sample added): {n_full} LPs {s_full:.3f} s from scratch, {n_bound} LPs "
                    f"{s_bound:.3f} s bounded by the round before ({s_full / s_bound:.1f} x); the same law: "
                    f"{got['same_law']}")
