"""One rule per input: a model's fields declare their ranges (`Annotated`), the model checks them
when it is built (kit.settings.check_fields), and a scene file and a Python call out of range get
the same sentence."""
import dataclasses
import importlib
import inspect
import pkgutil
from typing import Annotated, Literal, Union, get_args, get_origin

import pytest
from annotated_types import Ge, Gt, Le

import mechopt.models
from mechopt import registry
from mechopt.kit.errors import ModelError, SceneError
from mechopt.kit.settings import check_fields, declared_range, describe_range, field_problem
from mechopt.models.cam_shape import CamShape

# one scene per model a scene can name: its task is a valid instance to spoil one field of
SCENES = {"PressDrive": "press/kd2322", "PressDesign": "press/flywheel-design", "PressCatalogue": "press/motor-catalogue",
          "LinkageFit": "cam-cutter/minimax", "LinkageCheck": "cam-cutter/linkage-check",
          "LinkageLoads": "cam-cutter/joint-reactions", "ToolFamily": "cam-cutter/readjustable",
          "ProfileFit": "cam-cutter/other-profile", "CamShape": "stop-impact/lift-cam-profile",
          "Cyclogram": "loom/group1", "LeverStop": "stop-impact/frequencies", "CamFollower": "cam/translating-roller"}

# dataclasses of models/ whose numbers are no user's input, each with why they declare no range
NO_RANGE = {
    "Impact": "eq. (2)'s inputs for one approach, computed by LeverStop.impact from a checked lever",
    "SplineBasis": "built by the law synthesis from its checked settings; its own __post_init__ checks continuity",
    "SplineLaw": "a finished spline law (knots, coefficients) made by SplineBasis.law",
    "ExpressionCurve": "ProfileFit's curve: t0, t1 come from ProfileFit's checked t0_rad, t1_rad (and are checked again)",
    "TableCurve": "ProfileFit's table of points, checked row by row in its own __post_init__",
    "Equations": "the press's compiled equations for one structure (effects, kinematics), no number",
    "Dynamics": "the press's equations bound to a checked PressDrive's numbers",
    "PlacedPath": "a curve placed by `place`, which ProfileFit calls with its checked h_mm",
    "Pitch": "a computed result (pitch curve samples)",
    "ShapeSummary": "a computed result (radii and angles of a cam shape)",
    "PointTable": "a computed result (a shop's point table)",
    "Effect": "a description of an effect, no number",
    "PlainNetwork": "a plain timing table as index arrays, made by PlainNetwork.of from a Columns table whose cells "
                    "tables.read_columns checked (else the row path, which checks each row)",
    "Law": "a library law: its forms and breaks are the library's own; end_order is derived, not given",
    "_Piece": "a piece of a library law (SCCA, trapezoid), built by the library from its checked b, c, cv",
    "Segment": "a row of CamMotion.segments, checked by `cam_motion._segment` (kind, angle in (0, 360] deg, the "
               "lift's sign by kind, a finite number each) before it is built",
    "Join": "a computed result (a step of s' or s'' where two segments meet)",
    "CamMotion": "segments checked row by row (`cam_motion._segment`); a cam scene's task holds it",
    "CamCurves": "a computed result (a cam's pitch curve, profile, radii and pressure angle)",
    "Load": "a press load resolved by `press_loads` from PressDrive's checked load_* fields (or its checked table)",
    "Motion": "an operation row's motion, its cells checked by `loom_motions.motion_of` before it is built",
    "Clearance": "a clearances row resolved by `loom_motions.clearance_rows` from its checked cells",
}


def _model_dataclasses():
    for info in pkgutil.iter_modules(mechopt.models.__path__):
        module = importlib.import_module(f"mechopt.models.{info.name}")
        for name, cls in vars(module).items():
            if inspect.isclass(cls) and dataclasses.is_dataclass(cls) and cls.__module__ == module.__name__:
                yield name, cls


def _is_numeric(annotation) -> bool:
    base = get_args(annotation)[0] if get_origin(annotation) is Annotated else annotation
    kinds = get_args(base) if get_origin(base) in (Union, type(int | None)) else (base,)
    return any(k in (int, float) for k in kinds)


def _ranged_fields(cls):
    for f in dataclasses.fields(cls):
        low, high = declared_range(f.type)
        if f.init and (low or high):
            yield f.name, low, high


def _outside(low, high) -> list[float]:
    """Values past the declared range: below its lower end, above its upper end (those it has)."""
    below = [float(low[0] - abs(low[0]) - 1 if low[2] == "ge" else low[0])] if low else []
    above = [float(high[0] + abs(high[0]) + 1 if high[2] == "le" else high[0])] if high else []
    return below + above


