"""The rebound's exact bound (the walk) and what it costs the highest-speed solve and the co-design.

In one process, CPU seconds (time.process_time), medians over repeats, interleaved:

* ``fresh``          `mechopt run loom/machine-speed` as a scene run with every build cache
                     cleared (the walk, the n / t probe, the speed LP's compile all done anew);
* ``fresh, stored``  the same with the lever's walk and n / t probe read from the on-disk store
                     (MECHOPT_CACHE_DIR, src/mechopt/kit/store.py; a temporary folder
                     filled by one run first): a fresh process's solve of a lever seen before;
* ``re-solve``       the same run again (walk, probe and compiled LP kept): the issue's target is
                     fresh / re-solve <= 3 (the preparation shared between fresh solves of the
                     same lever: the stored row);
* ``walk (batch)``   the walk alone (`exact_amplitude_bound` at 420 rpm on [1, 60] deg, step
                     0.25), the chain's batch path, with its count of evaluations;
* ``walk (CVODES)``  the same walk stepped point by point on the per-point CVODES chain
                     (`rebound_amplitude_mm`: the walk as it was), the same crossing to 1e-9.

The whole command `mechopt run loom/machine-speed-codesign --json F` (a fresh process each, CPU
user + sys of the child, medians of `repeats`), against a baseline checkout when the variable
MECHOPT_BENCH_BASELINE names its `mechopt` executable (run from the executable's project: set
MECHOPT_BENCH_BASELINE_DIR), interleaved run by run; the machine's load average is printed
beside (the issue's target, < 5 s, is for a quiet 2-core machine). Timings live here only.
"""
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from mechopt import registry
from mechopt.kit.cache import clear as clear_caches

__all__ = ["cli", "codesign_command", "in_process"]

SCENE, CODESIGN = "loom/machine-speed", "loom/machine-speed-codesign"
FRESH_OVER_RESOLVE_TARGET, CODESIGN_TARGET_S = 3.0, 5.0


def _cpu(call):
    start = time.process_time()
    out = call()
    return time.process_time() - start, out


def _walk_point_by_point(lever, limit, n, to, step):
    """The walk one CVODES rise per point, brentq in the last cell (the session's start)."""
    from mechopt.solvers.stop_impact.law import rebound_amplitude_mm

    def excess(t):
        return float(rebound_amplitude_mm(lever, n, t, lost=np.inf)) - limit
    hi = to
    while hi > 1.0:
        lo = max(hi - step, 1.0)
        if excess(lo) > 0:
            return brentq(excess, lo, hi, xtol=1e-12 * hi, rtol=4 * np.finfo(float).eps)
        hi = lo
    return None


def in_process(repeats=3, progress=None):
    """{name: median CPU s} and the walk's evaluations, crossings and the speeds found."""
    from mechopt.solvers.loom.repair import exact_amplitude_bound
    registry.run(SCENE)                         # imports and first-use costs out of the way
    task = registry.find(SCENE).build()[0]
    times = {k: [] for k in ("fresh", "fresh_stored", "resolve", "walk_batch", "walk_cvodes")}
    for i in range(repeats):
        clear_caches()
        fresh, first = _cpu(lambda: registry.run(SCENE))
        again, second = _cpu(lambda: registry.run(SCENE))
        stored, third = _stored_fresh()
        times["fresh_stored"].append(stored)
        if not first.result.values == second.result.values == third.result.values:
            raise RuntimeError(f"{SCENE}: the fresh, re-solved and stored runs give different values")
        clear_caches()
        batch, bound = _cpu(lambda: exact_amplitude_bound(task, 420.0, 1.0, 60.0, 0.25))
        cvodes, root = _cpu(lambda: _walk_point_by_point(task.lever_model, task.amplitude_limit_mm, 420.0, 60.0, 0.25))
        for k, v in zip(("fresh", "resolve", "walk_batch", "walk_cvodes"), (fresh, again, batch, cvodes)):
            times[k].append(v)
        if progress:
            progress(f"repeat {i + 1}: fresh {fresh:.3f} s, re-solve {again:.4f} s, walk {batch:.3f} s "
                     f"against {cvodes:.2f} s")
    return {k: statistics.median(v) for k, v in times.items()} | {
        "evaluations": bound.evaluations, "from_batch": bound.from_deg, "from_cvodes": root,
        "speeds": (first.values["max_speed_rpm"], second.values["max_speed_rpm"])}


