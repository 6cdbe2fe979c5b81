"""What-if studies at scale: run every variant of a scene and keep one table of the answers.

A sweep is a scene plus ranges of its parameters or solver settings: ``--grid KEY=START:STOP:NUM``
(evenly spaced, all combinations) and ``--random KEY=LOW:HIGH --samples N`` (uniform, seeded; each
sample is combined with every grid point). Variants are numbered in a fixed order, so a sweep's
spec names the same variants every time it is expanded.

Variants run in chunks: in this process by default, or on a Dask distributed cluster when a
scheduler address is given. A worker finds the scene once and its solver keeps its build (the
CasADi NLP, the cvxpy problem with Parameters) per process, so a chunk is re-solves, not rebuilds;
a chunk's variants share one `kit.warm` session, so a solver may start from the variant before
(the cam-cutter certificate does, where its bound allows).
A variant that fails (infeasible, solver error, a setting the model refuses) is a row with its
status and message; the sweep goes on. Each finished chunk is written at once as one Parquet part
in the folder ``<out>.parts/``; the parts are consolidated into ``<out>`` at the end, so a stopped
sweep loses at most the chunks in flight and a re-run with the same ``--out`` skips what is done.
The file carries its case, its sweep spec and its scene file's hash in the Parquet metadata, and
a file of another sweep is refused rather than mixed.

Integrity: one writer per ``--out`` (an OS lock on ``<out>.lock``, opened without following a
link and re-checked at every chunk; a second sweep is refused at once); only files named as this
sweep's own are read or removed (a temporary only when its name is recorded in the sweep's own
lock, never by a pattern); each part has a sha256 beside it (``part-N.parquet.sha256``), and
a part that fails it is named, dropped and recomputed; the merge writes a temporary file, fsyncs it
and renames it over ``<out>``, and drops part rows already in ``<out>``, so a kill at any moment
leaves no variant twice. A table with a variant stored twice is refused when read or drawn. A
request is counted before anything is allocated and refused past ``max_variants``. The scene travels with each chunk
as its TOML text and hash, with every file it references (CSV tables, base scenes), so a scene from
any file runs on any worker.

Row columns: the swept keys, ``variant`` (its number), ``status`` (a Result status, or INVALID for
a setting the scene or model refuses, ERROR for an unexpected exception), ``message``, ``build_s``,
``solve_s``, then every ``values`` entry of the result (null where a variant did not produce it).
"""
import difflib
import hashlib
import inspect
import itertools
import json
import math
import numbers
import os
import re
import stat
import sys
import types
import warnings
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal, get_origin

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from mechopt import registry
from mechopt.files import (
    NAME_ROOM,
    holds,
    make_folder,
    open_regular,
    read_regular,
    recorded,
    shipped,
    take_lock,
    temporary_target,
    write_bytes_atomic,
)
from mechopt.kit import warm
from mechopt.kit.cache import BuildCache
from mechopt.kit.errors import MechoptError, SceneError, SolverError, quote
from mechopt.scene import MAX_SCENE_BYTES, Scene, loads, path_head, solver_options, split_assignment, task_fields

__all__ = ["Axis", "SweepSpec", "SceneText", "SweepInterrupted", "SweepWarning", "parse_grid", "parse_random",
           "grid_values", "count_variants", "plan", "sweep", "run_chunk", "read_table", "check_unique", "scene_hash", "describe_axes", "study", "list_problem"]

META_KEY = b"mechopt.sweep"
FIXED_COLUMNS = ("variant", "status", "message", "warnings", "build_s", "solve_s")
MAX_VARIANTS = 1_000_000
BYTES_PER_VARIANT = 400         # plan dicts (~190 B, 2 keys) and table; the audit saw 3.3 GB for 10^7
AXIS_LIMIT = 1e12               # no length, stress, speed or setting of a mechanism is larger
GRID_DIGITS = 12                # grid values keep this many significant digits (0.075, not 0.07500000000000001)
MAX_TABLE_BYTES = 4 * 10**9     # a table or part read back: 10^6 variants of a few dozen columns are far less
MAX_LOCK_BYTES = 4096           # a lock file holds a pid and the temporary in flight
MAX_CHECK_BYTES = 200           # a part's checksum file: 64 hex digits and a count


class SweepInterrupted(MechoptError):
    """Ctrl-C during a sweep: the finished variants are kept; `done` of `total` were computed."""

    def __init__(self, message: str, *, done: int, total: int):
        super().__init__(message)
        self.done, self.total = done, total


class SweepWarning(UserWarning):
    """Something on disk was repaired (a damaged part dropped and recomputed)."""


@dataclass(frozen=True)
class SceneText:
    """A scene as a worker receives it: its file's text, where it came from, the sha256 of its
    bytes, and every file it references (CSV tables, base and lever scenes) by resolved path, so
    that a worker on another machine needs no copy of them."""
    text: str
    path: str
    sha256: str
    files: tuple = ()           # ((resolved path, bytes), ...)

    @classmethod
    def of(cls, scene: Scene) -> "SceneText":
        try:
            data = read_regular(scene.path, max_bytes=MAX_SCENE_BYTES, what="a scene file")
            with recorded() as referenced:
                loads(data.decode("utf-8"), Path(scene.path))
        except OSError as exc:
            raise SceneError(f"{scene.path}: cannot read the scene file to send it to the workers: "
                             f"{exc.strerror}") from None
        except ValueError as exc:        # no longer a regular file, or grown past a scene's size
            raise SceneError(f"{exc} (the scene file changed after it was loaded)") from None
        return cls(data.decode("utf-8"), str(scene.path), hashlib.sha256(data).hexdigest(),
                   tuple(sorted(referenced.items())))

    @property
    def digest(self) -> str:
        """sha256 of the text and every file sent with it: a worker's cache key."""
        h = hashlib.sha256(self.sha256.encode())
        for path, data in self.files:
            h.update(path.encode() + b"\0" + hashlib.sha256(data).digest())
        return h.hexdigest()


