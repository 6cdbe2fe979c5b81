"""The guide for a new mechanism (docs/new-mechanism.md), followed in a test: a slider-crank is
added as a contributor would, as one row of `mechopt.mechanisms` plus its own files (a model with
declared ranges and warnings, a solver, a scene, a figure, a DXF writer, a benchmark), written
into a temporary tree; run, validate, new, describe and --dxf then work with it."""
import re
import sys
from pathlib import Path

import pytest

import mechopt
from mechopt import dxf, mechanisms, registry
from mechopt.cli import main
from mechopt.figures.registry import FIGURES
from mechopt.kit.errors import SceneError

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "new-mechanism.md"


def guide_files() -> dict[str, str]:
    """The contributor's files as the guide gives them: each code block whose first line is a
    comment naming a file of the repository (`# models/slider_crank.py`), by that place."""
    files = {}
    for block in re.findall(r"```(?:python|toml)\n(.*?)```", GUIDE.read_text(encoding="utf-8"), re.S):
        first = block.splitlines()[0]
        if re.fullmatch(r"# [\w/.-]+\.(py|toml)", first):
            files[first[2:]] = block
    return files


FILES = guide_files()
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


def test_the_guide_gives_every_file_of_the_mechanism():
    assert sorted(FILES) == ["benchmarks/slider_crank.py", "cases/slider-crank/stroke.toml", "models/slider_crank.py",
                             "solvers/slider_crank/__init__.py", "src/mechopt/figures/slider_crank.py"]


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
    from mechopt.models.slider_crank import SliderCrank
    with pytest.raises(mechopt.ModelError, match=r"crank_mm=-5\.0: allowed > 0 \.\.\. 1,000") as caught:
        SliderCrank(crank_mm=-5.0, rod_mm=200.0)           # from Python too, by the same declared range
    assert caught.value.key == "crank_mm"
