"""Scene files: load, validate, build the model's task, apply `--set` overrides.

A scene names a task (`models/<module>.<Class>`), the effects it switches on, parameters with
units in their names, a solver (`solvers/<module>.<function>`) with its settings, and what a
source says should come out. Nothing from a scene runs before all of that validated.
"""
import dataclasses
import importlib
import inspect
import math
import os
import re
import tomllib
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from types import MappingProxyType
from typing import Annotated, Any, Literal, get_args, get_origin

from annotated_types import DocInfo
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from mechopt.files import read_regular, real_path
from mechopt.kit.cache import memoised
from mechopt.kit.errors import MechoptError, ModelError, SceneError, SettingError, quote
from mechopt.kit.result import Status
from mechopt.kit.settings import declared_range, describe_range, field_problem, range_fault, setting_problem
from mechopt.models.provenance import provenance_problem
from mechopt.tables import Columns, check_header, number, read_columns, read_records, read_rows
from mechopt.units import unit_of

Number = int | float
STATUS_WORDS = tuple(s.value for s in Status)
MAX_SCENE_BYTES = 1_000_000      # a scene is a page of TOML; its tables of points come from CSV files
MAX_CHAIN = 32                   # scenes a chain of base / scene references reads (a variant of a variant ...)
MAX_LIST_ITEMS = 100             # a list typed into a scene or a --set (speeds, operations); longer: a CSV
MAX_ID_CHARS = 100               # an id names files (<id>.dxf, <id>_<figure>.png): far below a name's 255 bytes
_ID_FORM = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*(/[A-Za-z0-9][A-Za-z0-9._-]*)*")


def id_problem(text: str) -> str | None:
    """Why `text` cannot be a scene's id (which names its output files), or None."""
    if len(text) > MAX_ID_CHARS:
        return f"{len(text)} characters; an id has at most {MAX_ID_CHARS}"
    if not _ID_FORM.fullmatch(text):
        return ("expected names separated by '/', each of letters, digits, '.', '_' and '-' starting with a "
                "letter or digit (e.g. 'my/press-2'); an id names the run's files")
    return None


class Param(BaseModel):
    """A parameter with its provenance; a bare number in the file means `given` by the source."""
    model_config = ConfigDict(extra="forbid")
    value: Number | str | bool
    mark: Literal["given", "assumed", "calibrated"]
    why: str = ""          # required for assumed and calibrated: the reasoning, or the figure fitted
    where: str = ""        # for given: where in the source
    on: str = ""           # for calibrated: the value fitted to (a check of it is no reproduction)

    @model_validator(mode="before")
    @classmethod
    def _bare_number_is_given(cls, data):
        return data if isinstance(data, dict) else {"value": data, "mark": "given"}

    @model_validator(mode="after")
    def _explained(self):
        if isinstance(self.value, float) and not math.isfinite(self.value):
            raise ValueError(f"value = {self.value}: expected a finite number")
        problem = provenance_problem(self.mark, self.why, self.on)
        if problem:
            raise ValueError(f"a parameter {problem}" if problem.startswith("marked") else problem)
        return self