@dataclass(frozen=True)
class Axis:
    """One swept key: `num` evenly spaced values from `low` to `high` (grid), the listed `values`
    (a grid axis given as a list: `low`, `high` and `num` are then their least, greatest and count),
    or uniform draws (random)."""
    key: str
    low: float
    high: float
    num: int = 0            # grid points; 0 for a random axis
    values: tuple[float, ...] = ()      # the grid's points as listed (in that order); () for a range

    @classmethod
    def listed(cls, key: str, values) -> "Axis":
        """A grid axis of the given values, in their order (checked: `list_problem`)."""
        values = tuple(float(v) for v in values)
        return cls(key, min(values), max(values), len(values), values)


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep runs: the case, its grid and random axes, how many random samples, the seed."""
    case: str
    grid: tuple[Axis, ...] = ()
    random: tuple[Axis, ...] = ()
    samples: int = 0
    seed: int = 0

    @property
    def keys(self) -> list[str]:
        return [a.key for a in (*self.grid, *self.random)]

    def as_json(self) -> str:
        """The spec as stored in a table's metadata; a range axis without `values` (as tables written
        before listed axes hold it, so that they still resume)."""
        spec = asdict(self)
        for axis in (*spec["grid"], *spec["random"]):
            if not axis["values"]:
                del axis["values"]
        return json.dumps(spec, sort_keys=True)


def parse_grid(text: str) -> Axis:
    """``KEY=START:STOP:NUM`` as an Axis, NUM >= 1 points from START to STOP (START <= STOP), or
    ``KEY=V1,V2,...``: those values, in that order (distinct)."""
    key, sep, rest = split_assignment(text)
    if sep and key.strip() and ":" not in rest:
        words = rest.split(",")
        values = [_number(text, "--grid", w.strip(), f"value {i}") for i, w in enumerate(words, 1)]
        problem = list_problem(values)
        if problem:
            raise SceneError(f"--grid {text!r}: {problem}", key=key.strip())
        return Axis.listed(key.strip(), values)
    key, numbers = _split(text, "--grid", "KEY=START:STOP:NUM or KEY=V1,V2,...", 3)
    start, stop = _number(text, "--grid", numbers[0], "START"), _number(text, "--grid", numbers[1], "STOP")
    try:
        num = int(numbers[2])
    except ValueError:
        raise SceneError(f"--grid {text!r}: NUM = {numbers[2]!r} is not a whole number", key=key) from None
    if num < 1:
        raise SceneError(f"--grid {text!r}: NUM = {num}; a range needs at least 1 point", key=key)
    if start > stop:
        raise SceneError(f"--grid {text!r}: START = {start:g} > STOP = {stop:g}; give the range low to high", key=key)
    return Axis(key, start, stop, num)


def parse_random(text: str) -> Axis:
    """``KEY=LOW:HIGH`` as a random Axis (LOW <= HIGH)."""
    key, numbers = _split(text, "--random", "KEY=LOW:HIGH", 2)
    low, high = _number(text, "--random", numbers[0], "LOW"), _number(text, "--random", numbers[1], "HIGH")
    if low > high:
        raise SceneError(f"--random {text!r}: LOW = {low:g} > HIGH = {high:g}; give the range low to high", key=key)
    return Axis(key, low, high)


def grid_values(axis: Axis) -> list[float]:
    """The grid points of an axis as a user would type them: START + i (STOP - START) / (NUM - 1)
    kept to 12 significant digits (0.075, not linspace's 0.07500000000000001), unless that would
    move a point by more than 1e-6 of a step (a range far narrower than its magnitude); a listed
    axis's values as listed."""
    if axis.values:
        return list(axis.values)
    if axis.num == 1:
        return [axis.low]
    step = (axis.high - axis.low) / (axis.num - 1)
    out = []
    for i in range(axis.num):
        exact = axis.high if i == axis.num - 1 else axis.low + i * step
        short = float(f"{exact:.{GRID_DIGITS}g}")
        out.append(short if abs(short - exact) <= 1e-6 * abs(step) else exact)
    return out


def count_variants(grid=(), random=(), samples: int = 0) -> int:
    """How many variants a request expands to (grid points x samples), without expanding it."""
    return math.prod(a.num for a in grid) * (int(samples) if random else 1)


def plan(scene: Scene, grid=(), random=(), *, samples: int = 0, seed: int = 0,
         max_variants: int = MAX_VARIANTS) -> tuple[SweepSpec, list[dict]]:
    """Check the axes against the scene and expand them into variants (dicts of overrides).

    Every key must be a parameter of the scene's task or a numeric setting of its solver, swept
    once. Whole-number settings (``count``) take grids of whole numbers only (``samples=2.5`` is
    refused, not run as 2) and rounded random draws. Variant ``i`` is the i-th grid
    point (last axis fastest) of the ``i // n_grid``-th random sample. The count is checked
    against `max_variants` before anything is expanded.
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise SceneError(f"--seed {seed!r}: expected a whole number from 0 to 2**63 - 1", key="seed")
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)):     # int(2.5) would run 2
        raise SceneError(f"--samples {samples!r}: expected a whole number (int) of random draws, not "
                         f"{type(samples).__name__}", key="samples")
    spec = SweepSpec(scene.id, tuple(grid), tuple(random), int(samples), int(seed))
    if not spec.grid and not spec.random:
        raise SceneError("a sweep needs at least one --grid KEY=START:STOP:NUM or --random KEY=LOW:HIGH")
    if spec.random and spec.samples < 1:
        raise SceneError(f"--samples {spec.samples}: --random needs --samples N with N >= 1", key="samples")
    if spec.samples and not spec.random:
        raise SceneError(f"--samples {spec.samples} given without any --random KEY=LOW:HIGH", key="samples")
    twice = sorted({k for k in spec.keys if spec.keys.count(k) > 1})
    if twice:
        raise SceneError(f"swept twice: {', '.join(twice)}; give each key one range", key=twice[0])
    _check_size(count_variants(spec.grid, spec.random, spec.samples), max_variants)
    kinds = {key: _kind(scene, key) for key in spec.keys}
    for a in spec.grid:
        _require_whole(a, kinds[a.key])
    grids = [[kinds[a.key](v) for v in grid_values(a)] for a in spec.grid]
    points = list(itertools.product(*grids))
    if not spec.random:
        return spec, [dict(zip(spec.keys, p)) for p in points]
    rng = np.random.default_rng(spec.seed)
    draws = rng.uniform([a.low for a in spec.random], [a.high for a in spec.random],
                        size=(spec.samples, len(spec.random)))
    return spec, [dict(zip(spec.keys, (*p, *(kinds[a.key](v) for a, v in zip(spec.random, row)))))
                  for row in draws for p in points]


def _require_whole(axis, kind):
    """A grid of a whole-number setting must hold whole numbers: rounding 2.5 would run 2 unsaid."""
    if kind is float:
        return
    broken = [v for v in grid_values(axis) if abs(v - round(v)) > 1e-9 * max(1.0, abs(v))]
    if broken:
        raise SceneError(f"--grid {axis.key}: {axis.key} is a whole-number solver setting, but the grid holds "
                         f"{broken[0]:g}; choose whole numbers (START, STOP and NUM whose points are whole)", key=axis.key)


def _check_size(count, limit):
    if isinstance(limit, bool) or not isinstance(limit, int) or limit < 1:
        raise SceneError(f"max_variants = {limit!r}: expected a whole number >= 1", key="max_variants")
    if count > limit:
        raise SceneError(f"{count:,} variants (about {_size(count * BYTES_PER_VARIANT)} of memory before any "
                         f"solver runs) exceed the limit of {limit:,}; narrow the ranges, or raise the limit "
                         f"(max_variants) if the machine and the time allow", key="max_variants")


def _size(n_bytes):
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.3g} {unit}"
    return f"{n_bytes / 1e3:.3g} kB"


_SCENES = BuildCache("mechopt.sweep.scenes", 8)      # a worker parses each scene text once


def run_chunk(source: SceneText, chunk: list[tuple[int, dict]]) -> list[dict]:
    """Solve the variants `(number, overrides)` of one scene on a worker; one row each.

    The scene comes as its file's text (`SceneText`) with the files it references, so a scene
    from any file runs on any worker; a text whose sha256 is not the one sent (damaged on the way)
    is refused. The loaded scene is kept per process by hash.
    """
    got = hashlib.sha256(source.text.encode("utf-8")).hexdigest()
    if got != source.sha256:
        raise SceneError(f"{source.path}: the scene file this worker received differs from the sweep's "
                         f"(sha256 {got[:12]} != {source.sha256[:12]}); it was changed on the way")
    with shipped(dict(source.files)):
        scene, _ = _SCENES.get(source.digest, lambda: loads(source.text, Path(source.path)))
    return _solve_rows(scene, chunk)


def _solve_rows(scene: Scene, chunk) -> list[dict]:
    """A refused setting (SceneError, ModelError) is an INVALID row, a crashed back end a FAILED row,
    anything else unexpected an ERROR row naming the exception: a sweep outlives its variants."""
    rows = []
    with warm.session():        # a variant may start from the one before it in the chunk (kit.warm)
        for number, overrides in chunk:
            rows.append(_solve_row(scene, number, overrides))
    return rows


def _solve_row(scene, number, overrides) -> dict:
    row = {**overrides, "variant": number, "build_s": None, "solve_s": None}
    try:
        result = registry.run(scene, overrides).result
    except SolverError as exc:
        return row | {"status": "FAILED", "message": str(exc)}
    except MechoptError as exc:
        return row | {"status": "INVALID", "message": str(exc)}
    except Exception as exc:       # noqa: BLE001 -- one bad variant must not end the study
        return row | {"status": "ERROR", "message": f"{type(exc).__name__}: {exc}"}
    values = {k: float(v) for k, v in result.values.items() if k not in row}
    return row | {"status": result.status.value, "message": result.message,
                  "warnings": "; ".join(result.warnings), "build_s": result.timing.build_s,
                  "solve_s": result.timing.solve_s} | values


def sweep(scene: Scene, grid=(), random=(), *, samples: int = 0, seed: int = 0, out: Path | None = None,
          scheduler: str | None = None, workers: int = 1, chunk: int = 100, progress: bool | None = None,
          connect_timeout_s: float = 5.0, on_chunk: Callable[[list[dict]], None] | None = None,
          max_variants: int = MAX_VARIANTS) -> pa.Table:
    """Run every variant of a sweep and return (and write, when `out` is given) its table.

    Parameters
    ----------
    scene : the scene swept (``registry.find(case_id)`` or ``scene.load(path)``: any file).
    grid, random : Axis sequences (``parse_grid``, ``parse_random``).
    samples, seed : random draws per grid point and the seed of the generator.
    out : Parquet file; finished chunks go to ``<out>.parts/`` as they arrive and are merged into
        ``out`` at the end. Variants already in ``out`` or its parts are skipped. One sweep at a
        time writes it (``<out>.lock``); a second is refused at once.
    scheduler : a Dask scheduler address (``tcp://host:8786``); None runs on this machine.
    workers : without a scheduler, 1 runs in this process; more spreads the chunks over as many
        local processes (spawned, each keeping its own solver builds).
    chunk : variants per task (>= 1); each task's worker re-solves its cached build.
    progress : draw a tqdm bar on stderr (rate and time remaining): None (the default) when stderr
        is a terminal, True always, False never (a bar redraws itself with carriage returns, which
        a log file or a pipe keeps as they are).
    connect_timeout_s : how long to try the scheduler before giving up [s].
    on_chunk : called with each chunk's rows as it arrives (after it is written).
    max_variants : a larger request is refused before anything is allocated.

    Returns
    -------
    pyarrow.Table, one row per variant in variant order.

    Raises
    ------
    SweepInterrupted : on Ctrl-C; the finished chunks stay in ``<out>.parts/``.

    Examples
    --------
    >>> scene = registry.find("loom/group1")
    >>> table = sweep(scene, [parse_grid("amplitude_limit_mm=0.08:0.14:4")], progress=False)
    """
    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
        raise SceneError(f"chunk = {chunk!r}: expected a whole number of variants >= 1", key="chunk")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise SceneError(f"workers = {workers!r}: expected a whole number of processes >= 1", key="workers")
    if scheduler and workers > 1:
        raise SceneError("give either --scheduler (the cluster's workers run it) or --workers, not both",
                         key="workers")
    if out is not None:
        _check_out(Path(out))
    workers = _local_workers(workers, scheduler)
    spec, variants = plan(scene, grid, random, samples=samples, seed=seed, max_variants=max_variants)
    source = SceneText.of(scene)
    meta = {"case": spec.case, "spec": json.loads(spec.as_json()), "scene_sha256": source.sha256}
    client = _connect(scheduler, connect_timeout_s) if scheduler else None   # before anything is written
    store = _Store(Path(out), meta) if out is not None else None
    rows: list[dict] = []           # kept in memory only when there is no file to hold them
    lost: list[str] = []            # why a Dask task failed for good
    try:
        if store:
            store.lock()
        done = store.done() if store else set()
        todo = [(i, v) for i, v in enumerate(variants) if i not in done]
        chunks = [todo[i:i + chunk] for i in range(0, len(todo), chunk)]
        bar = _bar(len(variants), len(done), progress)
        count = len(done)
        try:
            for got in (_on_dask(client, source, chunks, lost) if client
                        else _on_pool(min(workers, len(chunks)), source, chunks) if workers > 1
                        else (_solve_rows(scene, c) for c in chunks)):
                if store:
                    store.write_part(got)
                else:
                    rows.extend(got)
                count += len(got)
                bar.update(len(got))
                if on_chunk:
                    on_chunk(got)
        except KeyboardInterrupt:
            bar.close()
            kept = (f"kept in {store.parts}; re-run the same command to resume" if store
                    else "nothing was kept (no --out); give --out to make a sweep resumable")
            raise SweepInterrupted(f"sweep of {spec.case} interrupted: {count} of {len(variants)} variants "
                                   f"done, {kept}", done=count, total=len(variants)) from None
        bar.close()
        table = store.consolidate() if store else _table(sorted(rows, key=lambda r: r["variant"]), spec.keys, meta)
    finally:
        if client:
            client.close()
        if store:
            store.unlock()
    missing = len(variants) - table.num_rows
    if missing:
        raise SolverError(f"{missing} of {len(variants)} variants were not computed"
                          + (f" ({lost[0]})" if lost else "")
                          + ("; re-run with the same --out to compute only those" if store else ""))
    return table


def _check_out(out):
    """Refuse an `out` that names no file (a folder, '.', '') before any work."""
    if out.name in ("", ".", "..") or out.is_dir():
        raise SceneError(f"{out}: a folder; --out names the table's file, e.g. "
                         f"{out / 'sweep.parquet'}", key="out")


def _local_workers(workers, scheduler):
    """`workers` capped at this machine's cores (more processes than cores only slow each other
    down), said as a SweepWarning; a scheduler's cluster is not capped."""
    cores = os.cpu_count() or 1
    if scheduler or workers <= cores:
        return workers
    warnings.warn(f"workers = {workers}: this machine has {cores} cores, so {cores} processes are used "
                  "(give --scheduler to run on more machines)", SweepWarning, stacklevel=3)
    return cores


def read_table(path) -> tuple[pa.Table, dict]:
    """A sweep's table and its metadata (case, spec, scene hash); refuses a Parquet file of no sweep
    and a table with a variant stored twice."""
    meta = _read_meta(path)
    table = _read_parquet(path)
    wanted = {**{k: "a number" for k in _keys(meta)}, "variant": "int64", "status": "string", "message": "string"}
    wrong = [name for name, kind in wanted.items() if name not in table.column_names
             or (kind != "a number" and str(table.schema.field(name).type) != kind)
             or (kind == "a number" and not pa.types.is_integer(table.schema.field(name).type)
                 and not pa.types.is_floating(table.schema.field(name).type))]
    if wrong:
        raise SceneError(f"{path}: not a sweep's table: column {quote(wrong[0])} is missing or not "
                         f"{wanted[wrong[0]]}", key="sweep")
    check_unique(table, path)
    return table, meta


def check_unique(table: pa.Table, where) -> None:
    """Refuse a sweep table holding a variant more than once (`where` names it in the message)."""
    variants = table.column("variant").to_numpy()
    numbers, counts = np.unique(variants, return_counts=True)
    twice = numbers[counts > 1]
    if len(twice):
        shown = ", ".join(str(int(v)) for v in twice[:5]) + (", ..." if len(twice) > 5 else "")
        raise SceneError(f"{where}: {len(twice)} variants are stored more than once ({shown}); the table is "
                         f"not one sweep's: re-run the sweep with this --out to rebuild it", key="variant")


def _read_meta(path) -> dict:
    """The sweep metadata of a Parquet file, from its footer only."""
    path = Path(path)
    schema = _read_parquet(path, pq.read_schema)
    raw = (schema.metadata or {}).get(META_KEY)
    if raw is None:
        raise SceneError(f"{path}: a Parquet file but not a mechopt sweep (no {META_KEY.decode()} metadata); "
                         f"choose another --out")
    problem = None
    if len(raw) > MAX_META_BYTES:
        problem = f"{len(raw):,} bytes, more than a sweep's spec ever needs ({MAX_META_BYTES:,})"
    else:
        try:
            meta = json.loads(raw)
            problem = _meta_problem(meta)
        except (ValueError, RecursionError):
            problem = f"not JSON (starts {quote(raw[:40].decode('utf-8', 'replace'))})"
    if problem:
        raise SceneError(f"{path}: its {META_KEY.decode()} metadata is not a sweep's: {problem}; "
                         f"this file was not written by mechopt sweep (choose another --out)", key="out")
    return meta


def _read_parquet(path, read=pq.read_table, **how):
    """`read(file, **how)` of the Parquet file `path`, refused (SceneError) unless it is a regular file
    of at most MAX_TABLE_BYTES (a FIFO would block the sweep for ever, a device never end)."""
    try:
        with open_regular(path, max_bytes=MAX_TABLE_BYTES, what="a sweep's table") as f:
            return read(f, **how)
    except (OSError, pa.ArrowInvalid) as exc:
        raise SceneError(f"{path}: not a readable Parquet file ({exc})") from None
    except ValueError as exc:            # not a regular file, or too large
        raise SceneError(str(exc), key="out") from None


MAX_META_BYTES = 100_000
_AXIS_FIELDS = {"key": str, "low": (int, float), "high": (int, float), "num": int}   # and a listed grid's values


def _meta_problem(meta) -> str | None:
    """What is wrong with a sweep table's metadata (read from a file anyone may have written), or None."""
    if not isinstance(meta, dict) or set(meta) != {"case", "spec", "scene_sha256"}:
        return "expected an object with case, spec and scene_sha256"
    if not isinstance(meta["case"], str) or not re.fullmatch(r"[0-9a-f]{64}", str(meta["scene_sha256"])):
        return "case must be text and scene_sha256 64 hex digits"
    spec = meta["spec"]
    if not isinstance(spec, dict) or set(spec) != {"case", "grid", "random", "samples", "seed"}:
        return "spec must hold case, grid, random, samples and seed"
    if not all(isinstance(spec[k], int) and not isinstance(spec[k], bool) and spec[k] >= 0
               for k in ("samples", "seed")):
        return "spec.samples and spec.seed must be whole numbers >= 0"
    for name in ("grid", "random"):
        axes = spec[name]
        if not isinstance(axes, list) or not all(
                isinstance(a, dict) and set(a) - {"values"} == set(_AXIS_FIELDS)
                and all(isinstance(a[k], t) and not isinstance(a[k], bool) for k, t in _AXIS_FIELDS.items())
                for a in axes):
            return f"spec.{name} must be a list of axes {{key, low, high, num}}"
        if any("values" in a and (name == "random" or not isinstance(a["values"], list) or len(a["values"]) != a["num"]
                                  or list_problem(a["values"])) for a in axes):
            return f"spec.{name}: an axis's values must be a list of num distinct finite numbers (grid axes only)"
    return None


class _Store:
    """The --out file, its lock and its sidecar folder of per-chunk parts (each with its sha256)."""

    def __init__(self, path: Path, meta: dict):
        self.path, self.meta = path, meta
        self.parts = path.with_name(path.name + ".parts")
        self.lock_path = path.with_name(path.name + ".lock")
        self._lock = None

    def lock(self):
        """Take `<out>.lock` (one writer per file), drop damaged parts, refuse another sweep's files."""
        if self.path.is_dir():
            raise SceneError(f"{self.path}: a folder; --out names the table's file, e.g. {self.path / 'sweep.parquet'}",
                             key="out")
        try:
            make_folder(self.path.parent)
        except OSError as exc:
            raise SceneError(f"{self.path.parent}: cannot make the folder of --out ({exc.strerror}); nothing was "
                             "written: choose another --out", key="out") from None
        if self.parts.is_symlink() or (self.parts.exists() and not self.parts.is_dir()):
            raise SceneError(f"{self.parts}: not this sweep's folder of parts (a symbolic link or a file); it is "
                             f"not followed: remove it, or choose another --out", key="out")
        fd = self._take()
        self._lock = fd
        try:
            self._drop_damaged()
            for file in self._files():
                self._own(file)
        except BaseException:
            self.unlock()
            raise

    def _take(self):
        """A descriptor holding `<out>.lock` (its pid written in it), or SceneError: held by another
        sweep, or not a regular file of one name (a link is never followed or written through), or
        holding text no sweep writes. The temporaries a killed sweep recorded in it are removed."""
        try:
            fd = take_lock(self.lock_path)
        except ValueError as exc:
            raise SceneError(f"{exc}; nothing was written", key="out") from None
        except OSError as exc:
            raise SceneError(f"{self.lock_path}: cannot create the sweep's lock file ({exc.strerror}); "
                             "nothing was written: choose another --out", key="out") from None
        if fd is None:
            raise SceneError(f"{self.path} is being written by another sweep (pid {self._holder()}); "
                             f"wait for it or choose another --out", key="out")
        try:
            for name in self._recorded(fd):
                self._remove_stale(name)
            _lock_text(fd, f"{os.getpid()}\n")
        except BaseException:
            os.close(fd)
            raise
        return fd

    def _recorded(self, fd) -> list[str]:
        """The temporaries a sweep killed while writing recorded in the lock (see `_note_temporary`);
        SceneError for a lock holding anything else (a file of the user's: it is not truncated)."""
        os.lseek(fd, 0, os.SEEK_SET)
        text = os.read(fd, MAX_LOCK_BYTES + 1).decode("utf-8", "replace")
        lines = text.splitlines()
        if len(text) > MAX_LOCK_BYTES or (text and (not text.endswith("\n") or not re.fullmatch(r"[0-9]+", lines[0])
                                                     or not all(map(self._is_temporary, lines[1:])))):
            raise SceneError(f"{self.lock_path}: holds text no sweep writes (a sweep's lock holds its pid); it is "
                             "left as it is: remove it, or choose another --out", key="out")
        return lines[1:]

    def _is_temporary(self, name):
        """Whether `name` (relative to out's folder) is a temporary this sweep's writes would create:
        of `<out>` beside it, or of a part or its checksum in `<out>.parts`."""
        folder, _, base = name.rpartition("/")
        target = temporary_target(base)
        if folder == "":
            return target == self.path.name[:NAME_ROOM]
        return (folder == self.parts.name and target is not None
                and (_PART_NAME.fullmatch(target) or _PART_NAME.fullmatch(target.removesuffix(".sha256"))) is not None)

    def _remove_stale(self, name):
        """A temporary a killed sweep of this --out recorded: removed if it is still a regular file of one name."""
        stale = self.path.parent / name
        try:
            found = os.stat(stale, follow_symlinks=False)
        except OSError:
            return
        if stat.S_ISREG(found.st_mode) and found.st_nlink == 1:
            stale.unlink(missing_ok=True)

    def _note_temporary(self, tmp):
        """Record in the lock the temporary being written (None: none), so that a sweep killed while
        writing has its temporary removed by the next one, and nothing else."""
        in_flight = f"{tmp.relative_to(self.path.parent).as_posix()}\n" if tmp else ""
        _lock_text(self._lock, f"{os.getpid()}\n{in_flight}")

    def _write(self, path, data):
        """`data` into `path` atomically, its temporary recorded in the lock while it exists."""
        try:
            write_bytes_atomic(path, data, on_temporary=self._note_temporary)
        finally:
            self._note_temporary(None)

    def check_lock(self):
        """Re-check that `<out>.lock` is still the file this sweep holds (someone may delete it, and a
        second sweep then takes a new one): a deleted lock is taken again; one another sweep now holds
        stops this sweep, its finished parts kept, rather than have two writers."""
        if self._lock is None or holds(self._lock, self.lock_path):
            return
        old, self._lock = self._lock, None
        os.close(old)
        try:
            self._lock = self._take()
        except SceneError as exc:
            raise SceneError(f"{self.lock_path} was removed while this sweep ran, and {exc}; this sweep stops "
                             f"(its finished parts are kept in {self.parts})", key="out") from None

    def unlock(self):
        if self._lock is not None:
            fd, self._lock = self._lock, None
            try:
                if holds(fd, self.lock_path):
                    os.unlink(self.lock_path)    # while still held: the next sweep makes a fresh one
            except PermissionError:              # Windows removes no open file: closed first, then removed
                os.close(fd)
                self.lock_path.unlink(missing_ok=True)
                return
            os.close(fd)

    def _holder(self):
        try:
            first = read_regular(self.lock_path, max_bytes=MAX_LOCK_BYTES, what="a lock file",
                                 follow_links=False).split(b"\n", 1)[0]
        except (OSError, ValueError):
            return "unknown"
        return first.decode() if first.isdigit() else "unknown"

    def _own(self, path):
        theirs = _read_meta(path)
        if theirs != self.meta:
            raise SceneError(f"{path} holds another sweep ({_describe(theirs)}); this one is "
                             f"{_describe(self.meta)}; refusing to mix them: choose another --out "
                             f"or remove that file", key="out")

    def _drop_damaged(self):
        """A part whose bytes are not those written (or cannot be read) is named, removed and its
        variants computed again; so is a part whose checksum never got written (killed in between)."""
        for part in self._parts():
            if part.is_symlink() or not part.is_file():
                raise SceneError(f"{part}: not a file this sweep wrote (a folder or a link); it is left as it is: "
                                 f"remove it by hand and re-run", key="out")
            check = part.with_name(part.name + ".sha256")
            if check.is_symlink() or (check.exists() and not check.is_file()):
                raise SceneError(f"{check}: not a file this sweep wrote (a link, FIFO, device or folder); it is left "
                                 f"as it is: remove it by hand and re-run", key="out")
            try:
                want, _, count = read_regular(check, max_bytes=MAX_CHECK_BYTES, what="a part's checksum file",
                                              follow_links=False).decode().partition(" ")
                count = int(count)
            except (OSError, ValueError):
                why, want, count = "no checksum (the sweep stopped while writing it)", None, None
            if want is not None:
                try:
                    got = hashlib.sha256(read_regular(part, max_bytes=MAX_TABLE_BYTES, what="a sweep's part",
                                                      follow_links=False)).hexdigest()
                    why = None if got == want else "damaged (checksum mismatch)"
                except OSError as exc:
                    why = f"unreadable ({exc.strerror})"
                except ValueError as exc:
                    why = f"not a part ({exc})"
            if why:
                what = f"its {count} variants are" if count is not None else "its variants are"
                warnings.warn(f"{part}: {why}; {what} recomputed", SweepWarning, stacklevel=4)
                try:
                    part.unlink(missing_ok=True)     # a regular file of this sweep's naming (_parts)
                    check.unlink(missing_ok=True)
                except OSError as exc:
                    raise SceneError(f"{part}: cannot remove this damaged part ({exc.strerror}); remove it "
                                     f"by hand and re-run", key="out") from None

    def done(self) -> set[int]:
        tables = [_read_parquet(p, columns=["variant"]) for p in self._files()]
        return {int(v) for t in tables for v in t.column("variant").to_pylist()}

    def write_part(self, rows):
        self.check_lock()
        self.parts.mkdir(parents=True, exist_ok=True)
        first = min(r["variant"] for r in rows)
        path = self.parts / f"part-{first:09d}.parquet"
        sink = pa.BufferOutputStream()
        pq.write_table(_table(rows, _keys(self.meta), self.meta), sink)
        data = sink.getvalue().to_pybytes()
        self._write(path, data)      # a part is whole or absent, even if the sweep is killed mid-write
        self._write(path.with_name(path.name + ".sha256"), f"{hashlib.sha256(data).hexdigest()} {len(rows)}\n".encode())

    def consolidate(self) -> pa.Table:
        """Merge `out` and the parts into `out` (atomic); part rows already in `out` (a merge killed
        before the parts were removed) are dropped, so the merge can be run again at any point."""
        self.check_lock()
        tables, seen, merged = [], pa.array([], pa.int64()), self._files()
        for file in merged:
            table = _read_parquet(file)
            table = table.filter(pc.invert(pc.is_in(table.column("variant"), value_set=seen)))
            table = _unique_variants(table)
            seen = pa.concat_arrays([seen, table.column("variant").combine_chunks()])
            tables.append(table)
        table = (pa.concat_tables(tables, promote_options="default") if tables
                 else _table([], _keys(self.meta), self.meta))
        table = _ordered(table.sort_by("variant"), _keys(self.meta)).replace_schema_metadata(
            {META_KEY: json.dumps(self.meta, sort_keys=True).encode()})
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink)
        self._write(self.path, sink.getvalue().to_pybytes())
        self._remove_parts([p for p in merged if p != self.path])      # all of them are in the file now
        return table

    def _remove_parts(self, parts):
        """The parts merged, their checksums and then the folder if nothing else is in it."""
        for part in parts:
            part.unlink(missing_ok=True)
            part.with_name(part.name + ".sha256").unlink(missing_ok=True)
        try:
            self.parts.rmdir()
        except OSError:
            pass                 # not empty (a file not this sweep's) or never made: left as it is

    def _parts(self):
        """This sweep's parts: the entries named part-<9 digits>.parquet (nothing else in the folder
        is read or removed; a symbolic link to the folder is refused by `lock`, so is a part that is
        not a regular file)."""
        if not self.parts.is_dir() or self.parts.is_symlink():
            return []
        return sorted(p for p in self.parts.glob("part-*.parquet") if _PART_NAME.fullmatch(p.name))

    def _files(self):
        return ([self.path] if self.path.exists() else []) + self._parts()


