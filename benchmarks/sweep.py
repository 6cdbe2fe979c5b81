"""Sweep throughput (`mechopt sweep`): variants per second in-process, and the Dask path's overhead.

* ``loom/group1``          a 100 x 100 grid of amplitude_limit_mm x sigma_H_limit_MPa (10^4 DPP re-solves
                           of the event-time LP), in this process, Parquet parts written as they arrive;
* ``cam-cutter/minimax``   a 100 x 100 grid of a_mm x h_mm (10^4 minimax NLPs, SQP rounds, cached build, each answer certified),
                           in this process, and on 2 local processes (``--workers 2``: spawn and
                           imports included in the time);
* ``Dask overhead``        the same loom sweep (2 000 variants) on a `distributed.LocalCluster` with
                           ONE single-threaded worker process against in-process, for chunks of 100,
                           500 and 2 000 variants: the ratio is the price of the Dask path per core
                           (scheduling, pickling rows back); a 2-worker run shows what the second
                           core buys. Workers are warmed up first (imports, the cached LP build), as
                           the in-process engine is.

Total wall time per sweep (including writing the table) is reported as the median of the runs.
Timings live here only; tests never assert them.
"""
import logging
import statistics
import tempfile
import time
from pathlib import Path

from mechopt import registry
from mechopt.sweep import parse_grid, sweep

__all__ = ["cli", "in_process", "solve_loop", "dask_overhead", "TARGETS"]

# Verdicts are ratios to a baseline timed in the same run (a loaded machine slows both): a sweep's
# time per variant against the same variants solved one by one by `registry.run` (the sweep's
# chunks, cached builds and Parquet parts may cost at most 20 % more); two local processes against
# one; the Dask path with one worker against in-process.
TARGETS = {"sweep_over_solve_loop": 1.20, "workers_2_over_in_process": 0.75, "dask_over_in_process": 1.20}
LOOP_SAMPLES = 100               # variants of the grid solved one by one for the baseline
LOOM_GRID = ("amplitude_limit_mm=0.05:0.2:{n}", "sigma_H_limit_MPa=600:1000:{n}")
CAM_GRID = ("a_mm=20:30:{n}", "h_mm=0:3:{n}")
CAM_REPEATS_MAX = 3               # a 10^4 cam sweep takes ~6 min: at most 3 runs for the median
DASK_CHUNKS = (100, 500, 2000)
DASK_SIDE = 45                   # 2 025 variants per Dask sweep


def _grid(texts, side):
    return [parse_grid(t.format(n=side)) for t in texts]


def _timed(case, grid, chunk, scheduler=None, workers=1):
    """Wall seconds for one sweep to a fresh Parquet file, its status counts, and the CPU seconds
    of this process meanwhile (the whole work of an in-process sweep: what it takes on a quiet
    machine, whatever the load)."""
    with tempfile.TemporaryDirectory() as folder:
        start, cpu = time.perf_counter(), time.process_time()
        table = sweep(registry.find(case), grid, out=Path(folder) / "s.parquet", chunk=chunk,
                      scheduler=scheduler, workers=workers, progress=False)
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    statuses = table.column("status").to_pylist()
    return seconds, {s: statuses.count(s) for s in sorted(set(statuses))}, cpu