class Expectation(BaseModel):
    """What should come out: `value` within `abs`/`rel`, or a bound `max`/`min`, or a status word."""
    model_config = ConfigDict(extra="forbid")
    value: Number | str | None = None
    abs: float | None = Field(default=None, gt=0)
    rel: float | None = Field(default=None, gt=0)
    max: Number | None = None
    min: Number | None = None
    # follows: a row that restates what the status already certifies (it cannot fail while SOLVED)
    kind: Literal["published", "experimental", "derived", "follows"]
    where: str
    follows: str = ""      # why agreement is by construction (it follows from a calibration): not a reproduction
    # A declared miss, as pytest's xfail: "not_reproduced" (computed, outside the tolerance: shown with its gap,
    # and flagged when it starts to pass) or "not_reproducible" (the source lacks what a computation needs).
    verdict: Literal["not_reproduced", "not_reproducible"] | None = None
    reason: str = ""       # why the figure is missed: required with a declared verdict, and only there
    # readings taken with the published figure in view: a reproduction that needs them says so
    readings_after_figure: list[str] = []
    of: str = ""           # the result's value this row checks, when not the row's own name (a second figure of it)
    # a figure met under a reading that excludes the one the scene named here takes (chosen before the
    # figure): its match is reported, not counted as a reproduction
    alternative_to: str = ""

    @model_validator(mode="after")
    def _one_form(self):
        if bool(self.verdict) != bool(self.reason.strip()):
            raise ValueError("'reason' goes with a declared verdict (not_reproduced, not_reproducible), and only there")
        if (self.verdict or self.alternative_to) and self.kind in ("derived", "follows"):
            raise ValueError(f"{'verdict' if self.verdict else 'alternative_to'} is for a figure of the source "
                             f"(kind published or experimental), not a {self.kind} check")
        if self.verdict and self.alternative_to:
            raise ValueError("a declared miss (verdict) has no alternative reading (alternative_to): give one")
        if self.verdict == "not_reproducible":
            if not isinstance(self.value, (int, float)) or isinstance(self.value, bool):
                raise ValueError("a not_reproducible figure states the source's number as 'value'")
            return self
        if isinstance(self.value, str):
            if self.value not in STATUS_WORDS:
                raise ValueError(f"status {self.value!r} is not a status word; allowed: {', '.join(STATUS_WORDS)}")
            return self
        for name in ("value", "max", "min"):
            if getattr(self, name) is not None and not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} = {getattr(self, name)}: expected a finite number")
        if self.value is not None and self.abs is None and self.rel is None:
            raise ValueError("a numeric 'value' needs a tolerance 'abs' or 'rel' (> 0)")
        if self.value is None and self.max is None and self.min is None:
            raise ValueError("give 'value' with 'abs' or 'rel', or a bound 'max' / 'min'")
        if self.max is not None and self.min is not None and self.min > self.max:
            raise ValueError(f"bounds reversed: min={self.min} > max={self.max}")
        return self

    def check(self, got) -> bool:
        if self.verdict == "not_reproducible":
            return False
        if isinstance(self.value, str):
            return got == self.value
        if got is None:
            return False
        ok = True
        if self.value is not None:
            tol = max(self.abs or 0.0, (self.rel or 0.0) * abs(self.value))
            ok = bool(abs(got - self.value) <= tol)
        if self.max is not None:
            ok = ok and bool(got <= self.max)
        if self.min is not None:
            ok = ok and bool(got >= self.min)
        return ok

    def describe(self) -> str:
        if isinstance(self.value, str):
            return self.value
        if self.verdict == "not_reproducible":
            return f"{self.value:g}"
        parts = []
        if self.value is not None:
            parts.append(f"{self.value:g} ± " + (f"{self.abs:g}" if self.abs else f"{self.rel:g} rel"))
        if self.min is not None:
            parts.append(f">= {self.min:g}")
        if self.max is not None:
            parts.append(f"<= {self.max:g}")
        return ", ".join(parts)


class SceneFile(BaseModel):
    """The TOML layout of a scene (see cases/)."""
    model_config = ConfigDict(extra="forbid")
    id: str
    title: str
    source: str
    task: str
    solver: str
    effects: list[str] = []
    params: dict[str, Param] = {}            # a scene whose inputs are all in structure (or defaults) needs none
    structure: dict[str, Any] = {}           # non-numeric inputs (a network's events, a list of speeds),
                                             # handed to the task as they are; it validates them
    derive: dict[str, str] = {}              # param = "other-scene-id:value_name": a chain of models
    solver_settings: dict[str, Number | str | bool] = {}
    method: dict[str, Number | str] = {}     # the source's own method, when it matters to the numbers
    expect: dict[str, Expectation] = {}
    headline: list[str] = []                 # values the README or report shows: their drivers (mechopt.drivers)
    headline_fixed: dict[str, str] = {}      # inputs not varied for the drivers, each with why

    @field_validator("id")
    @classmethod
    def _usable_as_a_file_name(cls, value):
        problem = id_problem(value)
        if problem:
            raise ValueError(problem)
        return value