_PART_NAME = re.compile(r"part-\d{9}\.parquet")


def _lock_text(fd, text):
    """The whole content of the lock file held by `fd` (checked to be the sweep's own: `_Store._take`)."""
    os.ftruncate(fd, 0)
    os.lseek(fd, 0, os.SEEK_SET)
    os.write(fd, text.encode())


def _unique_variants(table):
    """The first row of each variant (a table written twice by an interrupted merge holds two)."""
    variants = table.column("variant").to_numpy()
    _, first = np.unique(variants, return_index=True)
    return table if len(first) == len(variants) else table.take(np.sort(first))


def _on_dask(client, source, chunks, lost):
    """Chunks as Dask tasks; their rows as they finish. A lost worker's tasks are rescheduled by
    Dask; a task that still fails (KilledWorker, a scene text damaged on the way) leaves its
    variants out, its reason appended to `lost`, and the sweep says so at the end."""
    from distributed import as_completed
    futures = [client.submit(run_chunk, source, c, pure=False) for c in chunks]
    for future in as_completed(futures):
        if future.status == "finished":
            yield future.result()
        else:
            lost.append(f"{type(future.exception()).__name__}: {future.exception()}")
        future.release()


def _on_pool(workers, source, chunks):
    """Chunks on local processes, rows as they finish. Spawned, not forked: a child inherits no
    half-initialised solver state from this process. On Ctrl-C the chunks not started are dropped."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        for future in as_completed([pool.submit(run_chunk, source, c) for c in chunks]):
            yield future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _connect(address, timeout_s):
    """A Dask client for `address`, or SceneError within about `timeout_s`: distributed's own
    timeout covers the TCP connection but not its handshake, so a server that accepts and stays
    silent (not a Dask scheduler) would hang it; such a server is found by a probe first, and
    the client is made on a thread given a wall-clock limit."""
    import threading

    from distributed import Client
    hint = f"start one with `dask scheduler` and workers with `dask worker {address}`"
    problem = _silent_server(address, timeout_s)
    if problem:
        raise SceneError(f"--scheduler {address}: {problem}; {hint}", key="scheduler")
    made = {}

    def connect():
        try:
            made["client"] = Client(address, timeout=f"{timeout_s}s")
        except Exception as exc:         # noqa: BLE001 -- reported below, on the caller's thread
            made["error"] = exc
    worker = threading.Thread(target=connect, daemon=True)
    worker.start()
    worker.join(timeout_s + 5.0)
    if "client" in made:
        return made["client"]
    exc = made.get("error")
    why = f"{type(exc).__name__}: {exc}" if exc else f"no answer within {timeout_s + 5:g} s"
    raise SceneError(f"--scheduler {address}: cannot reach a Dask scheduler within {timeout_s:g} s ({why}); {hint}",
                     key="scheduler")


def _silent_server(address, timeout_s) -> str | None:
    """Why a tcp:// address is not a Dask scheduler (a Dask server speaks first: its handshake),
    or None when it answers, cannot be probed (another protocol) or refuses (said by the client)."""
    import socket
    scheme, _, where = address.rpartition("://")
    host, _, port = where.rpartition(":")
    if scheme not in ("", "tcp") or not port.isdigit():
        return None
    try:
        with socket.create_connection((host.strip("[]") or "127.0.0.1", int(port)), timeout=timeout_s) as conn:
            conn.settimeout(timeout_s)
            return None if conn.recv(1) else "the server closed the connection at once: not a Dask scheduler"
    except TimeoutError:
        return f"a server answers there but said nothing within {timeout_s:g} s: not a Dask scheduler"
    except OSError:
        return None


def _bar(total, done, enabled):
    from tqdm import tqdm
    if enabled is None:
        enabled = sys.stderr.isatty()
    return tqdm(total=total, initial=done, unit="variant", file=sys.stderr, disable=not enabled,
                smoothing=0.1, dynamic_ncols=True)


def _table(rows, keys, meta) -> pa.Table:
    columns = list(keys) + list(FIXED_COLUMNS)
    for row in rows:
        columns += [k for k in row if k not in columns]
    types = {k: pa.float64() for k in columns} | {"variant": pa.int64(), "status": pa.string(),
                                                 "message": pa.string(), "warnings": pa.string()}
    for key in keys:            # whole-number settings stay whole
        if rows and all(isinstance(r.get(key), int) for r in rows):
            types[key] = pa.int64()
    schema = pa.schema([(k, types[k]) for k in columns],
                       metadata={META_KEY: json.dumps(meta, sort_keys=True).encode()})
    return pa.Table.from_pylist(rows, schema=schema)


def _ordered(table, keys):
    first = [c for c in (*keys, *FIXED_COLUMNS) if c in table.column_names]
    return table.select(first + [c for c in table.column_names if c not in first])


def _keys(meta):
    spec = meta["spec"]
    return [a["key"] for a in (*spec["grid"], *spec["random"])]


def _kind(scene, key):
    """How a swept key's numbers are handed to the scene: float for parameters, int or float per setting."""
    params, settings = _sweepable(scene)
    if key in params:
        return float
    if key in settings:
        return (lambda v: int(round(v))) if isinstance(settings[key], int) else float
    if path_head(key) in scene.spec.structure and key != path_head(key):
        scene.build({key: 1.0})         # a number in a structure table: a path that leads nowhere is refused
        return float
    near = difflib.get_close_matches(key, [*params, *settings], n=3)
    raise SceneError(f"{scene.id}: {key!r} cannot be swept" + (f" (did you mean {', '.join(near)}?)" if near else "")
                     + f"; numeric parameters: {', '.join(params)}; numeric solver settings: "
                     + (", ".join(settings) or "none")
                     + ("; numbers in structure tables by path, e.g. 'operations[from=3,to=7].min_deg'"
                        if scene.spec.structure else ""), key=key)


