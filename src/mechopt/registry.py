"""The case registry: the scenes that ship with mechopt plus the user's folders (`--cases DIR`,
MECHOPT_CASES) and files (named by path); run one, check it against what its source says."""
import difflib
import os
from dataclasses import dataclass, field, replace
from importlib.resources import files
from pathlib import Path
from typing import Any

from mechopt.drivers import elasticities, uncertain_inputs
from mechopt.kit import interrupt
from mechopt.kit.cache import memoised
from mechopt.kit.errors import MechoptError, SceneError
from mechopt.kit.result import Result, Status
from mechopt.models.validity import out_of_range
from mechopt.scene import Scene, id_problem, load, scene_files
from mechopt.units import unit_of
from mechopt.verdicts import Check, check


@dataclass(frozen=True)
class Run:
    """One solved scene: the solver's result and its checks (none when parameters were overridden:
    a source's figures hold for the source's parameters only)."""
    scene: Scene
    result: Result
    checks: list[Check]
    overrides: dict = field(default_factory=dict)
    task: Any = None              # the task as solved: overrides and derived parameters applied
    settings: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """The answer is the one the scene asks for and every check passes: SOLVED, or the status
        the scene itself expects (an INFEASIBLE loom that names its conflict), even in a what-if
        where no check is made."""
        return self.status_as_expected and all(c.ok for c in self.checks)

    @property
    def status_as_expected(self) -> bool:
        """SOLVED, or the status the scene's `[expect.status]` names."""
        expected = self.scene.spec.expect.get("status")
        return self.result.status is Status.SOLVED or (expected is not None
                                                       and expected.value == self.result.status.value)

    @property
    def success(self) -> bool:
        """Whether the solver reached an answer to trust (SOLVED), as scipy's `OptimizeResult.success`."""
        return self.result.success

    @property
    def status(self) -> Status:
        return self.result.status

    @property
    def values(self) -> dict[str, float]:
        """The solver's values, named with their unit (`H_mm`): plain Python floats (a count an int)."""
        return self.result.values

    @property
    def message(self) -> str:
        """The solver's word on how it ended (the back end's status, rounds, nodes)."""
        return self.result.message

    @property
    def warnings(self) -> tuple[str, ...]:
        """Sentences, one per way this answer leaves what its model's source supports."""
        return self.result.warnings

    @property
    def diagnostics(self) -> dict:
        """What the solver adds about its answer (the drivers' elasticities, a certificate's gap)."""
        return self.result.diagnostics

    @property
    def violated(self) -> tuple[str, ...]:
        """The physical names of the limits the answer breaks (an INFEASIBLE run's best achievable)."""
        return self.result.violated

    @property
    def arrays(self) -> dict:
        """What the solver computed along the way (a run's `t_s` and states), named with units."""
        return self.result.arrays

    def with_units(self) -> dict[str, tuple[float, str]]:
        """Each value with the unit its name states: {"H_mm": (59.60, "mm"), ...}."""
        return {k: (v, unit_of(k)) for k, v in self.result.values.items()}

    def value_rows(self) -> list[tuple[str, float, str, str]]:
        """(name, value, unit, mark) per value: the mark is its check's verdict where the scene
        expects it ("reproduced", "calibrated", "not reproduced (-30.0%)"), else "computed"."""
        marks = {c.name: c.label if c.ok else f"FAIL ({c.label})" for c in self.checks}
        return [(k, v, unit_of(k), marks.get(k, "computed")) for k, v in self.result.values.items()]

    def __repr__(self) -> str:
        r = self.result
        what_if = f", what-if {self.overrides}" if self.overrides else ""
        checks = f"{sum(c.ok for c in self.checks)}/{len(self.checks)} checks pass" if self.checks else "no checks"
        return f"Run({self.scene.id!r}, {r.status.value}, ok={self.ok}, {checks}{what_if}, {r!r})"

    def _repr_html_(self) -> str:
        from html import escape

        from mechopt.answers import answers_html
        return f"<p><b>{escape(self.scene.id)}</b>: {escape(self.scene.spec.title)}</p>" + answers_html(self)

    def figures(self) -> dict:
        """This run's figures as matplotlib Figures, by name (shown as they are in a notebook)."""
        from mechopt.figures import figures_of
        return figures_of(self)

    def as_dict(self):
        r = self.result
        return {"case": self.scene.id, "status": r.status.value, "message": r.message,
                "values": {k: float(v) for k, v in r.values.items()},
                "checks": [c.as_dict() for c in self.checks],
                "timing": {"build_s": r.timing.build_s, "solve_s": r.timing.solve_s},
                "violated": list(r.violated), "warnings": list(r.warnings), "overrides": self.overrides,
                "diagnostics": _plain(r.diagnostics)}


ENV_CASES = "MECHOPT_CASES"          # more scene folders, separated like PATH


def cases_dir() -> Path:
    """The scenes that ship with mechopt."""
    return Path(str(files("mechopt.cases")))


_USER_FOLDERS: list[Path] = []