@dataclasses.dataclass(frozen=True)
class Scene:
    """A validated scene: the file's content plus the task class and solver it names."""
    path: Path
    spec: SceneFile
    task_class: type
    solver: Any
    # the build `load` validated, handed to the first build() without overrides: a scene read and
    # run builds its task once (a 10^5-operation timing table costs seconds per build)
    _validated: list = dataclasses.field(default_factory=list, compare=False, repr=False)

    @property
    def id(self) -> str:
        return self.spec.id

    def params(self) -> dict[str, Any]:
        return {k: v.value for k, v in self.spec.params.items()}

    def marks(self) -> dict[str, str]:
        return {k: v.mark for k, v in self.spec.params.items()}

    def settings(self) -> dict[str, Any]:
        return dict(self.spec.solver_settings)

    def split_overrides(self, overrides: dict[str, Any]) -> tuple[dict, dict]:
        """Sort `--set` pairs into parameters (structure paths included) and solver settings;
        unknown keys are refused."""
        fields = task_fields(self.task_class)
        options = solver_options(self.solver)
        params, settings = {}, {}
        for key, value in overrides.items():
            if key in fields or path_head(key) in self.spec.structure:
                params[key] = value
            elif key in options:
                settings[key] = value
            else:
                raise SceneError(f"{self.path}: {key}: unknown key; parameters: {', '.join(fields)}; "
                                 f"solver settings: {', '.join(options) or 'none'}"
                                 + (f"; structure entries as PATH, e.g. {_path_example(self.spec.structure)}"
                                    if self.spec.structure else ""), key=key)
        return params, settings

    def describe(self) -> list[dict[str, str]]:
        """Every key `--set` reaches, one row each: key, kind (parameter, setting, structure),
        unit, mark (given, assumed, calibrated, derived, default), allowed range, current value."""
        rows = []
        fields = task_fields(self.task_class)
        for key, f in fields.items():
            if key in self.spec.params:
                param = self.spec.params[key]
                mark, value = param.mark, param.value
            elif key in self.spec.derive:
                mark, value = "derived", self.spec.derive[key]
            elif key in self.spec.structure or key == "effects":
                continue
            elif f.default is not dataclasses.MISSING:
                mark, value = "default", f.default
            else:
                continue
            low, high = declared_range(f.type)
            rows.append({"key": key, "kind": "parameter", "unit": unit_of(key), "mark": mark,
                         "range": describe_range(low, high) if low or high else (
                             _relative_range(f.type) or "any finite number" if get_origin(f.type) is Annotated
                             else _shape(f.type, value)),
                         "value": _show(value)})
        for key, option in solver_options(self.solver).items():
            choices = get_args(option.annotation) if get_origin(option.annotation) is Literal else ()
            low, high = declared_range(option.annotation)
            rows.append({"key": key, "kind": f"setting of {self.solver.__name__}", "unit": unit_of(key),
                         "mark": "scene" if key in self.spec.solver_settings else "default",
                         "range": " | ".join(map(str, choices)) if choices else describe_range(low, high),
                         "value": _show(self.spec.solver_settings.get(key, option.default))})
        for key, value in self.spec.structure.items():
            rows.append({"key": key if not (isinstance(value, list) and value and isinstance(value[0], dict))
                         else _path_example(self.spec.structure, key).rsplit("=", 1)[0].strip("'"),
                         "kind": "structure", "unit": unit_of(key), "mark": "given",
                         "range": "a TOML value of the same shape", "value": _show(value)})
        return rows

    def build(self, overrides: dict[str, Any] | None = None):
        """The task instance and solver settings, overrides applied and validated like the file.
        A whole structure entry the scene does not have (`--set 'windows=[...]'`) is structure
        too: a table or list is never read as a parameter."""
        if not overrides and self._validated:
            return self._validated.pop()
        params, settings = self.split_overrides(overrides or {})
        long = _long_list(params)
        if long:
            raise SceneError(f"{self.path}: {long[0]}: {long[1]} entries; a list given here holds at most "
                             f"{MAX_LIST_ITEMS}", key=long[0])
        paths = {k: v for k, v in params.items() if path_head(k) in self.spec.structure}
        fields = task_fields(self.task_class)
        added = {k: v for k, v in params.items() if k not in paths and k not in self.spec.params
                 and isinstance(v, (list, dict, str)) and _is_structure(fields.get(k))}
        params = {k: v for k, v in params.items() if k not in paths and k not in added}
        return (_build_task(self.path, self.task_class, self.spec.effects, self.params() | params,
                            _set_paths(self.path, self.spec.structure, paths) | added),
                _check_settings(self.path, self.solver, self.settings() | settings))


def load(path: Path) -> Scene:
    """Read and validate one scene file; raise SceneError naming the file, the key and what is allowed."""
    path = Path(path)
    try:
        text = read_regular(path, max_bytes=MAX_SCENE_BYTES, what="a scene file").decode("utf-8")
    except FileNotFoundError:
        raise SceneError(f"{path}: no such scene file") from None
    except IsADirectoryError:
        raise SceneError(f"{path}: a folder, not a scene file") from None
    except UnicodeDecodeError as exc:
        raise SceneError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise SceneError(f"{path}: cannot read: {exc.strerror}") from None
    except ValueError as exc:            # not a regular file, or larger than a scene ever is
        raise SceneError(str(exc)) from None
    return loads(text, path)