def _sweepable(scene):
    """Numeric task fields (not structure: networks, lists) and numeric solver settings with their defaults."""
    given = scene.params()
    params = [k for k, f in task_fields(scene.task_class).items()
              if k in given or (isinstance(f.default, (int, float)) and not isinstance(f.default, bool))]
    settings = {k: o.default for k, o in solver_options(scene.solver).items()
                if get_origin(o.annotation) is not Literal and not isinstance(o.default, bool)
                and isinstance(o.default, (int, float))}
    return params, settings


def scene_hash(scene) -> str:
    """sha256 of a scene's file: a sweep table records it, so a table of another version shows."""
    return SceneText.of(scene).sha256


def describe_axes(spec: dict) -> list[str]:
    """A stored sweep spec's axes as they were given: ``KEY=LOW:HIGH:NUM``, ``KEY=V1,V2,...`` (listed),
    ``KEY=LOW:HIGH (random)``."""
    return ([f"{a['key']}=" + (",".join(f"{v:g}" for v in a["values"]) if a.get("values")
                               else f"{a['low']:g}:{a['high']:g}:{a['num']}") for a in spec["grid"]]
            + [f"{a['key']}={a['low']:g}:{a['high']:g} (random)" for a in spec["random"]])


def _describe(meta):
    spec = meta["spec"]
    extra = f", {spec['samples']} samples, seed {spec['seed']}" if spec["random"] else ""
    return (f"case {meta['case']}, {' '.join(describe_axes(spec))}{extra}, "
            f"scene file sha256 {meta['scene_sha256'][:12]}")


