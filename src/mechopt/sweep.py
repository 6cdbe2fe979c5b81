"""What-if studies at scale: run every variant of a scene and keep one table of the answers.

A sweep is a scene plus ranges of its parameters or solver settings: ``--grid KEY=START:STOP:NUM``
(evenly spaced, all combinations) and ``--random KEY=LOW:HIGH --samples N`` (uniform, seeded; each
sample is combined with every grid point). Variants are numbered in a fixed order, so a sweep's
spec names the same variants every time it is expanded.

Variants run in chunks: in this process by default, or on a Dask distributed cluster when a
scheduler address is given. A worker finds the scene once and its solver keeps its build (the
CasADi NLP, the cvxpy problem with Parameters) per process, so a chunk is re-solves, not rebuilds.
A variant that fails (infeasible, solver error, a setting the model refuses) is a row with its
status and message; the sweep goes on. Each finished chunk is written at once as one Parquet part
in the folder ``<out>.parts/``; the parts are consolidated into ``<out>`` at the end, so a stopped
sweep loses at most the chunks in flight and a re-run with the same ``--out`` skips what is done.
The file carries its case, its sweep spec and its scene file's hash in the Parquet metadata, and
a file of another sweep is refused rather than mixed.

Row columns: the swept keys, ``variant`` (its number), ``status`` (a Result status, or INVALID for
a setting the scene or model refuses, ERROR for an unexpected exception), ``message``, ``build_s``,
``solve_s``, then every ``values`` entry of the result (null where a variant did not produce it).
"""
import difflib
import hashlib
import itertools
import json
import math
import shutil
import sys
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal, get_origin

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from mechopt import registry
from mechopt.models.errors import MechoptError, SceneError, SolverError
from mechopt.scene import Scene, solver_options, task_fields

__all__ = ["Axis", "SweepSpec", "parse_grid", "parse_random", "plan", "sweep", "run_chunk", "read_table",
           "scene_hash", "describe_axes"]

META_KEY = b"mechopt.sweep"
FIXED_COLUMNS = ("variant", "status", "message", "build_s", "solve_s")


@dataclass(frozen=True)
class Axis:
    """One swept key: `num` evenly spaced values from `low` to `high` (grid), or uniform draws (random)."""
    key: str
    low: float
    high: float
    num: int = 0            # grid points; 0 for a random axis


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
        return json.dumps(asdict(self), sort_keys=True)


def parse_grid(text: str) -> Axis:
    """``KEY=START:STOP:NUM`` as an Axis; NUM >= 1 points from START to STOP (START <= STOP)."""
    key, numbers = _split(text, "--grid", "KEY=START:STOP:NUM", 3)
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


def plan(scene: Scene, grid=(), random=(), *, samples: int = 0, seed: int = 0) -> tuple[SweepSpec, list[dict]]:
    """Check the axes against the scene and expand them into variants (dicts of overrides).

    Every key must be a parameter of the scene's task or a numeric setting of its solver, swept
    once. Whole-number settings (``count``) take rounded values. Variant ``i`` is the i-th grid
    point (last axis fastest) of the ``i // n_grid``-th random sample.
    """
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
    kinds = {key: _kind(scene, key) for key in spec.keys}
    grids = [[kinds[a.key](v) for v in np.linspace(a.low, a.high, a.num)] for a in spec.grid]
    points = list(itertools.product(*grids))
    if not spec.random:
        return spec, [dict(zip(spec.keys, p)) for p in points]
    rng = np.random.default_rng(spec.seed)
    draws = rng.uniform([a.low for a in spec.random], [a.high for a in spec.random],
                        size=(spec.samples, len(spec.random)))
    return spec, [dict(zip(spec.keys, (*p, *(kinds[a.key](v) for a, v in zip(spec.random, row)))))
                  for row in draws for p in points]


def run_chunk(case_id: str, chunk: list[tuple[int, dict]], scene_sha256: str | None = None) -> list[dict]:
    """Solve the variants `(number, overrides)` of one scene in this process; one row each.

    A refused setting (SceneError, ModelError) is an INVALID row, a crashed back end a FAILED row,
    anything else unexpected an ERROR row naming the exception: a sweep outlives its variants.
    With `scene_sha256`, a worker whose scene file differs from the client's refuses the chunk
    (a cluster's workers read their own installation's cases/).
    """
    scene = registry.find(case_id)
    if scene_sha256 is not None and scene_hash(scene) != scene_sha256:
        raise SceneError(f"{scene.path}: this worker's scene file differs from the sweep's (sha256 "
                         f"{scene_hash(scene)[:12]} != {scene_sha256[:12]}); install the same mechopt on every worker")
    rows = []
    for number, overrides in chunk:
        row = {**overrides, "variant": number, "build_s": None, "solve_s": None}
        try:
            result = registry.run(scene, overrides).result
        except SolverError as exc:
            rows.append(row | {"status": "FAILED", "message": str(exc)})
            continue
        except MechoptError as exc:
            rows.append(row | {"status": "INVALID", "message": str(exc)})
            continue
        except Exception as exc:       # noqa: BLE001 -- one bad variant must not end the study
            rows.append(row | {"status": "ERROR", "message": f"{type(exc).__name__}: {exc}"})
            continue
        values = {k: float(v) for k, v in result.values.items() if k not in row}
        rows.append(row | {"status": result.status.value, "message": result.message,
                           "build_s": result.timing.build_s, "solve_s": result.timing.solve_s} | values)
    return rows


