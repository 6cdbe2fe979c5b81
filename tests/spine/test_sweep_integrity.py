"""Sweep output integrity and grid values as typed: one writer per --out,
an atomic and repeatable merge, damaged parts named and recomputed, duplicated tables refused,
requests counted before anything is allocated, Ctrl-C keeping the finished parts, and a scene from
any file run the same in-process, on local processes and on a Dask cluster."""
import os
import subprocess
import sys
from decimal import Decimal

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from mechopt import registry
from mechopt import scene as scene_mod
from mechopt import sweep as sw
from mechopt.figures.sweep import plot_sweep
from mechopt.kit.errors import SceneError

LOOM = "loom/group1"
GRID = "amplitude_limit_mm=0.05:0.15:10"      # 10 variants; chunk 3 makes parts of 3, 3, 3, 1
RUN = registry.run                             # the real one, whatever a test has patched in


def _grid(*texts):
    return [sw.parse_grid(t) for t in texts]


def _values(table):
    """The table without wall-clock columns and messages (which say whether a build was reused):
    every key, status and value must be reproduced exactly."""
    return table.drop_columns(["build_s", "solve_s", "message"])


@pytest.fixture(scope="module")
def clean():
    """The loom sweep run once, start to end, in memory."""
    return sw.sweep(registry.find(LOOM), _grid(GRID), chunk=3, progress=False)


def _counting(monkeypatch, stop_at=None, stop=None):
    """Count the variants solved; raise `stop` instead of solving the `stop_at`-th one."""
    calls = []

    def counted(scene, overrides):
        if stop_at is not None and len(calls) + 1 == stop_at:
            raise stop
        calls.append(dict(overrides))
        return RUN(scene, overrides)
    monkeypatch.setattr(sw.registry, "run", counted)
    return calls


class _Kill(Exception):
    """Stands for a kill -9 at that moment: nothing after it runs."""


def _two_parts(tmp_path, monkeypatch):
    """A sweep stopped after its second chunk: 6 variants in two parts, no table yet."""
    out = tmp_path / "s.parquet"

    def stop_after_two(rows):
        if rows[0]["variant"] == 3:
            raise _Kill
    with pytest.raises(_Kill):
        sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False, on_chunk=stop_after_two)
    return out, sorted((tmp_path / "s.parquet.parts").glob("*.parquet"))


# --- 1. one writer per --out -------------------------------------------------------------------

def test_a_second_sweep_on_the_same_out_is_refused_at_once(tmp_path, clean, monkeypatch):
    scene, out = registry.find(LOOM), tmp_path / "s.parquet"
    calls = _counting(monkeypatch)
    refused = []

    def second_writer(rows):
        if not refused:
            before = len(calls)
            with pytest.raises(SceneError, match=rf"s.parquet is being written by another sweep \(pid {os.getpid()}\); "
                                                 r"wait for it or choose another --out"):
                sw.sweep(scene, _grid("amplitude_limit_mm=0.05:0.15:4"), out=out, progress=False)
            refused.append(len(calls) - before)
    table = sw.sweep(scene, _grid(GRID), out=out, chunk=3, progress=False, on_chunk=second_writer)
    assert refused == [0] and len(calls) == 10          # the second sweep solved nothing; the first, its 10
    assert _values(table).equals(_values(clean))          # the first sweep's table, nothing of the second's
    assert _values(pq.read_table(out)).equals(_values(clean))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.parquet"]     # lock and parts gone