def _split(text, flag, form, count):
    key, sep, rest = split_assignment(text)
    numbers = rest.split(":")
    if not sep or not key.strip() or len(numbers) != count:
        raise SceneError(f"{flag} {text!r}: expected {form}", key=key.strip() or None)
    return key.strip(), numbers


def axis_value_problem(value: float) -> str:
    """What is wrong with an axis end ('' when nothing): the one rule of the CLI and the API."""
    if not math.isfinite(value):
        return "is not a finite number"
    if abs(value) > AXIS_LIMIT:
        return f"is beyond ±{AXIS_LIMIT:g}; no parameter or setting of a mechanism is that large"
    return ""


def list_problem(values) -> str:
    """What is wrong with a listed grid axis ('' when nothing): numbers, each finite and within
    AXIS_LIMIT, at least one, none twice (a variant solved twice would hold one point twice)."""
    if len(values) == 0:
        return "an empty list; give at least one value"
    for value in values:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            return f"{value!r} is not a number"
        if axis_value_problem(float(value)):
            return f"{value!r} {axis_value_problem(float(value))}"
    twice = sorted(v for v, n in Counter(float(v) for v in values).items() if n > 1)
    if twice:
        return f"{twice[0]:g} is listed twice; give each value once"
    return ""


def _number(text, flag, word, name):
    try:
        value = float(word)
    except ValueError:
        value = math.nan
    problem = axis_value_problem(value)
    if problem:
        shown = repr(word) if problem.startswith("is not") else word
        raise SceneError(f"{flag} {text!r}: {name} = {shown} {problem}", key=split_assignment(text)[0])
    return value