def loads(text: str, path: Path) -> Scene:
    """Validate a scene from its TOML text; `path` names it in messages (and is where it came
    from: a sweep's worker loads the client's file from its text)."""
    path = Path(path)
    try:
        raw = tomllib.loads(text.removeprefix("\ufeff"))     # a byte-order mark, as some editors write
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None
    except RecursionError:
        raise SceneError(f"{path}: not a scene: arrays or tables nested too deeply") from None
    except ValueError as exc:            # an integer of thousands of digits
        raise SceneError(f"{path}: not a scene: {str(exc).split(';')[0]}") from None
    long = _long_list(raw.get("structure"))
    if long:
        raise SceneError(f"{path}: structure.{long[0]}: {long[1]} entries; a list in a scene holds at most "
                         f"{MAX_LIST_ITEMS} (a longer table: {{ csv = \"file.csv\", columns = [...] }})", key=long[0])
    if "base" in raw:
        raw = _on_base(path, raw)
    try:
        spec = SceneFile.model_validate(raw)
    except ValidationError as exc:
        raise SceneError(f"{path}: " + "; ".join(_explain(e) for e in exc.errors())) from None
    task_class = _resolve(path, "task", spec.task, "mechopt.models")
    with _reading(path):
        spec = spec.model_copy(update={"structure": _read_tables(path, spec.structure,
                                                                 getattr(task_class, "CSV_TABLES", {}),
                                                                 getattr(task_class, "COLUMNAR_TABLES", {}))})
    solver = _resolve(path, "solver", spec.solver, "mechopt.solvers")
    fields = task_fields(task_class)
    for key, ref in spec.derive.items():
        source, sep, value = ref.partition(":")
        if key not in fields or key in spec.params or not sep or not source or not value:
            raise SceneError(f"{path}: derive.{key} = {ref!r}: expected a parameter of {task_class.__name__} "
                             "that params does not give, set to 'scene-id:value_name'", key=key)
    scene = Scene(path, spec, task_class, solver)
    if not spec.derive:     # a derived scene is checked when its sources have run (registry.run)
        scene._validated.append(scene.build())   # parameters, effects and settings valid before anything runs
    return scene


MAX_WALK_ENTRIES = 20_000       # files and folders looked at under one folder of scenes


def scene_files(folder) -> list[Path]:
    """The *.toml files under `folder` (recursively, symbolic links to folders not followed), in
    path order; a folder holding more than MAX_WALK_ENTRIES entries (`--cases /`: the whole disk)
    is refused after looking at that many, not walked to the end."""
    found, seen = [], 0
    for root, dirs, names in os.walk(folder):
        seen += len(dirs) + len(names)
        if seen > MAX_WALK_ENTRIES:
            raise SceneError(f"{folder}: more than {MAX_WALK_ENTRIES:,} files and folders below it; a folder of "
                             "scenes is smaller: name the folder that holds your *.toml files", key="cases")
        dirs.sort()
        found += [Path(root) / n for n in names if n.endswith(".toml")]
    return sorted(found)


def parse_overrides(pairs: list[str]) -> dict[str, Any]:
    """`KEY=VALUE` strings as typed values: TOML literals (3, 0.5, true, "x"), else plain text."""
    out = {}
    for pair in pairs:
        key, sep, text = split_assignment(pair)
        if not sep or not key.strip():
            raise SceneError(f"--set {pair!r}: expected KEY=VALUE, e.g. --set a_mm=40")
        try:
            out[key.strip()] = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = text.strip()
        except (ValueError, RecursionError):        # thousands of digits, or lists nested thousands deep
            raise SceneError(f"--set {key.strip()}: the value ({len(text):,} characters) is no number or table "
                             "a mechanism takes", key=key.strip()) from None
    return out


def split_assignment(text):
    """(key, "=", value) split at the first '=' outside a selector's brackets
    (`operations[from=3,to=7].min_deg=10` -> key `operations[from=3,to=7].min_deg`); (text, "", "")
    when there is none."""
    depth = 0
    for i, ch in enumerate(text):
        depth += (ch == "[") - (ch == "]")
        if ch == "=" and depth == 0:
            return text[:i], "=", text[i + 1:]
    return text, "", ""


def _is_structure(field) -> bool:
    """Whether a task field takes a table or list (its default is one, or none), not a number."""
    return field is not None and (field.default_factory is not dataclasses.MISSING
                                  or field.default is None or isinstance(field.default, (list, tuple, dict, str)))


def _long_list(table):
    """(key, length) of the first list in `table` longer than MAX_LIST_ITEMS, or None."""
    for key, value in (table or {}).items() if isinstance(table, dict) else ():
        if isinstance(value, list) and len(value) > MAX_LIST_ITEMS:
            return key, len(value)
    return None


def _path_parts(key):
    """`a.b[k=10.1].c` -> ["a", "b[k=10.1]", "c"]: dots inside a selector's brackets belong to it."""
    parts, depth, current = [], 0, ""
    for ch in key:
        depth += (ch == "[") - (ch == "]")
        if ch == "." and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    return parts + [current]