def test_a_lock_held_by_another_process_is_refused_and_nothing_is_written(tmp_path):
    out = tmp_path / "s.parquet"
    holder = subprocess.Popen(
        [sys.executable, "-c", "import fcntl, os, sys, time\n"
         f"fd = os.open({str(out) + '.lock'!r}, os.O_RDWR | os.O_CREAT)\n"
         "fcntl.flock(fd, fcntl.LOCK_EX); os.write(fd, f'{os.getpid()}\\n'.encode())\n"
         "print('locked', flush=True); sys.stdin.read()"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(SceneError, match=rf"is being written by another sweep \(pid {holder.pid}\)"):
            sw.sweep(registry.find(LOOM), _grid(GRID), out=out, progress=False)
    finally:
        holder.communicate("")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.parquet.lock"]    # the holder's, untouched


def test_out_that_is_a_folder_is_refused_before_any_work(tmp_path, monkeypatch):
    calls = _counting(monkeypatch)
    (tmp_path / "out").mkdir()
    with pytest.raises(SceneError, match=r"out: a folder; --out names the table's file"):
        sw.sweep(registry.find(LOOM), _grid(GRID), out=tmp_path / "out", progress=False)
    assert calls == [] and [p.name for p in tmp_path.iterdir()] == ["out"]


# --- 2. an atomic, repeatable merge; duplicated tables refused ---------------------------------

def test_kill_between_merge_and_removing_the_parts_leaves_no_variant_twice(tmp_path, monkeypatch, clean):
    scene, out = registry.find(LOOM), tmp_path / "s.parquet"

    def killed(*args, **kwargs):
        raise _Kill
    with monkeypatch.context() as m:
        m.setattr(sw._Store, "_remove_parts", killed)
        with pytest.raises(_Kill):
            sw.sweep(scene, _grid(GRID), out=out, chunk=3, progress=False)
    assert pq.read_table(out).num_rows == 10 and len(list((tmp_path / "s.parquet.parts").glob("*.parquet"))) == 4
    (tmp_path / "s.parquet.4242.tmp").write_bytes(b"not the sweep's")    # named as the old temporaries were
    calls = _counting(monkeypatch)
    table = sw.sweep(scene, _grid(GRID), out=out, chunk=3, progress=False)
    assert calls == []
    assert _values(table).equals(_values(clean))
    assert _values(sw.read_table(out)[0]).equals(_values(clean))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.parquet", "s.parquet.4242.tmp"]   # not its own: kept


def test_a_table_with_variants_twice_is_refused_and_a_rerun_repairs_it(tmp_path, monkeypatch, clean):
    out = tmp_path / "s.parquet"
    sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False)
    meta = pq.read_schema(out).metadata
    twice = pa.concat_tables([pq.read_table(out)] * 2).replace_schema_metadata(meta)   # the old merge's 2 x 10 rows
    pq.write_table(twice, out)
    with pytest.raises(SceneError, match=r"s.parquet: 10 variants are stored more than once \(0, 1, 2, 3, 4, \.\.\.\); "
                                         r"the table is not one sweep's"):
        sw.read_table(out)
    with pytest.raises(SceneError, match=r"sweep table of loom/group1: 10 variants are stored more than once"):
        plot_sweep(twice, tmp_path / "fig")
    assert not (tmp_path / "fig").exists()
    calls = _counting(monkeypatch)
    table = sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False)
    assert calls == [] and _values(table).equals(_values(clean))
    assert sw.read_table(out)[0].num_rows == 10


# --- 3. damaged parts: named, dropped, recomputed ---------------------------------------------

def _flip(data):
    middle = len(data) // 2
    return data[:middle] + bytes(b ^ 0xFF for b in data[middle:middle + 8]) + data[middle + 8:]


@pytest.mark.parametrize("damage", [_flip, lambda d: d[:len(d) // 2], lambda d: bytes(len(d))],
                         ids=["flipped", "truncated", "zeroed"])
def test_a_damaged_part_is_named_and_recomputed(tmp_path, monkeypatch, clean, damage):
    out, parts = _two_parts(tmp_path, monkeypatch)
    parts[0].write_bytes(damage(parts[0].read_bytes()))
    calls = _counting(monkeypatch)
    with pytest.warns(sw.SweepWarning, match=r"part-000000000.parquet: damaged \(checksum mismatch\); "
                                             r"its 3 variants are recomputed"):
        table = sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False)
    solved = [c["amplitude_limit_mm"] for c in calls]
    assert sorted(solved) == sorted(clean.column("amplitude_limit_mm").to_pylist()[i] for i in (0, 1, 2, 6, 7, 8, 9))
    assert _values(table).equals(_values(clean))


def test_an_unreadable_part_is_named_and_recomputed(tmp_path, monkeypatch, clean):
    out, parts = _two_parts(tmp_path, monkeypatch)
    calls = _counting(monkeypatch)
    read = sw.read_regular

    def refused(path, **how):       # as an unreadable file (chmod 0 does not stop root)
        if path == parts[0]:
            raise PermissionError(13, "Permission denied")
        return read(path, **how)
    monkeypatch.setattr(sw, "read_regular", refused)
    with pytest.warns(sw.SweepWarning, match=r"part-000000000.parquet: unreadable \(Permission denied\); "
                                             r"its 3 variants are recomputed"):
        table = sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False)
    assert len(calls) == 7
    assert _values(table).equals(_values(clean))


