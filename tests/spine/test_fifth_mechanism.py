"""The guide for a new mechanism (docs/new-mechanism.md), followed in a test: a slider-crank is
added as a contributor would, as one row of `mechopt.mechanisms` plus its own files (a model with
declared ranges and warnings, a solver, a scene, a figure, a DXF writer, a benchmark), written
into a temporary tree; run, validate, new, describe and --dxf then work with it."""
import sys

import pytest

import mechopt
from mechopt import dxf, mechanisms, registry
from mechopt.cli import main
from mechopt.figures.registry import FIGURES
from mechopt.kit.errors import SceneError

MODEL = '''"""A slider-crank: crank r, rod l, the slider on the line through the crank's centre."""
import math
from dataclasses import dataclass
from typing import Annotated

import numpy as np
from annotated_types import Gt, Le

from mechopt.kit.errors import ModelError


@dataclass(frozen=True)
class SliderCrank:
    crank_mm: Annotated[float, Gt(0), Le(1000)]
    rod_mm: Annotated[float, Gt(0), Le(10000)]

    def __post_init__(self):            # a relational rule: the ranges are the fields' own
        if self.rod_mm <= self.crank_mm:
            raise ModelError(f"rod_mm={self.rod_mm:g}: must be longer than crank_mm={self.crank_mm:g}",
                             key="rod_mm")

    def slider_mm(self, phi):
        """The slider's distance from the crank's centre at crank angle phi [mm]."""
        s = self.crank_mm * np.sin(phi)
        return self.crank_mm * np.cos(phi) + np.sqrt(self.rod_mm**2 - s**2)

    def warnings(self, values: dict) -> list[str]:
        ratio = self.crank_mm / self.rod_mm
        if ratio <= 1 / 3:
            return []
        return [f"crank_mm / rod_mm = {ratio:.3g} > 1/3: the rod swings {math.degrees(math.asin(ratio)):.3g} deg, "
                f"its guide's side force is large"]
'''

SOLVER = '''"""Solvers of the slider-crank: its stroke."""
import math
import time

import numpy as np

from mechopt.kit.result import Result, Status, Timing
from mechopt.kit.settings import Annotated, Interval


def stroke(task, *, samples: Annotated[int, Interval(ge=3, le=100_000)] = 361) -> Result:
    """The stroke (2 r, exactly) and the slider's travel over a crank turn."""
    start = time.perf_counter()
    phi = np.linspace(0.0, 2 * np.pi, samples)
    x = task.slider_mm(phi)
    values = {"stroke_mm": float(x.max() - x.min()),
              "rod_angle_max_deg": math.degrees(math.asin(task.crank_mm / task.rod_mm))}
    return Result(Status.SOLVED, values, Timing(0.0, time.perf_counter() - start),
                  arrays={"crank_deg": np.degrees(phi), "slider_mm": x})
'''

FIGURE = '''"""Figures (and the shop's drawing) of the slider-crank: drawn from the Result only."""
import numpy as np

from mechopt.dxf import ShopCurve, shop_drawing
from mechopt.figures.registry import figure, new_figure
from mechopt.models.cam_shape import point_table
from mechopt.solvers.slider_crank import stroke


@figure(stroke)
def travel(run):
    fig = new_figure(figsize=(6, 4))
    ax = fig.add_subplot()
    ax.plot(run.arrays["crank_deg"], run.arrays["slider_mm"])
    ax.set(xlabel="crank angle [deg]", ylabel="slider [mm]", title=run.scene.id)
    return {"travel": fig}


@shop_drawing(stroke)
def crank_circle(run):
    r = run.task.crank_mm
    table = point_table(lambda t: np.array([r * np.cos(t), r * np.sin(t)]), 0.01)
    return [ShopCurve("CRANK_PIN_CIRCLE", table.xy, table.chord_error_mm, f"crank pin, r = {r:g} mm")]
'''

BENCHMARK = '''"""The slider-crank's accuracy against time: its stroke is exact."""


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    return "slider-crank: stroke exact"
'''

SCENE = '''id = "slider-crank/stroke"
title = "Slider-crank: the stroke is twice the crank"
source = "any kinematics textbook: the slider-crank's stroke is 2 r"
task = "slider_crank.SliderCrank"
solver = "slider_crank.stroke"
effects = []

[params]
crank_mm = { value = 50.0, mark = "assumed", why = "a small press" }
rod_mm = { value = 200.0, mark = "assumed", why = "four cranks long" }

[expect.stroke_mm]
value = 100.0
abs = 1e-9
kind = "derived"
where = "2 r, the slider's extreme positions at crank angles 0 and 180 deg"
'''