def path_head(key):
    """The structure entry a `--set` path starts at: `operations[from=3,to=7].min_deg` -> operations."""
    return _path_parts(key)[0].split("[", 1)[0]


def _path_example(structure, only=None):
    for name, value in structure.items():
        if only is not None and name != only:
            continue
        if isinstance(value, list) and value and isinstance(value[0], dict):
            first = value[0]
            keys = [k for k in first if isinstance(first[k], str)][:2]
            number = next((k for k, v in first.items() if isinstance(v, (int, float)) and not isinstance(v, bool)), "x")
            return f"'{name}[{','.join(f'{k}={first[k]}' for k in keys)}].{number}=...'"
    return f"{next(iter(structure))}.<key>=..."


def _set_paths(path, structure, assignments):
    """A copy of the structure with `--set` paths applied: `a.b.c` walks tables, and
    `list[k=v,k2=v2]` picks the one table of a list whose entries match (one pair is enough when
    it matches one entry: `operations[from=9]`). Only the tables and lists on a path are copied:
    a timing table of 10^5 operations is not deep-copied for one changed number."""
    out = dict(structure)
    for key, value in assignments.items():
        node, parts = out, _path_parts(key)
        for i, part in enumerate(parts):
            name, _, selector = part.partition("[")
            last = i == len(parts) - 1
            if not isinstance(node, dict) or name not in node:
                raise SceneError(f"{path}: {key}: no entry {name!r} here; there are "
                                 f"{', '.join(node) if isinstance(node, dict) else 'none'}", key=key)
            if selector:
                if last:
                    raise SceneError(f"{path}: {key}: name the entry to change after the selector", key=key)
                node[name] = items = list(node[name]) if isinstance(node[name], (list, Columns)) else node[name]
                pairs = _selector_pairs(path, key, name, selector, items)
                matches = [j for j, item in enumerate(items) if isinstance(item, dict)
                           and all(str(item.get(k)) == v for k, v in pairs.items())]
                if len(matches) != 1:
                    hint = "add a key" if matches else "none has those values; the form"
                    raise SceneError(f"{path}: {key}: [{selector} matches {len(matches)} entries of "
                                     f"{name!r}, not one ({hint}: {_selector_form(name, items)})", key=key)
                items[matches[0]] = node = dict(items[matches[0]])
            elif last:
                node[name] = value
            else:
                node[name] = node = dict(node[name]) if isinstance(node[name], dict) else node[name]
    return out


def _selector_pairs(path, key, name, selector, items):
    """The key=value pairs of a selector `[k=v,k2=v2]`; SceneError for a part without '=', or
    a key no entry of the list has, naming the allowed forms."""
    if not isinstance(items, list):
        raise SceneError(f"{path}: {key}: {name!r} is not a list of tables; a selector [...] picks "
                         "one table of a list", key=key)
    parts = [p.strip() for p in selector.removesuffix("]").split(",")]
    known = list(dict.fromkeys(k for item in items if isinstance(item, dict) for k in item))
    for part in parts:
        k, eq, v = part.partition("=")
        if not eq or not k.strip() or not v.strip() or k.strip() not in known:
            why = (f"{k.strip()!r} is no key of its entries (they have {', '.join(known)})" if eq and k.strip()
                   and v.strip() else f"{part!r} is not key=value")
            raise SceneError(f"{path}: {key}: [{selector}: {why}; allowed: {_selector_form(name, items)} "
                             f"or any key=value pairs that match one entry", key=key)
    return {k.strip(): v.strip() for k, _, v in (p.partition("=") for p in parts)}


def _selector_form(name, items):
    """An example selector from the list's first table: `operations[from=1,to=2]`."""
    first = next((item for item in items if isinstance(item, dict)), {})
    keys = [k for k in first if isinstance(first[k], str)][:2]
    return f"{name}[{','.join(f'{k}={first[k]}' for k in keys)}]"


# scene files whose tables are being read: a loop of references is refused. A context variable, so
# that threads loading scenes at once each see only their own chain (a shared set made one thread's
# chain look like another's loop)
_READING: ContextVar[frozenset] = ContextVar("mechopt_scene_reading", default=frozenset())


@contextmanager
def _reading(path):
    token = _READING.set(_READING.get() | {real_path(path)})
    try:
        yield
    finally:
        _READING.reset(token)