def sweep(scene: Scene, grid=(), random=(), *, samples: int = 0, seed: int = 0, out: Path | None = None,
          scheduler: str | None = None, workers: int = 1, chunk: int = 100, progress: bool = True,
          connect_timeout_s: float = 5.0, on_chunk: Callable[[list[dict]], None] | None = None) -> pa.Table:
    """Run every variant of a sweep and return (and write, when `out` is given) its table.

    Parameters
    ----------
    scene : the scene swept (``registry.find(case_id)``).
    grid, random : Axis sequences (``parse_grid``, ``parse_random``).
    samples, seed : random draws per grid point and the seed of the generator.
    out : Parquet file; finished chunks go to ``<out>.parts/`` as they arrive and are merged into
        ``out`` at the end. Variants already in ``out`` or its parts are skipped.
    scheduler : a Dask scheduler address (``tcp://host:8786``); None runs on this machine.
    workers : without a scheduler, 1 runs in this process; more spreads the chunks over as many
        local processes (spawned, each keeping its own solver builds).
    chunk : variants per task (>= 1); each task's worker re-solves its cached build.
    progress : draw a tqdm bar on stderr (rate and time remaining).
    connect_timeout_s : how long to try the scheduler before giving up [s].
    on_chunk : called with each chunk's rows as it arrives (after it is written).

    Returns
    -------
    pyarrow.Table, one row per variant in variant order.

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
    spec, variants = plan(scene, grid, random, samples=samples, seed=seed)
    meta = {"case": spec.case, "spec": json.loads(spec.as_json()), "scene_sha256": scene_hash(scene)}
    store = _Store(Path(out), meta) if out is not None else None
    done = store.done() if store else set()
    todo = [(i, v) for i, v in enumerate(variants) if i not in done]
    chunks = [todo[i:i + chunk] for i in range(0, len(todo), chunk)]
    client = _connect(scheduler, connect_timeout_s) if scheduler else None   # before anything is written
    rows: list[dict] = []           # kept in memory only when there is no file to hold them
    lost: list[str] = []            # why a Dask task failed for good
    try:
        if store:
            store.open()
        bar = _bar(len(variants), len(done), progress)
        for got in (_on_dask(client, spec.case, chunks, meta["scene_sha256"], lost) if client
                    else _on_pool(workers, spec.case, chunks) if workers > 1
                    else (run_chunk(spec.case, c) for c in chunks)):
            if store:
                store.write_part(got)
            else:
                rows.extend(got)
            bar.update(len(got))
            if on_chunk:
                on_chunk(got)
        bar.close()
    finally:
        if client:
            client.close()
    table = store.consolidate() if store else _table(sorted(rows, key=lambda r: r["variant"]), spec.keys, meta)
    missing = len(variants) - table.num_rows
    if missing:
        raise SolverError(f"{missing} of {len(variants)} variants were not computed"
                          + (f" ({lost[0]})" if lost else "")
                          + ("; re-run with the same --out to compute only those" if store else ""))
    return table


def read_table(path) -> tuple[pa.Table, dict]:
    """A sweep's table and its metadata (case, spec, scene hash); refuses a Parquet file of no sweep."""
    meta = _read_meta(path)
    return pq.read_table(path), meta


def _read_meta(path) -> dict:
    """The sweep metadata of a Parquet file, from its footer only."""
    path = Path(path)
    try:
        schema = pq.read_schema(path)
    except (OSError, pa.ArrowInvalid) as exc:
        raise SceneError(f"{path}: not a readable Parquet file ({exc})") from None
    raw = (schema.metadata or {}).get(META_KEY)
    if raw is None:
        raise SceneError(f"{path}: a Parquet file but not a mechopt sweep (no {META_KEY.decode()} metadata); "
                         f"choose another --out")
    return json.loads(raw)