def in_process(case, texts, side, *, chunk=1000, repeats=3, workers=1, progress=None):
    """Median wall time [s] of a side x side sweep in this process (after one small warm-up sweep),
    or on `workers` local processes (spawned by the sweep: their start-up is in the time), the
    status counts of the last run, the number of variants and the median CPU seconds of this
    process (None on several processes: the work is theirs)."""
    _timed(case, _grid(texts, 2), chunk)
    if workers > 1:     # every process gets chunks to take (a quick 900-variant sweep was one chunk: one process)
        chunk = min(chunk, -(-side * side // (4 * workers)))
    times, cpus, counts = [], [], {}
    for r in range(repeats):
        seconds, counts, cpu = _timed(case, _grid(texts, side), chunk, workers=workers)
        times.append(seconds)
        cpus.append(cpu)
        if progress:
            progress(f"{case}: {side * side} variants on {workers} process(es) in {seconds:.1f} s "
                     + (f"({cpu:.1f} s CPU) " if workers == 1 else "") + f"(run {r + 1}/{repeats})")
    return statistics.median(times), counts, side * side, statistics.median(cpus) if workers == 1 else None


def solve_loop(case, texts, side, *, samples=LOOP_SAMPLES):
    """Seconds per variant of `samples` variants spread over the same grid, solved one by one by
    `registry.run` (the baseline of a sweep's verdict), after one warm-up solve."""
    import itertools

    from mechopt.sweep import grid_values
    axes = _grid(texts, side)
    points = list(itertools.product(*(grid_values(a) for a in axes)))
    chosen = points[:: max(1, len(points) // samples)][:samples]
    scene = registry.find(case)
    registry.run(scene, dict(zip((a.key for a in axes), chosen[0])))
    start = time.perf_counter()
    for point in chosen:
        registry.run(scene, dict(zip((a.key for a in axes), point)))
    return (time.perf_counter() - start) / len(chosen)


def dask_overhead(*, side=DASK_SIDE, repeats=3, progress=None):
    """Median wall time [s] per chunk size: in-process, Dask with 1 worker, Dask with 2 workers."""
    from distributed import Client, LocalCluster
    # dashboard_address ":0": any free port (the default 8787 is taken by the second cluster: a warning)
    grid = _grid(LOOM_GRID, side)
    out = {}
    clusters = {w: LocalCluster(n_workers=w, processes=True, threads_per_worker=1, dashboard_address=":0",
                                silence_logs=logging.CRITICAL)   # a worker closing mid-heartbeat logs at ERROR
                for w in (1, 2)}
    try:
        for cluster in clusters.values():          # warm the workers: imports and the cached LP build
            with Client(cluster.scheduler_address) as client:
                client.wait_for_workers(len(cluster.workers))
            _timed("loom/group1", _grid(LOOM_GRID, 10), 10, cluster.scheduler_address)
        _timed("loom/group1", _grid(LOOM_GRID, 10), 10)
        for chunk in DASK_CHUNKS:
            row = {}
            for name, scheduler in (("in_process", None), ("dask_1", clusters[1].scheduler_address),
                                    ("dask_2", clusters[2].scheduler_address)):
                row[name] = statistics.median(_timed("loom/group1", grid, chunk, scheduler)[0]
                                              for _ in range(repeats))
            out[chunk] = row
            if progress:
                progress(f"dask overhead, chunk {chunk}: " + ", ".join(f"{k} {v:.2f} s" for k, v in row.items()))
    finally:
        logging.getLogger("distributed").setLevel(logging.ERROR)     # closing logs at INFO otherwise
        for cluster in clusters.values():
            cluster.close()
    return out


def table(loom, cam, cam_pool, dask, dask_side=DASK_SIDE, loops=None):
    """The throughput and its verdicts: ratios to baselines timed in the same run (`TARGETS`)."""
    loops = loops or {}
    lines = ["sweep throughput (medians; wall time including the Parquet table; CPU: this process's)",
             f"{'sweep':<34}{'variants':>9}{'median s':>10}{'ms/variant':>12}{'CPU ms':>8}{'baseline ms':>13}"
             f"{'ratio':>7}{'target':>8}  verdict  statuses"]
    rows = (("loom/group1 in-process", loom, loops.get("loom"), "one by one", TARGETS["sweep_over_solve_loop"]),
            ("cam-cutter/minimax in-process", cam, loops.get("cam"), "one by one", TARGETS["sweep_over_solve_loop"]),
            ("cam-cutter/minimax --workers 2", cam_pool, cam[0] / cam[2], "in-process",
             TARGETS["workers_2_over_in_process"]))
    for name, (seconds, counts, n, cpu), base, _, target in rows:
        per = seconds / n
        verdict = "" if base is None else ("met" if per / base < target else "MISSED")
        ratio = f"{per / base:>7.2f}" if base else f"{'-':>7}"
        cpu = f"{cpu / n * 1e3:>8.2f}" if cpu is not None else f"{'-':>8}"
        lines.append(f"{name:<34}{n:>9}{seconds:>10.1f}{per * 1e3:>12.2f}{cpu}{(base or 0) * 1e3:>13.2f}{ratio}"
                     f"{'< ' + format(target, 'g'):>8}  {verdict:<7}  {counts}")
    lines.append("baselines: the same grid's variants solved one by one by registry.run "
                 f"({LOOP_SAMPLES} of them); --workers 2 against the in-process sweep")
    lines += ["", f"Dask path on a LocalCluster, loom/group1, {dask_side * dask_side} variants (target: 1 worker / in-process "
              f"< {TARGETS['dask_over_in_process']:.2f})",
              f"{'chunk':>7}{'in-process s':>14}{'dask 1w s':>11}{'ratio':>7}{'dask 2w s':>11}{'ratio':>7}  verdict"]
    for chunk, row in dask.items():
        ratio = row["dask_1"] / row["in_process"]
        lines.append(f"{chunk:>7}{row['in_process']:>14.2f}{row['dask_1']:>11.2f}"
                     f"{ratio:>7.2f}{row['dask_2']:>11.2f}"
                     f"{row['dask_2'] / row['in_process']:>7.2f}  "
                     f"{'met' if ratio < TARGETS['dask_over_in_process'] else 'MISSED'}")
    return "\n".join(lines)


QUICK_SIDE, QUICK_DASK_SIDE = 30, 20          # --quick: 900 and 400 variants, one run each
WARM_UP_S = 25.0                 # imports, clusters started, warm-up sweeps
# Per 10^4 variants / per run [s] on a quiet 2-core machine: an in-process sweep takes its CPU time
# (the table's CPU column). Re-measured with the certificate at under two solves (--quick, 900
# variants, on a 2-core machine shared by six sessions): loom 3.7 ms of CPU a variant; cam
# (cam-cutter/minimax, every answer certified: a_mm 20..30 x h_mm 0..3, neighbours too far apart
# for a warm start) 30 ms (9.7 ms uncertified; it was 46 ms); on 2 processes half of it plus ~5 s of
# spawn and imports; a Dask run of 2 025 variants ~3 s. The quick mode: 1 min 35 s wall at load
# ~2 (47 s of CPU in this process; cam in-process 27 s, on 2 processes 31 s: the other sessions held
# the second core; Dask 24 s with its clusters' start), 2 min 19 s at load ~3.5, 4 min 32 s at ~7.5
MEASURED_S = {"loom": 37.0, "cam": 300.0, "cam_pool": 170.0, "dask_chunk": 3.0}


def expected_s(repeats, quick=False) -> float:
    """A rough wall time [s] of `cli` on 2 cores (from the medians measured when it was written)."""
    if quick:
        repeats, scale, dask_scale = 1, QUICK_SIDE**2 / 1e4, (QUICK_DASK_SIDE / DASK_SIDE) ** 2
    else:
        scale, dask_scale = 1.0, 1.0
    cam_repeats = min(repeats, CAM_REPEATS_MAX)
    return (WARM_UP_S + scale * (repeats * MEASURED_S["loom"] + cam_repeats * (MEASURED_S["cam"] + MEASURED_S["cam_pool"]))
            + dask_scale * len(DASK_CHUNKS) * 3 * repeats * MEASURED_S["dask_chunk"])


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """What `mechopt bench sweep` prints, and its figure in out_dir. The 10^4 cam sweeps run at most
    CAM_REPEATS_MAX times (minutes each); `quick` runs 900-variant sweeps once (about 1.5 min on a
    quiet 2-core machine: the cam sweeps in-process and on two processes are two thirds of it, and
    fewer variants would leave the two processes' start-up, ~5 s, deciding their verdict)."""
    side, dask_side = (QUICK_SIDE, QUICK_DASK_SIDE) if quick else (100, DASK_SIDE)
    repeats = 1 if quick else repeats
    if progress:
        seconds = expected_s(repeats, quick)
        progress(f"sweep benchmark: expect about {f'{seconds / 60:.0f} min' if seconds > 120 else f'{seconds:.0f} s'} "
                 "on a quiet 2-core machine" + ("" if quick else f" (--quick: about {expected_s(1, True) / 60:.1f} min)"))
    loom = in_process("loom/group1", LOOM_GRID, side, repeats=repeats, progress=progress)
    cam_repeats = min(repeats, CAM_REPEATS_MAX)
    cam = in_process("cam-cutter/minimax", CAM_GRID, side, repeats=cam_repeats, progress=progress)
    cam_pool = in_process("cam-cutter/minimax", CAM_GRID, side, repeats=cam_repeats, workers=2, progress=progress)
    dask = dask_overhead(side=dask_side, repeats=repeats, progress=progress)
    loops = {"loom": solve_loop("loom/group1", LOOM_GRID, side),
             "cam": solve_loop("cam-cutter/minimax", CAM_GRID, side)}
    plot(loom, cam, cam_pool, dask, out_dir)
    return table(loom, cam, cam_pool, dask, dask_side, loops)


def plot(loom, cam, cam_pool, dask, out_dir):
    """Variants per second of each route, and the Dask path's time over in-process per chunk size."""
    from mechopt.figures import save_figure
    from mechopt.figures.registry import new_figure
    fig = new_figure(figsize=(11, 4.5))
    left, right = fig.subplots(1, 2)
    names = ["loom/group1\nin-process", "cam-cutter/minimax\nin-process", "cam-cutter/minimax\n--workers 2"]
    rates = [n / seconds for seconds, _, n, _ in (loom, cam, cam_pool)]
    left.bar(names, rates, color=["tab:blue", "tab:orange", "tab:green"])
    for i, rate in enumerate(rates):
        left.annotate(f"{rate:.0f}", (i, rate), ha="center", va="bottom", fontsize=9)
    left.set(ylabel="variants per second [1/s]", title="sweep throughput (median wall time, table included)")
    chunks = list(dask)
    for key, colour, label in (("dask_1", "tab:red", "Dask, 1 worker"), ("dask_2", "tab:purple", "Dask, 2 workers")):
        right.plot(chunks, [dask[c][key] / dask[c]["in_process"] for c in chunks], "o-", color=colour, label=label)
    right.axhline(TARGETS["dask_over_in_process"], color="0.4", ls=":", label="target for 1 worker")
    right.axhline(1.0, color="k", lw=0.6)
    right.set(xscale="log", xlabel="chunk [variants per task]", ylabel="wall time / in-process [-]",
              title="loom/group1 on a LocalCluster")
    right.legend(fontsize=8)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, out_dir / "sweep_throughput.png")