def _read_tables(path, structure, records=None, columnar=None):
    """Structure entries that name a file, read when the scene loads (paths relative to the scene
    file's folder):
    * `{ csv = "file.csv", columns = ["x_mm", "y_mm"] }`: the file's rows of those columns, so a
      designer's point table stays in the CSV their CAD system wrote (errors name line and column);
      for a key of the task's `CSV_TABLES` ({key: (required cells, {column: str or float})}), the
      rows as tables of the columns the file has (text or numbers by column; `columns` the ones
      it must have), as a machine's timing table of operations between named events; for a key
      of its `COLUMNAR_TABLES` ({key: the columns a whole-column table may have}), a plain file
      of those columns only as whole columns (tables.Columns, no object per row);
    * `{ scene = "../other/scene.toml", drop = [...] }`: that scene's model as a table: its params
      (with their marks), structure entries and effects, less the names dropped. One mechanism's
      data then lives in one place when another's model needs it (the loom takes the lift lever)."""
    out = dict(structure)
    for key, value in structure.items():
        if isinstance(value, dict) and "scene" in value:
            out[key] = _scene_table(path, key, value)
            continue
        if not (isinstance(value, dict) and "csv" in value):
            continue
        if set(value) - {"csv", "columns"} or not isinstance(value["csv"], str) or not (
                isinstance(value.get("columns"), list) and value["columns"]
                and all(isinstance(c, str) for c in value["columns"])):
            raise SceneError(f'{path}: structure.{key}: a table from a file is {{ csv = "file.csv", '
                             f'columns = ["x_mm", "y_mm"] }}; got {value!r}', key=key)
        if key in (records or {}):
            out[key] = _csv_records(path, value["csv"], value["columns"], key, *records[key], (columnar or {}).get(key))
        else:
            out[key] = _csv_rows(path.parent / value["csv"], value["columns"], key)
    return out


def _csv_records(path, csv_name, columns, key, required, kinds, columnar=None):
    """The CSV `csv_name` beside the scene `path` as a list of tables (column: text or number by
    `kinds`), every name of `columns` in its header and every cell of `required` in each row;
    `columnar` (a set of columns): a plain file of those columns only as tables.Columns
    (read_columns), the same rows when read as a list; any other file as a list of rows."""
    unknown = [c for c in columns if c not in kinds]
    if unknown:
        raise SceneError(f"{path}: structure.{key}.columns: unknown {', '.join(map(quote, unknown))}; "
                         f"allowed: {', '.join(kinds)}", key=key)
    try:
        table = read_columns(path.parent / csv_name, columns, kinds, required=required, what=f"a table of {key}",
                             example=",".join(columns), only=columnar) if columnar else None
        if table is not None:
            return table
        rows = read_records(path.parent / csv_name, columns, kinds, required=required, what=f"a table of {key}",
                            example=",".join(columns))
    except ModelError as exc:
        raise SceneError(f"{exc} (the table for structure.{key})", key=key) from None
    return [row for _, row in rows]


def _scene_table(path, key, value):
    source, drop = _other_scene(path, f"structure.{key}", value)
    params = {name: p.model_dump(exclude_defaults=True) for name, p in source.spec.params.items()}
    table = {"effects": list(source.spec.effects)} | source.spec.structure | params
    return {name: entry for name, entry in table.items() if name not in drop}


def _on_base(path, raw):
    """A scene file with `base = { scene = "kd2322.toml", drop = [...] }`: that scene's params,
    effects and structure under its own (its own win; its id, title, question and expectations
    are its own), so a press's data lives in one file and each question states only what differs."""
    source, drop = _other_scene(path, "base", raw.pop("base"))
    params = {name: p.model_dump(exclude_defaults=True) for name, p in source.spec.params.items() if name not in drop}
    structure = {name: v for name, v in source.spec.structure.items() if name not in drop}
    return raw | {"params": params | raw.get("params", {}), "structure": structure | raw.get("structure", {}),
                  "effects": raw.get("effects", list(source.spec.effects)),
                  "expect": _with_base_readings(raw.get("expect", {}), source)}


def _with_base_readings(expect, source):
    """The scene's figures of the source, each carrying the readings its base's figures were chosen
    after (the model it runs is the base's, readings and all), unless the row names its own."""
    readings = list(dict.fromkeys(r for e in source.spec.expect.values() for r in e.readings_after_figure))
    if not readings or not isinstance(expect, dict):
        return expect
    return {name: ({"readings_after_figure": readings} | row
                   if isinstance(row, dict) and row.get("kind") in ("published", "experimental") else row)
            for name, row in expect.items()}


