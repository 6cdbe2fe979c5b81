"""mkdocs hooks (mkdocs.yml, `hooks:`): the scene-key page, and the package laid out for griffe.

* The generated page: every registry scene's keys, from `mechopt.describe`, added to the build in
  memory, so the checkout is never written to. `python tools/docs_hooks.py` prints the same Markdown.
* mkdocstrings reads the source with griffe, which finds a package by its folder; mechopt's
  subpackages live beside src/ (the package-dir mapping puts models/ at mechopt.models, ...). The
  layout as imported is mirrored with symlinks in a temporary folder searched first.
"""
import atexit
import importlib.util
import shutil
import sys
import tempfile
from pathlib import Path

from mechopt import describe, scenes
from mechopt.mechanisms import mechanisms

PAGE = "reference/scenes.md"
COLUMNS = ("key", "kind", "unit", "mark", "range", "value", "why")
LONGEST = 70            # a structure value (a whole network) is cut here: `mechopt describe` shows it all


def cell(text) -> str:
    """One table cell: pipes escaped, newlines flattened, long values cut."""
    text = " ".join(str(text).split())
    if len(text) > LONGEST:
        text = text[:LONGEST - 1] + "…"
    return text.replace("|", "\\|") or " "


def scene_table(rows) -> list[str]:
    """The describe rows as a Markdown table, with the columns describe gives (`why` when present)."""
    columns = [c for c in COLUMNS if any(c in row for row in rows)]
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(cell(row.get(c, "")) for c in columns) + " |" for row in rows]
    return lines


def row_of(scene, rows) -> str:
    """The row (its name) a scene belongs to: the one whose solver package its `solver` names
    (`cyclogram.plan_cyclogram` the cyclogram wing's, `loom.repair_cyclogram` the loom's), so that
    two rows sharing a cases folder (the cyclogram's scenes live in cases/loom/) each title their
    own; a solver no row names falls back to the scene id's folder."""
    package = scene.spec.solver.rpartition(".")[0].removeprefix("mechopt.solvers.").partition(".")[0]
    return next((m.name for m in rows if m.solvers.rpartition(".")[2] == package), scene.id.split("/")[0])


def scene_reference() -> str:
    """The page: one section per mechanism (in the table's order), one table per scene."""
    out = ["# Scene keys", "",
           "Every key a scene of the registry lets you change (in the file, with `--set KEY=VALUE` or as a",
           "keyword of `mechopt.solve`), generated from `mechopt.describe` when the site is built: its unit",
           "(read from the key's name), its mark (given, assumed, calibrated, derived, default; a solver",
           "setting is `scene` or `default`), the allowed range declared on the model or solver, and the",
           "scene's value. `mechopt describe SCENE` prints the same table for any scene, yours included.", ""]
    rows = {m.name: m for m in mechanisms()}          # section titles and order, from the one table
    by_mechanism = {name: [] for name in rows}
    for scene in scenes():
        by_mechanism.setdefault(row_of(scene, rows.values()), []).append(scene)
    for mechanism, members in ((name, members) for name, members in by_mechanism.items() if members):
        row = rows.get(mechanism)
        out += [f"## {row.title if row else mechanism}", ""]
        if row and row.folder != row.name:            # a wing whose scenes live in another row's folder
            out += [f"Its scenes live in `cases/{row.folder}/` (ids `{row.folder}/...`).", ""]
        for scene in members:
            spec = scene.spec
            out += [f"### `{scene.id}`", "", f"{spec.title}", "",
                    f"Task `{spec.task}`, solver `{spec.solver}`, effects: "
                    + (", ".join(f"`{e}`" for e in spec.effects) or "none") + ".", ""]
            out += scene_table(describe(scene)) + [""]
    return "\n".join(out)


ROOT = Path(__file__).resolve().parent.parent


def mirror_package(root: Path) -> Path:
    """A temporary folder holding `mechopt/` as imported: its own folder's entries, and each folder
    of the repository that Python imports as a subpackage (mechopt.models from models/, ...)."""
    import mechopt
    folder = Path(tempfile.mkdtemp(prefix="mechopt-docs-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    top = folder / "mechopt"
    top.mkdir()
    for entry in Path(mechopt.__file__).parent.iterdir():
        (top / entry.name).symlink_to(entry)
    for sub in sorted(p for p in root.iterdir() if (p / "__init__.py").is_file()):
        spec = importlib.util.find_spec(f"mechopt.{sub.name}")
        if spec and spec.origin and Path(spec.origin).parent.resolve() == sub.resolve():
            (top / sub.name).symlink_to(sub)
    return folder


def on_startup(command, dirty):
    """Before mkdocstrings makes its first griffe loader: the mirrored package leads the search."""
    sys.path.insert(0, str(mirror_package(ROOT)))


def on_files(files, config):
    """mkdocs hook: add the generated page to the build (in memory)."""
    from mkdocs.structure.files import File  # here: the page itself needs no mkdocs (tests read it)
    files.append(File.generated(config, PAGE, content=scene_reference()))
    return files


if __name__ == "__main__":
    print(scene_reference())