def add_cases(folder) -> None:
    """Add a folder of the user's scenes (searched recursively for *.toml) to the registry."""
    folder = Path(folder).expanduser()
    if not folder.is_dir():
        raise SceneError(f"--cases {folder}: no such folder")
    if folder.resolve() not in [f.resolve() for f in _USER_FOLDERS]:
        _USER_FOLDERS.append(folder)


def user_folders() -> tuple[Path, ...]:
    """The user's scene folders: `add_cases` (`--cases DIR`) and the MECHOPT_CASES variable."""
    from_env = [Path(p).expanduser() for p in os.environ.get(ENV_CASES, "").split(os.pathsep) if p.strip()]
    missing = [str(p) for p in from_env if not p.is_dir()]
    if missing:
        raise SceneError(f"{ENV_CASES}: no such folder {', '.join(missing)}")
    return tuple(dict.fromkeys([*_USER_FOLDERS, *from_env]))


@dataclass(frozen=True)
class Catalogue:
    """Every scene the registry knows, in id order, and the user's files it could not load."""
    scenes: tuple[Scene, ...]
    problems: tuple[str, ...]        # one line each: "<file>: <what is wrong>"


def catalogue() -> Catalogue:
    return _catalogue(user_folders())


@memoised(maxsize=4)
def _catalogue(folders: tuple[Path, ...]) -> Catalogue:
    # the package's own scenes must all load: a bad one stops everything
    scenes = [load(p) for p in sorted(cases_dir().glob("*/*.toml"))]
    _refuse_twice(scenes, cases_dir())
    problems = []
    for folder in folders:
        for path in scene_files(folder):
            try:
                scene = load(path)
            except MechoptError as exc:      # one bad file of the user's does not stop the others
                problems.append(str(exc))
                continue
            clash = next((s for s in scenes if s.id == scene.id), None)
            if clash is not None:
                problems.append(f"{path}: id {scene.id!r} is already taken by {clash.path}; give it another id")
                continue
            scenes.append(scene)
    expected = {name for s in scenes for name in s.spec.expect}
    ids = {s.id for s in scenes}
    ours = [s for s in scenes if s.path.is_relative_to(cases_dir())]
    for scene in ours:
        _check_calibration_targets(scene, expected)
        _check_alternatives(scene, ids)
    kept = list(ours)
    for scene in scenes[len(ours):]:
        try:
            _check_calibration_targets(scene, expected)
            _check_alternatives(scene, ids)
            kept.append(scene)
        except SceneError as exc:
            problems.append(str(exc))
    return Catalogue(tuple(sorted(kept, key=lambda s: s.id)), tuple(problems))


def all_scenes() -> tuple[Scene, ...]:
    """Every scene in the registry (the package's and the user's folders'), validated, in id order."""
    return catalogue().scenes


def _refuse_twice(scenes, where):
    ids = [s.id for s in scenes]
    twice = {i for i in ids if ids.count(i) > 1}
    if twice:
        raise SceneError(f"{where}: scene ids used twice: {', '.join(sorted(twice))}")


def _check_calibration_targets(scene, expected):
    """A calibration names a figure some scene expects: a typo would silently make it a 'reproduction'."""
    for key, param in scene.spec.params.items():
        if param.mark == "calibrated" and param.on not in expected:
            near = difflib.get_close_matches(param.on, sorted(expected), n=2)
            raise SceneError(f"{scene.path}: params.{key}.on = {param.on!r}: no scene expects that value"
                             + (f"; did you mean {', '.join(near)}?" if near else ""), key=key)


def _check_alternatives(scene, ids):
    """An alternative reading names the scene whose reading is taken: a typo would hide which one counts."""
    for name, exp in scene.spec.expect.items():
        if exp.alternative_to and exp.alternative_to not in ids:
            near = difflib.get_close_matches(exp.alternative_to, sorted(ids), n=2)
            raise SceneError(f"{scene.path}: expect.{name}.alternative_to = {exp.alternative_to!r}: no such scene"
                             + (f"; did you mean {', '.join(near)}?" if near else ""), key=name)


def is_path(ref: str) -> bool:
    """Whether a reference names a file or folder rather than a registry id."""
    ref = str(ref)
    return ref.endswith(".toml") or Path(ref).is_dir() or Path(ref).is_file() or ref.startswith((".", "~", os.sep))


def find(ref) -> Scene:
    """A scene by registry id ("loom/group1"), or loaded from a scene file's path."""
    if isinstance(ref, Scene):
        return ref
    if is_path(ref):
        path = Path(ref).expanduser()
        if path.is_dir():
            raise SceneError(f"{path}: a folder of scenes; name one file, or use it where several scenes are taken "
                             "(validate, report)")
        return load(path)
    own = _package_scene(ref)
    if own is not None:
        return own
    for scene in all_scenes():
        if scene.id == ref:
            return scene
    ids = [s.id for s in all_scenes()]
    near = difflib.get_close_matches(ref, ids, n=3)
    raise SceneError(f"unknown case {ref!r}" + (f"; did you mean {', '.join(near)}?" if near else "")
                     + " (`mechopt cases` lists the ids; a scene file is named by its path, e.g. ./my.toml)")