def _other_scene(path, where, value):
    """(the scene `value` names, relative to `path`'s folder; the names it drops), checked."""
    drop = value.get("drop", []) if isinstance(value, dict) else None
    if not isinstance(value, dict) or set(value) - {"scene", "drop"} or not isinstance(value.get("scene"), str) or not (
            isinstance(drop, list) and all(isinstance(d, str) for d in drop)):
        raise SceneError(f'{path}: {where}: a model from another scene is {{ scene = "../other/scene.toml", '
                         f'drop = ["name", ...] }}; got {value!r}', key=where)
    source_path = real_path(path.parent / value["scene"])
    if source_path in _READING.get():
        raise SceneError(f"{path}: {where}: {value['scene']} leads back to a scene being read (a loop)", key=where)
    if len(_READING.get()) >= MAX_CHAIN:        # deeper, the reading itself would run out of stack
        raise SceneError(f"{path}: {where}: {value['scene']} makes a chain of references (base, scene = ...) of "
                         f"more than {MAX_CHAIN} scenes; a chain holds at most {MAX_CHAIN}", key=where)
    with _reading(path):
        source = load(source_path)
    unknown = sorted(set(drop) - set(source.spec.params) - set(source.spec.structure))
    if unknown:
        raise SceneError(f"{path}: {where}.drop: {', '.join(unknown)} not in {value['scene']}", key=where)
    return source, drop


def _csv_rows(csv_path, columns, key):
    try:
        header, rows, delimiter = read_rows(csv_path, what="a point table", example=",".join(columns))
        check_header(csv_path, header, columns, ", ".join(columns))
    except ModelError as exc:
        raise SceneError(f"{exc} (the table for structure.{key})", key=key) from None
    missing = [c for c in columns if c not in header]
    if missing:
        raise SceneError(f"{csv_path}: header {quote(header)} lacks {', '.join(missing)} (structure.{key}.columns)",
                         key=key)
    out, at = [], [header.index(c) for c in columns]       # looked up once, not per row
    for line, cells in rows:
        try:
            row = [number(cells[i], delimiter) for i in at]
        except (ValueError, IndexError):
            raise SceneError(f"{csv_path}: line {line} ({quote(delimiter.join(cells))}): expected numbers in "
                             f"{', '.join(columns)}", key=key) from None
        if not all(math.isfinite(v) and abs(v) <= MAX_TABLE_VALUE for v in row):
            raise SceneError(f"{csv_path}: line {line}: expected finite numbers within ±{MAX_TABLE_VALUE:g} "
                             f"(a point table's unit is in its column names: mm, deg)", key=key)
        out.append(row)
    return out


MAX_TABLE_VALUE = 1e9                # a kilometre in mm: no mechanism's point table reaches it


def _resolve(path, field, dotted, package):
    module_name, _, name = dotted.rpartition(".")
    if not module_name:
        raise SceneError(f"{path}: {field} = {dotted!r}: expected '<module>.<name>'", key=field)
    try:
        module = importlib.import_module(f"{package}.{module_name}")
    except ModuleNotFoundError:
        raise SceneError(f"{path}: {field} = {dotted!r}: no module {package}.{module_name}", key=field) from None
    if not hasattr(module, name):
        known = getattr(module, "__all__", [n for n, v in vars(module).items() if inspect.isclass(v)
                                            and dataclasses.is_dataclass(v) and v.__module__ == module.__name__])
        raise SceneError(f"{path}: unknown {field} {dotted!r}; known: "
                         + ", ".join(f"{module_name}.{n}" for n in known), key=field)
    found = getattr(module, name)
    right = (inspect.isclass(found) and dataclasses.is_dataclass(found) if field == "task"
             else callable(found) and not inspect.isclass(found))
    if not right:
        raise SceneError(f"{path}: {field} = {dotted!r} names a {type(found).__name__}, not a "
                         + ("model's task class" if field == "task" else "solver function"), key=field)
    return found


def _show(value) -> str:
    text = repr(value) if isinstance(value, str) else str(value)
    return text if len(text) <= 40 else f"{text[:37]}..."


def task_fields(task_class):
    """The task dataclass's fields by name (its parameters and structure inputs)."""
    return {f.name: f for f in dataclasses.fields(task_class)}