class _Store:
    """The --out file and its sidecar folder of per-chunk parts."""

    def __init__(self, path: Path, meta: dict):
        self.path, self.meta = path, meta
        self.parts = path.with_name(path.name + ".parts")
        for file in self._files():
            self._own(file)

    def _own(self, path):
        theirs = _read_meta(path)
        if theirs != self.meta:
            raise SceneError(f"{path} holds another sweep ({_describe(theirs)}); this one is "
                             f"{_describe(self.meta)}; refusing to mix them: choose another --out "
                             f"or remove that file", key="out")

    def done(self) -> set[int]:
        tables = [pq.read_table(p, columns=["variant"]) for p in self._files()]
        return {int(v) for t in tables for v in t.column("variant").to_pylist()}

    def open(self):
        self.parts.mkdir(parents=True, exist_ok=True)

    def write_part(self, rows):
        first = min(r["variant"] for r in rows)
        path = self.parts / f"part-{first:09d}.parquet"
        tmp = path.with_suffix(".tmp")
        pq.write_table(_table(rows, _keys(self.meta), self.meta), tmp)
        tmp.replace(path)          # a part is whole or absent, even if the sweep is killed mid-write

    def consolidate(self) -> pa.Table:
        tables = [pq.read_table(p) for p in self._files()]
        table = (pa.concat_tables(tables, promote_options="default") if tables
                 else _table([], _keys(self.meta), self.meta))
        table = _ordered(table.sort_by("variant"), _keys(self.meta)).replace_schema_metadata(
            {META_KEY: json.dumps(self.meta, sort_keys=True).encode()})
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(self.path.name + ".tmp")
        pq.write_table(table, tmp)
        tmp.replace(self.path)
        shutil.rmtree(self.parts, ignore_errors=True)     # all of it is in the file now
        return table

    def _files(self):
        parts = sorted(self.parts.glob("*.parquet")) if self.parts.is_dir() else []
        return ([self.path] if self.path.exists() else []) + parts


def _on_dask(client, case_id, chunks, scene_sha256, lost):
    """Chunks as Dask tasks; their rows as they finish. A lost worker's tasks are rescheduled by
    Dask; a task that still fails (KilledWorker, a worker's different scene) leaves its variants
    out, its reason appended to `lost`, and the sweep says so at the end."""
    from distributed import as_completed
    futures = [client.submit(run_chunk, case_id, c, scene_sha256, pure=False) for c in chunks]
    for future in as_completed(futures):
        if future.status == "finished":
            yield future.result()
        else:
            lost.append(f"{type(future.exception()).__name__}: {future.exception()}")
        future.release()


def _on_pool(workers, case_id, chunks):
    """Chunks on local processes, rows as they finish. Spawned, not forked: a child inherits no
    half-initialised solver state from this process."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        for future in as_completed([pool.submit(run_chunk, case_id, c) for c in chunks]):
            yield future.result()


def _connect(address, timeout_s):
    from distributed import Client
    try:
        return Client(address, timeout=f"{timeout_s}s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise SceneError(f"--scheduler {address}: cannot reach a Dask scheduler within {timeout_s:g} s "
                         f"({type(exc).__name__}: {exc}); start one with `dask scheduler` and workers "
                         f"with `dask worker {address}`", key="scheduler") from None


def _bar(total, done, enabled):
    from tqdm import tqdm
    return tqdm(total=total, initial=done, unit="variant", file=sys.stderr, disable=not enabled,
                smoothing=0.1, dynamic_ncols=True)


def _table(rows, keys, meta) -> pa.Table:
    columns = list(keys) + list(FIXED_COLUMNS)
    for row in rows:
        columns += [k for k in row if k not in columns]
    types = {k: pa.float64() for k in columns} | {"variant": pa.int64(), "status": pa.string(),
                                                 "message": pa.string()}
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
    near = difflib.get_close_matches(key, [*params, *settings], n=3)
    raise SceneError(f"{scene.id}: {key!r} cannot be swept" + (f" (did you mean {', '.join(near)}?)" if near else "")
                     + f"; numeric parameters: {', '.join(params)}; numeric solver settings: "
                     + (", ".join(settings) or "none"), key=key)


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
    return hashlib.sha256(Path(scene.path).read_bytes()).hexdigest()


def describe_axes(spec: dict) -> list[str]:
    """A stored sweep spec's axes as they were given: ``KEY=LOW:HIGH:NUM``, ``KEY=LOW:HIGH (random)``."""
    return ([f"{a['key']}={a['low']:g}:{a['high']:g}:{a['num']}" for a in spec["grid"]]
            + [f"{a['key']}={a['low']:g}:{a['high']:g} (random)" for a in spec["random"]])


def _describe(meta):
    spec = meta["spec"]
    extra = f", {spec['samples']} samples, seed {spec['seed']}" if spec["random"] else ""
    return (f"case {meta['case']}, {' '.join(describe_axes(spec))}{extra}, "
            f"scene file sha256 {meta['scene_sha256'][:12]}")


def _split(text, flag, form, count):
    key, sep, rest = text.partition("=")
    numbers = rest.split(":")
    if not sep or not key.strip() or len(numbers) != count:
        raise SceneError(f"{flag} {text!r}: expected {form}", key=key.strip() or None)
    return key.strip(), numbers


def _number(text, flag, word, name):
    try:
        value = float(word)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise SceneError(f"{flag} {text!r}: {name} = {word!r} is not a finite number", key=text.partition("=")[0])
    return value
