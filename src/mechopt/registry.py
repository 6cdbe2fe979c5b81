"""The case registry: every scene under cases/, run one, check it against what its source says."""
import difflib
from dataclasses import dataclass, field
from functools import lru_cache
from importlib.resources import files
from pathlib import Path
from typing import Any

from mechopt.models.errors import SceneError
from mechopt.scene import Scene, load
from mechopt.solvers.result import Result, Status


@dataclass(frozen=True)
class Check:
    name: str
    expected: str            # as the scene states it: "1.5 ± 0.01", "<= 0.2", "INFEASIBLE"
    got: Any                 # float, status word, or None when the solver did not produce it
    tol: float | None
    ok: bool
    kind: str                # published | experimental | derived
    where: str
    calibrated: bool = False  # fitted to this value, or it follows from a fit: agreement by construction

    def as_dict(self):
        return {"name": self.name, "expected": self.expected, "got": self.got, "tol": self.tol,
                "ok": self.ok, "kind": self.kind, "where": self.where, "calibrated": self.calibrated}

    @property
    def verdict(self) -> str:
        """What a passed check shows: "reproduced" (a value from the source, not fitted to it),
        "calibrated" (agreement by construction), "consistent" (a derived value: an independent
        computation, a bound or a status); or "failed"."""
        if not self.ok:
            return "failed"
        if self.calibrated:
            return "calibrated"
        return "reproduced" if self.kind in ("published", "experimental") else "consistent"


def tally(checks) -> dict[str, int]:
    """How many checks are reproduced, calibrated, consistent and failed (see `Check.verdict`)."""
    verdicts = [c.verdict for c in checks]
    return {v: verdicts.count(v) for v in ("reproduced", "calibrated", "consistent", "failed")}


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
        return all(c.ok for c in self.checks)

    def as_dict(self):
        r = self.result
        return {"case": self.scene.id, "status": r.status.value, "message": r.message,
                "values": {k: float(v) for k, v in r.values.items()},
                "checks": [c.as_dict() for c in self.checks],
                "timing": {"build_s": r.timing.build_s, "solve_s": r.timing.solve_s},
                "violated": list(r.violated), "overrides": self.overrides,
                "diagnostics": _plain(r.diagnostics)}


def cases_dir() -> Path:
    return Path(str(files("mechopt.cases")))


@lru_cache(maxsize=1)
def all_scenes() -> tuple[Scene, ...]:
    """Every scene in the registry, validated, in id order; a bad file stops the whole load."""
    scenes = [load(p) for p in sorted(cases_dir().glob("*/*.toml"))]
    ids = [s.id for s in scenes]
    twice = {i for i in ids if ids.count(i) > 1}
    if twice:
        raise SceneError(f"{cases_dir()}: scene ids used twice: {', '.join(sorted(twice))}")
    _check_calibration_targets(scenes)
    return tuple(sorted(scenes, key=lambda s: s.id))


def _check_calibration_targets(scenes):
    """A calibration names a figure some scene expects: a typo would silently make it a 'reproduction'."""
    expected = {name for s in scenes for name in s.spec.expect}
    for scene in scenes:
        for key, param in scene.spec.params.items():
            if param.mark == "calibrated" and param.on not in expected:
                near = difflib.get_close_matches(param.on, sorted(expected), n=2)
                raise SceneError(f"{scene.path}: params.{key}.on = {param.on!r}: no scene expects that value"
                                 + (f"; did you mean {', '.join(near)}?" if near else ""), key=key)


def find(case_id: str) -> Scene:
    for scene in all_scenes():
        if scene.id == case_id:
            return scene
    ids = [s.id for s in all_scenes()]
    near = difflib.get_close_matches(case_id, ids, n=3)
    raise SceneError(f"unknown case {case_id!r}" + (f"; did you mean {', '.join(near)}?" if near else "")
                     + f" (known: {', '.join(ids)}; `mechopt cases` lists them)")


def run(scene: Scene, overrides: dict | None = None) -> Run:
    """Solve a scene (with `--set` overrides, validated like the file) and check its expectations."""
    overrides = dict(overrides or {})
    task, settings = scene.build(_derived_params(scene) | overrides)
    result = scene.solver(task, **settings)
    params_changed = bool(scene.split_overrides(overrides)[0])
    checks = [] if params_changed else check(scene, result)
    return Run(scene, result, checks, overrides, task, settings)


def _derived_params(scene: Scene, chain: tuple[str, ...] = ()) -> dict:
    """Values of the parameters a scene takes from other scenes' results (run as their files say)."""
    out = {}
    for key, (source_id, name) in scene.derived().items():
        if source_id in chain + (scene.id,):
            raise SceneError(f"{scene.path}: derive.{key}: {' -> '.join(chain + (scene.id, source_id))} is a loop")
        result = _source_result(source_id, chain + (scene.id,))
        if result.status is not Status.SOLVED or name not in result.values:
            raise SceneError(f"{scene.path}: derive.{key}: scene {source_id} gave status {result.status.value}"
                             + ("" if name in result.values else f" and no value {name!r}; it has "
                                + ", ".join(result.values)), key=key)
        out[key] = result.values[name]
    return out


@lru_cache(maxsize=None)
def _source_result(source_id: str, chain: tuple[str, ...]) -> Result:
    """A scene's result as its file says: depends on the file alone, so a sweep of a derived
    scene solves its source once per process, not once per variant."""
    source = find(source_id)
    task, settings = source.build(_derived_params(source, chain))
    return source.solver(task, **settings)


def check(scene: Scene, result: Result) -> list[Check]:
    """Each expectation of the scene against the result. A number counts only from a SOLVED
    result, or from the status the scene itself expects (an INFEASIBLE best-achievable value)."""
    expected_status = scene.spec.expect.get("status")
    trusted = result.status is Status.SOLVED or (expected_status is not None
                                                 and result.status.value == expected_status.value)
    out = []
    for name, exp in scene.spec.expect.items():
        got = result.status.value if name == "status" else result.values.get(name)
        tol = None if isinstance(exp.value, str) or exp.value is None else max(exp.abs or 0.0, (exp.rel or 0.0) * abs(exp.value))
        ok = exp.check(got) and (name == "status" or trusted)
        out.append(Check(name, exp.describe(), None if got is None else (got if isinstance(got, str) else float(got)),
                         tol, ok, exp.kind, exp.where, name in scene.calibrated_on() or bool(exp.follows)))
    return out


def _plain(value):
    """Diagnostics as JSON-ready values (numpy scalars to Python numbers)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item"):
        return value.item()
    return value
