"""The examples in the package's docstrings run as written and print what they say.

They are run here, module by module under the package's import names (`mechopt.models.cam_law`,
not `models.cam_law`: the root folders are subpackages of mechopt, see setup.py), rather than by
`--doctest-modules`, which would import the root folders by their bare names. A module is collected
when its source holds an example, so a new example is run without being listed."""
import doctest
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# import name -> folder, as setup.py maps them
FOLDERS = {"mechopt": ROOT / "src" / "mechopt", "mechopt.models": ROOT / "models", "mechopt.solvers": ROOT / "solvers"}


def modules_with_examples():
    names = []
    for package, folder in FOLDERS.items():
        for path in sorted(folder.rglob("*.py")):
            if ">>> " in path.read_text(encoding="utf-8"):
                parts = path.relative_to(folder).with_suffix("").parts
                parts = parts[:-1] if parts[-1] == "__init__" else parts
                names.append(".".join((package, *parts)))
    return names


def test_the_examples_are_found():
    names = modules_with_examples()
    assert {"mechopt.figures.text", "mechopt.models.cam_law", "mechopt.solvers.press"} <= set(names)


@pytest.mark.parametrize("name", modules_with_examples())
def test_a_modules_examples_run_as_written(name, solved_once):
    module = importlib.import_module(name)
    examples = [t for t in doctest.DocTestFinder().find(module, name) if t.examples]
    assert examples, f"{name}: no example found by doctest"
    report = []
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in examples:
        runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)