def _package_scene(ref: str) -> Scene | None:
    """The package's scene `ref` read from its own file (cases/<id>.toml), without reading the
    whole catalogue: solving one scene imports its own model and solver only. The package's ids
    win over the user's (a clash is refused in the catalogue), and its scenes' cross-references
    are checked by the catalogue in the tests."""
    if id_problem(ref):
        return None
    path = cases_dir() / f"{ref}.toml"
    if not path.is_file():
        return None
    scene = _package_file(path)
    return scene if scene.id == ref else None


@memoised(maxsize=256)
def _package_file(path: Path) -> Scene:
    return load(path)


def select(refs=()) -> tuple[list[Scene], list[str]]:
    """Scenes for several references (ids, files, folders of *.toml), or the whole registry when
    none is given: the scenes, and one line per file that could not be loaded (the others run)."""
    if not refs:
        catalogue_now = catalogue()
        return list(catalogue_now.scenes), list(catalogue_now.problems)
    scenes, problems = [], []
    for ref in refs:
        path = Path(str(ref)).expanduser()
        if not isinstance(ref, Scene) and is_path(ref) and path.is_dir():
            found = scene_files(path)
            if not found:
                raise SceneError(f"{path}: no scene files (*.toml) in this folder")
            for file in found:
                try:
                    scenes.append(load(file))
                except MechoptError as exc:
                    problems.append(str(exc))
        else:
            scenes.append(find(ref))
    return scenes, problems


def run(scene: Scene | str, overrides: dict | None = None, *, drivers: bool = False) -> Run:
    """Solve a scene (a Scene, a registry id or a scene file's path), with overrides validated like
    the file, and check its expectations. With `drivers`, a scene's headline values gain their
    largest elasticities to its assumed and calibrated inputs (`diagnostics["drivers"]`: one
    re-solve per input and side, so only where asked)."""
    scene = find(scene)
    overrides = dict(overrides or {})
    what_if = bool(scene.split_overrides(overrides)[0])     # a source's figures hold for its own parameters
    task, settings = _pose(scene, overrides)
    result = _solve(scene.solver, task, settings)
    result = result.with_warnings(out_of_range(task, result.values))
    if drivers and scene.spec.headline:
        result = _with_drivers(scene, overrides, result)
    checks = [] if what_if else check(scene.spec, result)
    return Run(scene, result, checks, overrides, task, settings)


def pose(scene: Scene | str, overrides: dict | None = None):
    """(task, settings) as `run` would solve them, without solving the scene: its file, the values
    it derives from its sources (each solved once, as its file says), the overrides."""
    return _pose(find(scene), dict(overrides or {}))


def _pose(scene: Scene, overrides: dict, chain: tuple[str, ...] = ()):
    """The task and settings a scene poses: its file, the values it derives from other scenes'
    results (each source solved as its file says), then the overrides."""
    derived = {}
    for key, reference in scene.spec.derive.items():
        source_id, name = reference.split(":", 1)
        if source_id in chain + (scene.id,):
            raise SceneError(f"{scene.path}: derive.{key}: {' -> '.join(chain + (scene.id, source_id))} is a loop")
        try:
            result = _source_result(source_id, chain + (scene.id,))
        except SceneError as exc:        # a source that is not there: say which file and key asked for it
            raise SceneError(f"{scene.path}: derive.{key} = '{reference}': {exc}", key=key) from None
        if result.status is not Status.SOLVED or name not in result.values:
            raise SceneError(f"{scene.path}: derive.{key}: scene {source_id} gave status {result.status.value}"
                             + ("" if name in result.values else f" and no value {name!r}; it has "
                                + ", ".join(result.values)), key=key)
        derived[key] = result.values[name]
    return scene.build(derived | overrides)


@memoised(maxsize=64)
def _source_result(source_id: str, chain: tuple[str, ...]) -> Result:
    """A scene's result as its file says: depends on the file alone, so a sweep of a derived
    scene solves its source once per process, not once per variant."""
    source = find(source_id)
    return _solve(source.solver, *_pose(source, {}, chain))


def _with_drivers(scene: Scene, overrides: dict, result: Result) -> Result:
    def solve(more):
        return _solve(scene.solver, *_pose(scene, overrides | more))
    inputs = [replace(i, value=float(overrides[i.key])) if isinstance(overrides.get(i.key), (int, float)) else i
              for i in uncertain_inputs(scene)]
    found = elasticities(solve, inputs, scene.spec.headline, result.values)
    return replace(result, diagnostics={**result.diagnostics, "drivers": found})


def _solve(solver, task, settings) -> Result:
    """The solver's result; a Ctrl-C during it, which CasADi turns into a failed solve, raised
    as KeyboardInterrupt instead, so that no interrupted result is ever stored or reported."""
    with interrupt.honoured():
        try:
            return solver(task, **settings)
        finally:
            interrupt.check()


def _plain(value):
    """Diagnostics as JSON-ready values (numpy scalars to Python numbers)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item"):
        return value.item()
    return value