def _stored_fresh():
    """(CPU s, run): a fresh run (caches cleared) whose lever's walk and probe the on-disk store
    holds (filled by a first fresh run in a temporary folder)."""
    from mechopt.kit.store import ENV
    before = os.environ.get(ENV)
    with tempfile.TemporaryDirectory() as folder:
        os.environ[ENV] = folder
        try:
            clear_caches()
            registry.run(SCENE)                 # fills the store
            clear_caches()
            return _cpu(lambda: registry.run(SCENE))
        finally:
            if before is None:
                os.environ.pop(ENV, None)
            else:
                os.environ[ENV] = before


def _child_cpu(command, cwd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    run = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if run.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: exit {run.returncode}: {run.stderr[-500:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def codesign_command(repeats=3, progress=None):
    """{"this": median CPU s, "baseline": ... or None, "load": (1, 5, 15 min) before and after}."""
    this = shutil.which("mechopt", path=str(Path(sys.executable).parent)) or "mechopt"
    base = os.environ.get("MECHOPT_BENCH_BASELINE")
    base_dir = os.environ.get("MECHOPT_BENCH_BASELINE_DIR") or (str(Path(base).parent) if base else None)
    runs = {"this": [], "baseline": []}
    load = [os.getloadavg()]
    with tempfile.TemporaryDirectory() as out:
        for i in range(repeats):
            for name, exe, cwd in (("baseline", base, base_dir), ("this", this, None)):
                if exe is None:
                    continue
                runs[name].append(_child_cpu([exe, "run", CODESIGN, "--json", f"{out}/{name}-{i}.json"], cwd))
                if progress:
                    progress(f"{CODESIGN} ({name}) run {i + 1}: {runs[name][-1]:.2f} s CPU")
    load.append(os.getloadavg())
    return {"this": statistics.median(runs["this"]),
            "baseline": statistics.median(runs["baseline"]) if runs["baseline"] else None, "load": load,
            "runs": runs}


def table(proc, command) -> str:
    ratio, stored = proc["fresh"] / proc["resolve"], proc["fresh_stored"] / proc["resolve"]
    lines = [f"{SCENE}, in one process (CPU s, medians)",
             f"  fresh (caches cleared)    {proc['fresh']:.4f}",
             f"  fresh, walk stored        {proc['fresh_stored']:.4f}  (the lever's walk and probe from MECHOPT_CACHE_DIR)",
             f"  re-solve                  {proc['resolve']:.4f}",
             f"  fresh / re-solve          {ratio:.1f}  (nothing shared)",
             f"  fresh, stored / re-solve  {stored:.1f}  (<= {FRESH_OVER_RESOLVE_TARGET:g}: "
             f"{'met' if stored <= FRESH_OVER_RESOLVE_TARGET else 'MISSED'})",
             f"  walk, batch path          {proc['walk_batch']:.4f}  ({proc['evaluations']} evaluations)",
             f"  walk, CVODES point by point {proc['walk_cvodes']:.3f}  (x{proc['walk_cvodes'] / proc['walk_batch']:.0f})",
             f"  crossing: batch {proc['from_batch']:.10f} deg, CVODES {proc['from_cvodes']:.10f} deg "
             f"({abs(proc['from_batch'] / proc['from_cvodes'] - 1):.1e} relative); speeds {proc['speeds'][0]:.9g}, "
             f"{proc['speeds'][1]:.9g} rpm"]
    load = ", ".join(f"{a:.2f}" for a in command["load"][0]) + " -> " + ", ".join(f"{a:.2f}" for a in command["load"][1])
    lines.append(f"mechopt run {CODESIGN} --json F, whole process (CPU user + sys, median; load {load})")
    lines.append(f"  this checkout             {command['this']:.2f} s  (< {CODESIGN_TARGET_S:g} s on a quiet machine: "
                 f"{'met' if command['this'] < CODESIGN_TARGET_S else 'MISSED'})")
    if command["baseline"] is None:
        lines.append("  baseline                  (set MECHOPT_BENCH_BASELINE to a baseline checkout's mechopt)")
    else:
        lines.append(f"  baseline                  {command['baseline']:.2f} s  (this / baseline "
                     f"{command['this'] / command['baseline']:.2f})")
    return "\n".join(lines)


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """The table alone (no figure): `mechopt bench walk`."""
    reps = 1 if quick else min(repeats, 3)
    return table(in_process(repeats=reps, progress=progress), codesign_command(repeats=reps, progress=progress))