def test_a_folder_named_as_a_part_is_named_and_left_alone(tmp_path, monkeypatch):
    out, parts = _two_parts(tmp_path, monkeypatch)
    parts[0].unlink()
    parts[0].mkdir()
    (parts[0] / "keep.txt").write_text("precious")
    with pytest.raises(SceneError, match=r"part-000000000.parquet: not a file this sweep wrote \(a folder or a link\)"):
        sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False)
    assert (parts[0] / "keep.txt").read_text() == "precious"


def test_a_damaged_part_that_cannot_be_removed_is_named(tmp_path, monkeypatch):
    out, parts = _two_parts(tmp_path, monkeypatch)
    parts[0].write_bytes(b"")

    def refused(self, missing_ok=False):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(sw.Path, "unlink", refused)
    with pytest.warns(sw.SweepWarning), pytest.raises(
            SceneError, match=r"part-000000000.parquet: cannot remove this damaged part \(Permission denied\); "
                              r"remove it by hand and re-run"):
        sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False)


def test_a_part_without_its_checksum_is_recomputed(tmp_path, monkeypatch, clean):
    out, parts = _two_parts(tmp_path, monkeypatch)
    parts[1].with_name(parts[1].name + ".sha256").unlink()         # killed between the part and its sum
    calls = _counting(monkeypatch)
    with pytest.warns(sw.SweepWarning, match=r"part-000000003.parquet: no checksum .*; its variants are recomputed"):
        table = sw.sweep(registry.find(LOOM), _grid(GRID), out=out, chunk=3, progress=False)
    assert len(calls) == 7
    assert _values(table).equals(_values(clean))


# --- 4. limits before work ---------------------------------------------------------------------

def test_a_huge_request_is_refused_before_anything_is_allocated():
    import tracemalloc
    scene = registry.find("cam-cutter/minimax")
    tracemalloc.start()
    with pytest.raises(SceneError, match=r"1,000,000,000 variants \(about 400 GB of memory before any solver runs\) "
                                         r"exceed the limit of 1,000,000; narrow the ranges, or raise the limit"):
        sw.sweep(scene, _grid("a_mm=20:30:1000", "h_mm=1:3:1000", "step_mm=0.01:0.02:1000"), progress=False)
    with pytest.raises(SceneError, match=r"100,000,000 variants \(about 40 GB"):
        sw.plan(scene, random=[sw.parse_random("a_mm=20:30")], samples=10 ** 8)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 10 * 2**20                            # bytes: a thousand points an axis at most, no product
    with pytest.raises(SceneError, match=r"^6 variants \(about 2.4 kB .* exceed the limit of 5;"):
        sw.plan(scene, _grid("a_mm=20:30:3", "h_mm=1:2:2"), max_variants=5)
    assert len(sw.plan(scene, _grid("a_mm=20:30:3", "h_mm=1:2:2"), max_variants=6)[1]) == 6   # the limit is raised
    with pytest.raises(SceneError, match=r"max_variants = 0: expected a whole number >= 1"):
        sw.plan(scene, _grid("a_mm=20:30:3"), max_variants=0)


@pytest.mark.parametrize("text, flag, message", [
    ("a_mm=0:1e300:3", "grid", r"STOP = 1e300 is beyond ±1e\+12; no parameter or setting of a mechanism is that large"),
    ("a_mm=-2e12:0:3", "grid", r"START = -2e12 is beyond ±1e\+12"),
    ("a_mm=-inf:0:3", "grid", r"START = '-inf' is not a finite number"),
    ("a_mm=nan:1", "random", r"LOW = 'nan' is not a finite number"),
    ("a_mm=1:1e13", "random", r"HIGH = 1e13 is beyond ±1e\+12"),
])
def test_silly_axis_values_are_refused(text, flag, message):
    with pytest.raises(SceneError, match=message):
        (sw.parse_grid if flag == "grid" else sw.parse_random)(text)


# --- 5. Ctrl-C ---------------------------------------------------------------------------------

