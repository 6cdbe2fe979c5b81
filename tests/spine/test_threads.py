"""Thread safety: the build caches, the cvxpy problems re-solved with new Parameter values, CasADi's
integrators, and a sweep on one Dask worker running four tasks at once in threads, every row
against the serial sweep."""
import itertools
import os
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import mechopt
from mechopt import registry
from mechopt import sweep as sw
from mechopt.kit.cache import BuildCache

LOOM = "loom/group1"
AXES = ("amplitude_limit_mm=0.05:0.2:20", "sigma_H_limit_MPa=600:1000:10")       # 200 variants
THREADS = 4


def _at_once(work, threads=THREADS):
    """`work()` in `threads` threads released together; their answers."""
    start = threading.Barrier(threads)

    def run(_):
        start.wait()
        return work()
    with ThreadPoolExecutor(threads) as pool:
        return list(pool.map(run, range(threads)))


def test_threads_asking_together_for_a_key_get_one_build():
    cache, builds = BuildCache("test.one_build", 4), []

    def build():
        builds.append(1)
        time.sleep(0.05)          # the others arrive while it is being built
        return object()
    got = _at_once(lambda: cache.get("k", build)[0])
    assert len(builds) == 1 and all(g is got[0] for g in got)
    cache.clear()


def test_a_held_build_serves_one_thread_at_a_time():
    cache, inside, most = BuildCache("test.held", 4), [0], [0]

    def use():
        with cache.held("lp", dict) as (lp, _):
            inside[0] += 1
            most[0] = max(most[0], inside[0])
            lp["parameter"] = threading.get_ident()
            time.sleep(0.01)      # another thread setting the parameter now would be seen below
            seen = lp["parameter"]
            inside[0] -= 1
            return seen == threading.get_ident()
    assert all(_at_once(use)) and most[0] == 1
    cache.clear()


def test_a_per_thread_cache_builds_once_per_thread_and_keeps_it():
    cache = BuildCache("test.per_thread", 16, per_thread=True)
    first = _at_once(lambda: cache.get("integrator", object)[0])
    assert len({id(g) for g in first}) == THREADS
    mine = cache.get("integrator", object)[0]
    assert cache.get("integrator", object) == (mine, 0.0) and "integrator" in cache
    cache.clear()


@pytest.mark.slow
def test_cvodes_solves_on_four_threads_match_serial_ones_and_do_not_crash():
    """CasADi's CVODES integrators are kept per thread: one shared by threads at once corrupted
    its memory (the process aborted: munmap_chunk(): invalid pointer)."""
    variants = [{"damping_ratio": float(z)} for z in np.linspace(0.02, 0.1, 12)]

    def answer(overrides):
        run = mechopt.solve("stop-impact/rebound-177rpm-paper-reading", overrides)
        return run.status.value, dict(run.values)
    serial = [answer(v) for v in variants]
    with ThreadPoolExecutor(THREADS) as pool:
        threaded = list(pool.map(answer, variants))
    assert {status for status, _ in serial} == {"SOLVED"}
    assert [i for i, (a, b) in enumerate(zip(threaded, serial)) if a != b] == []


def _rows(table):
    """(status, values) per variant, the timings and the message (compiled or re-solved) left out."""
    keep = [c for c in table.column_names if c not in ("build_s", "solve_s", "message")]
    return table.select(keep).to_pylist()


@pytest.fixture(scope="module")
def serial_table():
    return sw.sweep(registry.find(LOOM), [sw.parse_grid(a) for a in AXES], chunk=5, progress=False)


@pytest.mark.slow
def test_a_sweep_on_one_worker_with_four_threads_matches_the_serial_sweep(serial_table):
    distributed = pytest.importorskip("distributed")
    # one worker in this process: its four threads share every cache and cached LP of the process
    with distributed.LocalCluster(n_workers=1, threads_per_worker=THREADS, processes=False,
                                  dashboard_address=":0") as cluster:
        threaded = sw.sweep(registry.find(LOOM), [sw.parse_grid(a) for a in AXES], chunk=5,
                            scheduler=cluster.scheduler_address, progress=False)
    assert threaded.num_rows == serial_table.num_rows == 200
    serial = _rows(serial_table)
    assert {r["status"] for r in serial} == {"SOLVED"}
    assert [i for i, (a, b) in enumerate(zip(_rows(threaded), serial)) if a != b] == []


@pytest.mark.slow
def test_lp_solves_through_the_api_on_four_threads_match_serial_ones():
    """The cached event-time LP re-solved with each variant's Parameters: every status, value and
    sensitivity (its duals) as when solved one after another."""
    variants = [{"amplitude_limit_mm": float(a), "sigma_H_limit_MPa": float(s), "method": "lp"}
                for a, s in itertools.product(np.linspace(0.05, 0.2, 20), np.linspace(600, 1000, 10))]

    def answer(overrides):
        run = mechopt.solve(LOOM, overrides)
        return run.status.value, dict(run.values)
    serial = [answer(v) for v in variants]
    with ThreadPoolExecutor(THREADS) as pool:
        threaded = list(pool.map(answer, variants))
    assert {status for status, _ in serial} == {"SOLVED"} and any(k.startswith("sens_") for k in serial[0][1])
    assert [i for i, (a, b) in enumerate(zip(threaded, serial)) if a != b] == []


def test_threads_making_the_first_highs_object_together_leave_stdout_where_it_was(monkeypatch):
    """Each thread's swap of descriptor 1 staggered after the one before it has begun: unguarded, a
    later thread saves the earlier one's null device as its "stdout" and restores that, last."""
    from mechopt.kit import highs
    arrived = itertools.count()

    class Staggered:            # sys.stdout, whose flush (the swap's first step) waits its turn
        def flush(self):
            time.sleep(0.02 * next(arrived))

    class SlowHighs:            # the first Highs object, made while descriptor 1 is swapped
        def __init__(self):
            time.sleep(0.1)
    monkeypatch.setattr(highs, "RealHighs", SlowHighs)
    monkeypatch.setattr(sys, "stdout", Staggered())
    highs.quiet_banner.cache_clear()
    before = os.fstat(1)
    try:
        _at_once(highs.quiet_banner)
    finally:
        highs.quiet_banner.cache_clear()
    after = os.fstat(1)
    assert (after.st_dev, after.st_ino) == (before.st_dev, before.st_ino)