def study(scene, grid: dict | None = None, random: dict | None = None, *, samples: int = 0, seed: int = 0,
          out=None, progress: bool = False, **options):
    """Every variant of a scene (a Scene, a registry id or a scene file's path) as one pyarrow Table.

    grid : {key: (start, stop, num)}, num evenly spaced values from start to stop, or {key: [v1, v2, ...]},
        those values (a list; distinct); all combinations of the axes.
    random : {key: (low, high)}, `samples` uniform draws (seeded) combined with every grid point.
    out : a Parquet file to write (and to resume from); further options as `mechopt.sweep.sweep`
    (workers, scheduler, chunk, max_variants). A variant that fails is a row with its status.
    """
    axes = [_python_axis("grid", key, bounds, 3) for key, bounds in (grid or {}).items()]
    draws = [_python_axis("random", key, bounds, 2) for key, bounds in (random or {}).items()]
    return sweep(registry.find(scene), axes, draws, samples=samples, seed=seed, out=out, progress=progress, **options)


def _python_axis(kind, key, bounds, size):
    """An axis of the Python call: a tuple (start, stop, num) or (low, high); a grid's list of values."""
    if size == 3 and isinstance(bounds, (list, np.ndarray)):
        problem = list_problem(bounds)
        if problem:
            raise SceneError(f"{kind}[{key!r}] = {bounds!r}: {problem}", key=key)
        return Axis.listed(key, bounds)
    form = "(start, stop, num) or a list of values" if size == 3 else "(low, high)"
    if not isinstance(bounds, (tuple, list)) or len(bounds) != size:
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: expected {form}", key=key)
    low, high, *num = bounds
    if any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in (low, high)):
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: expected numbers {form}", key=key)
    for end in (low, high):
        if axis_value_problem(float(end)):
            raise SceneError(f"{kind}[{key!r}] = {bounds!r}: {end!r} {axis_value_problem(float(end))}", key=key)
    if low > high:
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: {low:g} > {high:g}; give the range low to high", key=key)
    if num and (isinstance(num[0], bool) or not isinstance(num[0], int) or num[0] < 1):
        raise SceneError(f"{kind}[{key!r}] = {bounds!r}: num = {num[0]!r}; expected a whole number >= 1", key=key)
    return Axis(key, float(low), float(high), *num)


class _CallableStudies(types.ModuleType):
    """`mechopt.sweep(...)` runs a study (`study`) while `mechopt.sweep.<name>` stays this module."""

    def __call__(self, *args, **kwargs):
        return study(*args, **kwargs)

    __call__.__doc__ = study.__doc__
    # inspect.signature(mechopt.sweep) reads this (less `self`): study's own parameters
    __call__.__signature__ = inspect.signature(study).replace(parameters=[
        inspect.Parameter("self", inspect.Parameter.POSITIONAL_ONLY), *inspect.signature(study).parameters.values()])


sys.modules[__name__].__class__ = _CallableStudies
# help(mechopt.sweep) shows a module's page: it opens with the call and its parameters
__doc__ = f"mechopt.sweep{inspect.signature(study)}\n{inspect.getdoc(study)}\n\n{__doc__}"