def test_ctrl_c_keeps_finished_parts_and_says_how_to_resume(tmp_path, monkeypatch, clean):
    scene, out = registry.find(LOOM), tmp_path / "s.parquet"
    _counting(monkeypatch, stop_at=7, stop=KeyboardInterrupt())       # during the third chunk
    with pytest.raises(sw.SweepInterrupted, match=r"^sweep of loom/group1 interrupted: 6 of 10 variants done, kept in "
                                                  r".*s.parquet.parts; re-run the same command to resume$") as err:
        sw.sweep(scene, _grid(GRID), out=out, chunk=3, progress=False)
    assert (err.value.done, err.value.total) == (6, 10)
    assert len(list((tmp_path / "s.parquet.parts").glob("*.parquet"))) == 2
    assert not (tmp_path / "s.parquet.lock").exists()
    calls = _counting(monkeypatch)
    table = sw.sweep(scene, _grid(GRID), out=out, chunk=3, progress=False)
    assert len(calls) == 4 and _values(table).equals(_values(clean))
    _counting(monkeypatch, stop_at=2, stop=KeyboardInterrupt())
    with pytest.raises(sw.SweepInterrupted, match=r"0 of 10 variants done, nothing was kept \(no --out\)"):
        sw.sweep(scene, _grid(GRID), chunk=3, progress=False)


# --- 6. a scene from any file ------------------------------------------------------------------

@pytest.fixture
def own_scene(tmp_path):
    text = (registry.cases_dir() / "cam-cutter" / "minimax.toml").read_text(encoding="utf-8")
    assert 'id = "cam-cutter/minimax"' in text and "a_mm = { value = 25.0," in text
    text = text.replace('id = "cam-cutter/minimax"', 'id = "my/cam"').replace("a_mm = { value = 25.0,",
                                                                              "a_mm = { value = 30.0,")
    path = tmp_path / "elsewhere" / "my-cam.toml"
    path.parent.mkdir()
    path.write_text(text, encoding="utf-8")
    return scene_mod.load(path)


@pytest.mark.slow
def test_a_scene_from_any_file_runs_alike_everywhere(own_scene, tmp_path):
    distributed = pytest.importorskip("distributed")
    with pytest.raises(SceneError, match="unknown case 'my/cam'"):
        registry.find("my/cam")                    # not in the registry: the workers cannot look it up
    grid = _grid("h_mm=1.5:2.5:3")
    here = sw.sweep(own_scene, grid, chunk=1, progress=False)
    for row in here.to_pylist():                   # each row is a direct run of this file's scene (a = 30)
        direct = registry.run(own_scene, {"h_mm": row["h_mm"]}).result
        assert row["status"] == direct.status.value == "SOLVED"
        assert row["max_deviation_mm"] == direct.values["max_deviation_mm"]
        published = registry.run(registry.find("cam-cutter/minimax"), {"h_mm": row["h_mm"]}).result
        assert abs(row["H_mm"] - published.values["H_mm"]) > 1.0        # a = 30, not the registry's 25
    pooled = sw.sweep(own_scene, grid, chunk=1, workers=2, progress=False)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0") as c:
        there = sw.sweep(own_scene, grid, chunk=1, scheduler=c.scheduler_address, out=tmp_path / "d.parquet",
                         progress=False)
    assert _values(pooled).equals(_values(here))
    assert _values(there).equals(_values(here))
    assert sw.read_table(tmp_path / "d.parquet")[1]["scene_sha256"] == sw.scene_hash(own_scene)


# --- 7. grid values as typed ---------------------------------------------------------------

def test_grid_values_are_stored_as_typed():
    assert np.linspace(0.05, 0.1, 3)[1] == 0.07500000000000001       # what used to be stored
    table = sw.sweep(registry.find(LOOM), _grid("amplitude_limit_mm=0.05:0.1:3"), progress=False)
    assert table.column("amplitude_limit_mm").to_pylist() == [0.05, 0.075, 0.1]
    assert table.filter(pc.equal(table.column("amplitude_limit_mm"), 0.075)).num_rows == 1
    for text in ("x=0.05:0.15:10", "x=0.1:0.7:7", "x=-0.004:0:3", "x=700:900:3", "x=1e-6:3e-6:5"):
        start, stop, num = text.split("=")[1].split(":")
        exact = [Decimal(start) + i * (Decimal(stop) - Decimal(start)) / (int(num) - 1) for i in range(int(num))]
        assert sw.grid_values(sw.parse_grid(text)) == [float(f"{d:.12g}") for d in exact], text


def test_grid_values_of_a_narrow_range_stay_distinct():
    values = sw.grid_values(sw.parse_grid("x=1000.0000000001:1000.0000000003:3"))
    assert values == pytest.approx([1000.0000000001, 1000.0000000002, 1000.0000000003], abs=2e-13)
    assert len(set(values)) == 3