def test_every_numeric_input_of_a_model_declares_its_range():
    seen, missing = set(), []
    for name, cls in _model_dataclasses():
        seen.add(name)
        if name in NO_RANGE:
            continue
        missing += [f"{name}.{f.name}" for f in dataclasses.fields(cls)
                    if f.init and _is_numeric(f.type) and get_origin(f.type) is not Annotated]
    assert not missing, f"numbers without a declared range (Annotated[...]): {missing}"
    assert set(SCENES) | set(NO_RANGE) == seen, "a model dataclass is neither a scene's task nor explained in NO_RANGE"


@pytest.fixture(scope="module")
def tasks():
    return {name: registry.find(scene_id).build()[0] for name, scene_id in SCENES.items()}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_a_field_out_of_its_range_from_python_is_refused_naming_key_and_range(tasks, name):
    task = tasks[name]
    fields = list(_ranged_fields(type(task)))
    assert fields, f"{name} declares no range"
    for key, low, high in fields:
        for bad in _outside(low, high):
            with pytest.raises(ModelError) as err:
                dataclasses.replace(task, **{key: bad})
            assert str(err.value) == f"{key}={bad!r}: allowed {describe_range(low, high)}"
            assert err.value.key == key


@pytest.mark.parametrize("name", sorted(SCENES))
def test_a_scene_and_a_python_call_give_the_same_sentence(tasks, name):
    scene = registry.find(SCENES[name])
    key, low, high = next(f for f in _ranged_fields(scene.task_class) if f[0] in scene.spec.params)
    bad = _outside(low, high)[0]
    with pytest.raises(ModelError) as python:
        dataclasses.replace(tasks[name], **{key: bad})
    with pytest.raises(SceneError) as from_file:
        scene.build({key: bad})
    assert str(from_file.value) == f"{scene.path}: params.{python.value}"
    assert from_file.value.key == python.value.key == key


def test_a_cam_built_from_python_with_a_negative_radius_is_refused():
    """CamShape's ranges were read only from scene files: from Python a negative base radius passed."""
    with pytest.raises(ModelError, match=r"^base_radius_mm=-5\.0: allowed > 0$") as err:
        CamShape(base_radius_mm=-5.0, roller_radius_mm=10.0, stroke_mm=20.0, rise_deg=120.0, return_deg=120.0)
    assert err.value.key == "base_radius_mm"
    with pytest.raises(ModelError, match=r"^follower='rotating': allowed translating, oscillating$"):
        CamShape(base_radius_mm=5.0, roller_radius_mm=10.0, stroke_mm=20.0, rise_deg=120.0, return_deg=120.0,
                 follower="rotating")


@dataclasses.dataclass(frozen=True)
class _Probe:
    length_mm: Annotated[float, Gt(0), Le(10)]
    count: Annotated[int, Ge(1), Le(5)] = 1
    spare_mm: Annotated[float | None, Ge(0)] = None
    flag: bool = False
    mode: Literal["a", "b"] = "a"
    name: str = "x"

    def __post_init__(self):
        check_fields(self)


@pytest.mark.parametrize("changes, message", [
    ({"length_mm": 0}, "length_mm=0: allowed > 0 ... 10"),
    ({"length_mm": float("inf")}, "length_mm=inf: expected a finite number"),
    ({"length_mm": 10 ** 400}, "length_mm=1000000000000000000000000000000000000000... (401 characters): expected a "
                               "finite number"),
    ({"length_mm": True}, "length_mm=True: expected a number"),
    ({"length_mm": "5"}, "length_mm='5': expected a number"),
    ({"length_mm": None}, "length_mm=None: expected a value, not None"),
    ({"count": 2.5}, "count=2.5: expected a whole number"),
    ({"count": 6}, "count=6: allowed 1 ... 5"),
    ({"spare_mm": -1.0}, "spare_mm=-1.0: allowed >= 0"),
    ({"flag": 1}, "flag=1: expected true or false"),
    ({"mode": "c"}, "mode='c': allowed a, b"),
    ({"name": 3}, "name=3: expected text"),
])
def test_check_fields_reads_kind_and_range_from_the_annotation(changes, message):
    with pytest.raises(ModelError) as err:
        _Probe(**({"length_mm": 5.0} | changes))
    assert str(err.value) == message
    assert err.value.key == next(iter(changes))


def test_valid_values_pass_and_a_whole_float_is_a_whole_number():
    probe = _Probe(length_mm=10, count=5.0, spare_mm=None, flag=True, mode="b", name="y")
    assert probe.count == 5.0
    assert field_problem(Annotated[float | None, Gt(0)], None) == ""