# the contributor's files, by their place in the repository
FILES = {"models/slider_crank.py": MODEL, "solvers/slider_crank/__init__.py": SOLVER,
         "src/mechopt/figures/slider_crank.py": FIGURE, "benchmarks/slider_crank.py": BENCHMARK,
         "cases/slider-crank/stroke.toml": SCENE}
ROW = mechanisms.Mechanism("slider-crank", "Slider-crank (a textbook check)", ("mechopt.models.slider_crank",),
                           "mechopt.solvers.slider_crank", ("mechopt.figures.slider_crank",),
                           "mechopt.benchmarks.slider_crank", (("slider-crank", "slider-crank/stroke"),))


@pytest.fixture
def fifth(tmp_path, monkeypatch):
    """The slider-crank's files in a temporary tree (its folders joined to the packages'), its row
    added to the table; everything restored afterwards."""
    import mechopt.benchmarks
    import mechopt.figures
    import mechopt.models
    import mechopt.solvers
    tree = tmp_path / "repo"
    for where, text in FILES.items():
        (tree / where).parent.mkdir(parents=True, exist_ok=True)
        (tree / where).write_text(text, encoding="utf-8")
    for package, folder in ((mechopt.models, "models"), (mechopt.solvers, "solvers"),
                            (mechopt.figures, "src/mechopt/figures"), (mechopt.benchmarks, "benchmarks")):
        monkeypatch.setattr(package, "__path__", [*package.__path__, str(tree / folder)])
    monkeypatch.setattr(mechanisms, "MECHANISMS", (*mechanisms.MECHANISMS, ROW))
    monkeypatch.setattr(registry, "_USER_FOLDERS", [tree / "cases"])
    figures, drawings = dict(FIGURES), dict(dxf.SHOP_DRAWINGS)
    mechopt.clear_caches()
    yield tree
    mechopt.clear_caches()
    FIGURES.clear(), FIGURES.update(figures)
    dxf.SHOP_DRAWINGS.clear(), dxf.SHOP_DRAWINGS.update(drawings)
    for name in [n for n in sys.modules if n.rpartition(".")[2] == "slider_crank"]:
        del sys.modules[name]


def test_a_fifth_mechanism_is_one_row_plus_its_own_files(fifth, tmp_path, capsys):
    assert sorted(p.relative_to(fifth).as_posix() for p in fifth.rglob("*") if p.is_file()) == sorted(FILES)
    assert set(mechanisms.mechanisms()) - set(mechanisms.MECHANISMS[:-1]) == {ROW}

    assert main(["run", "slider-crank/stroke", "--plot", str(tmp_path / "figs"), "--dxf", str(tmp_path / "dxf")]) == 0
    out = capsys.readouterr().out
    assert "stroke_mm" in out and "warning" not in out
    assert (tmp_path / "figs" / "slider-crank_stroke_travel.png").is_file()
    assert "CRANK_PIN_CIRCLE" in dxf.read_polylines(tmp_path / "dxf" / "slider-crank_stroke.dxf")

    assert main(["validate", "slider-crank/stroke"]) == 0
    assert main(["describe", "slider-crank/stroke"]) == 0
    described = capsys.readouterr().out
    assert "> 0 ... 1,000" in described and "3 ... 100,000" in described    # the declared ranges

    mine = tmp_path / "mine.toml"
    assert main(["new", "slider-crank", str(mine)]) == 0
    assert main(["run", str(mine), "--set", "rod_mm=120"]) == 0
    assert "warning: crank_mm / rod_mm = 0.417 > 1/3" in capsys.readouterr().out
    run = mechopt.solve(str(mine), crank_mm=60.0)
    assert run.values["stroke_mm"] == pytest.approx(120.0, abs=1e-9)


def test_a_fifth_mechanisms_declared_ranges_hold_in_its_scenes(fifth):
    with pytest.raises(SceneError, match="crank_mm"):
        mechopt.solve("slider-crank/stroke", crank_mm=-5.0)
    with pytest.raises(mechopt.MechoptError, match="must be longer than crank_mm"):
        mechopt.solve("slider-crank/stroke", rod_mm=40.0)