def _build_task(path, task_class, effects, params, structure=None):
    known_effects = getattr(task_class, "EFFECTS", {})
    unknown = [e for e in effects if e not in known_effects]
    if unknown:
        raise SceneError(f"{path}: effects: unknown {unknown}; {task_class.__name__} knows "
                         f"{', '.join(known_effects) or 'none'}", key="effects")
    fields = task_fields(task_class)
    for key, value in params.items():
        if key not in fields:
            raise SceneError(f"{path}: params.{key}: unknown parameter; allowed: {', '.join(fields)}", key=key)
        owner = next((e for e, spec in known_effects.items() if key in spec.params), None)
        if owner is not None and owner not in effects:
            raise SceneError(f"{path}: params.{key} belongs to effect '{owner}', which this scene does "
                             f"not call for; add it to effects or drop the parameter", key=key)
        # the model's own rule (kit.settings.field_problem), checked here to name the file: the same sentence
        problem = ("expected a number" if isinstance(value, bool) or not isinstance(value, (int, float))
                   else field_problem(fields[key].type, value))
        if problem:
            raise SceneError(f"{path}: params.{range_fault(key, value, problem)}", key=key)
    structure = dict(structure or {})
    if "effects" in fields:             # a task assembled from its effects is told which ones
        structure["effects"] = tuple(effects)
    for key in structure:
        if key not in fields or key in params:
            free = [k for k in fields if k not in params]
            raise SceneError(f"{path}: structure.{key}: unknown or given twice; {task_class.__name__} takes "
                             + (", ".join(free) if free else "nothing more (all its inputs are in params)"), key=key)
    missing = [name for name, f in fields.items() if f.default is dataclasses.MISSING
               and f.default_factory is dataclasses.MISSING and name not in params and name not in structure]
    if missing:
        raise SceneError(f"{path}: params: missing {', '.join(missing)}", key=missing[0])
    try:
        return task_class(**{k: float(v) for k, v in params.items()}, **structure)
    except MechoptError as exc:
        table = "structure" if exc.key and path_head(exc.key) in structure else "params"
        said = str(exc) if exc.key and str(exc).startswith(f"{exc.key}=") else f"{exc.key}: {exc}"   # the key once
        raise SceneError(f"{path}: {table}.{said}" if exc.key else f"{path}: {exc}", key=exc.key) from None
    except OverflowError:                # an integer of hundreds of digits in a table: no float holds it
        where = _beyond_float(structure) or "structure"
        raise SceneError(f"{path}: {where}: a number beyond a float's range (at most 1.8e308)",
                         key=path_head(where.removeprefix("structure."))) from None


def _beyond_float(structure):
    """The path (`structure.operations[2].min_deg`) of an integer in the tables and lists of
    `structure` that no float holds, or None; walked without recursion (a table may nest deeply)."""
    stack = [("structure", structure)]
    while stack:
        at, value = stack.pop()
        if isinstance(value, dict):
            stack += [(f"{at}.{k}", v) for k, v in value.items()]
        elif isinstance(value, (list, tuple)):
            stack += [(f"{at}[{i}]", v) for i, v in enumerate(value)]
        elif isinstance(value, int) and not isinstance(value, bool) and not abs(value) <= 1.7976931348623157e308:
            return at
    return None


@memoised(maxsize=256)
def solver_options(solver):
    """A solver's keyword-only settings by name (each with its default); read-only, cached: a
    sweep asks for them with every variant and `inspect.signature` is slow."""
    return MappingProxyType({name: p for name, p in inspect.signature(solver).parameters.items()
                             if p.kind is p.KEYWORD_ONLY})


def _check_settings(path, solver, settings):
    options = solver_options(solver)
    for key, value in settings.items():
        if key not in options:
            raise SettingError(f"{path}: solver_settings.{key}: unknown setting of {solver.__name__}; "
                             f"allowed: {', '.join(options) or 'none'}", key=key)
        problem = setting_problem(options[key], value)
        if problem:
            raise SettingError(f"{path}: solver_settings.{range_fault(key, value, problem)}", key=key)
    return {k: (float(v) if type(options[k].default) is float else v) for k, v in settings.items()}


def _explain(error) -> str:
    loc = ".".join(str(p) for p in error["loc"] if not str(p).startswith(("function-after", "union")))
    if error["type"] == "extra_forbidden":
        allowed = _allowed_at(error["loc"])
        return f"{loc}: unknown key" + (f"; allowed: {', '.join(allowed)}" if allowed else "")
    if error["type"] == "missing":
        return f"{loc}: missing"
    return f"{loc}: {error['msg']} (got {quote(error.get('input'))})"


def _allowed_at(loc):
    head = loc[0] if loc else None
    if len(loc) == 1:
        return list(SceneFile.model_fields)
    if head == "expect":
        return list(Expectation.model_fields)
    if head == "params":
        return list(Param.model_fields)
    return []


def _relative_range(annotation) -> str:
    """A range that depends on another input, declared as text (`annotated_types.doc`) on the field."""
    return next((mark.documentation for mark in get_args(annotation)[1:] if isinstance(mark, DocInfo)), "")


def _shape(annotation, value) -> str:
    """What a field that is not a number takes: its choices, text or a table (its model checks it)."""
    if get_origin(annotation) is Literal:
        return " | ".join(map(str, get_args(annotation)))
    return "text" if isinstance(value, str) else "a list or table (structure)"
