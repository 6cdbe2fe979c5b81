"""The documentation site: it builds strictly, its generated page is complete, its tutorials run.

A code block is run when the line before its fence is `<!-- runnable -->`; a page's runnable
blocks run in order in one temporary folder (```bash with `bash -e`, ```python in this process),
so a later block sees the files an earlier one wrote. A ```text block right after a
runnable one is what it prints (its last lines): the page quotes the code, and the test holds it to that.
"""
import contextlib
import importlib.util
import io
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
MARK = "<!-- runnable -->"
FENCE = re.compile(r"^(`{3,})(\w+)[^\n]*\n(.*?)^\1\s*$", re.S | re.M)
PAGES_WITH_CODE = sorted(p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md") if MARK in p.read_text("utf-8"))


def runnable_blocks(text: str) -> list[tuple[str, str, str | None]]:
    """(language, code, printed output or None) of every fenced block whose preceding line is the mark."""
    fences, blocks = list(FENCE.finditer(text)), []
    for match, after in zip(fences, fences[1:] + [None]):
        if text[:match.start()].rstrip("\n").rsplit("\n", 1)[-1].strip() != MARK:
            continue
        output = after is not None and after[2] == "text" and not text[match.end():after.start()].strip()
        blocks.append((match[2], match[3], after[3] if output else None))
    return blocks


def environment():
    """This interpreter's bin folder first, so `mechopt` and `python` are the tested ones."""
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg", NO_MKDOCS_2_WARNING="1")
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    return env


def checkout_files():
    return sorted(p for p in ROOT.rglob("*") if ".git" not in p.parts and "__pycache__" not in p.parts)


def load_hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "tools" / "docs_hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_runnable_blocks_are_found_only_after_the_mark():
    text = (f"{MARK}\n```bash\necho one\n```\n\n```bash\necho two\n```\n{MARK}\n```python\nprint(3)\n```\n\n"
            "```text\n3\n```\nthen\n```text\nnot an output\n```\n")
    assert runnable_blocks(text) == [("bash", "echo one\n", None), ("python", "print(3)\n", "3\n")]


def test_every_tutorial_has_runnable_code_and_every_mark_a_block():
    for page in sorted((DOCS / "tutorials").glob("*.md")):
        text = page.read_text("utf-8")
        assert runnable_blocks(text), f"{page.name}: no runnable block"
        assert len(runnable_blocks(text)) == text.count(MARK), f"{page.name}: a {MARK} not followed by a fence"


def run_python(code: str) -> str:
    """A python block in this process (mechopt is imported once for every page): what it printed."""
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(code, "<docs block>", "exec"), {"__name__": "__main__"})
    return printed.getvalue()


@pytest.mark.parametrize("page", PAGES_WITH_CODE)
def test_page_code_runs(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for number, (language, code, output) in enumerate(runnable_blocks((DOCS / page).read_text("utf-8")), 1):
        where = f"{page}, block {number} ({language}):\n{code}"
        if language == "python":
            printed = run_python(code)
        else:
            done = subprocess.run(["bash", "-e", "-c", code], env=environment(), capture_output=True, text=True,
                                  timeout=600)
            printed = done.stdout
            assert done.returncode == 0, f"{where}\n{done.stdout}\n{done.stderr}"
        if output is not None:
            assert output.strip() in printed, f"{where}\n{printed}"


def test_scene_reference_has_every_scene_with_its_declared_keys():
    import mechopt
    page = load_hooks().scene_reference()
    for scene in mechopt.scenes():
        assert f"### `{scene.id}`" in page
    kd2322 = page.split("### `press/kd2322`")[1].split("### ")[0]
    row = next(line for line in kd2322.splitlines() if line.startswith("| flywheel_inertia_kgm2 |"))
    assert "| kg m² | assumed |" in row


def test_scenes_sharing_a_cases_folder_are_titled_under_the_row_of_their_solver():
    """cases/loom/ holds two rows' scenes: the cyclogram wing's (task and solver cyclogram.*) under
    its title, the loom's (loom.*) under the loom's."""
    from mechopt.mechanisms import mechanisms
    titles = {m.name: m.title for m in mechanisms()}
    sections = {s.split("\n")[0]: s for s in load_hooks().scene_reference().split("\n## ")[1:]}
    wing, loom = sections[titles["cyclogram"]], sections[titles["loom"]]
    for scene in ("packaging", "recurrent-indexer", "recurrent-maxplus", "recurrent-tasks", "turret-die-overlap",
                  "turret-die-speed"):
        assert f"### `loom/{scene}`" in wing and f"### `loom/{scene}`" not in loom
    assert "### `loom/group1`" in loom and "### `loom/group1`" not in wing


def test_a_cell_escapes_pipes_and_cuts_long_values():
    cell = load_hooks().cell
    assert cell("HIGHS | CLARABEL") == "HIGHS \\| CLARABEL"
    assert cell("x" * 200).endswith("…") and len(cell("x" * 200)) == 70


def test_site_builds_strictly_outside_the_checkout(tmp_path):
    pytest.importorskip("mkdocstrings", reason="the docs extra (pip install '.[test]' includes it)")
    before = checkout_files()
    build = [sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-f", str(ROOT / "mkdocs.yml"),
             "-d", str(tmp_path / "site")]
    done = subprocess.run(build, env=environment(), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "site" / "reference" / "scenes" / "index.html").exists()
    assert checkout_files() == before
    # read offline, the equations are MathML written at build time: no script from a CDN, no raw TeX
    pages = {p.relative_to(tmp_path / "site").as_posix(): p.read_text("utf-8")
             for p in (tmp_path / "site").rglob("*.html")}
    assert not [name for name, text in pages.items() if re.search(r"<(script|link)[^>]+(src|href)=\"https?://", text)]
    guides = {name: text for name, text in pages.items() if name.startswith("guide/")}
    assert len(guides) == 5 and all("<math " in text for text in guides.values())
    assert not [name for name, text in guides.items() if "\\(" in text or "\\[" in text]


def test_usage_lists_every_template_of_mechopt_new():
    from mechopt.mechanisms import templates
    line = next(x for x in (DOCS / "usage.md").read_text("utf-8").splitlines() if x.startswith("mechopt new "))
    listed = line.split("to start from:", 1)[1].split(",")
    assert sorted(name.strip() for name in listed) == sorted(templates())


def test_every_tutorial_is_linked_from_the_home_page_and_in_the_nav():
    home, nav = (DOCS / "index.md").read_text("utf-8"), (ROOT / "mkdocs.yml").read_text("utf-8")
    for page in sorted((DOCS / "tutorials").glob("*.md")):
        assert f"(tutorials/{page.name})" in home, page.name
        assert f"- tutorials/{page.name}" in nav, page.name


def test_every_guide_is_linked_from_the_home_page_and_in_the_nav():
    """A guide page the site builds but no one reaches (the cyclogram wing's once had none)."""
    home, nav = (DOCS / "index.md").read_text("utf-8"), (ROOT / "mkdocs.yml").read_text("utf-8")
    guides = sorted((DOCS / "guide").glob("*.md"))
    assert "cyclogram.md" in [page.name for page in guides]
    for page in guides:
        assert f"(guide/{page.name})" in home, page.name
        assert f"- guide/{page.name}" in nav, page.name


def test_the_cyclogram_tutorial_names_the_template_for_a_machine_of_ones_own():
    """It once waited for a template that `mechopt new cyclogram` has since written."""
    from mechopt.mechanisms import templates
    assert "cyclogram" in templates()
    text = (DOCS / "tutorials" / "own-cyclogram.md").read_text("utf-8")
    assert "`mechopt new cyclogram`" in text and "arrives" not in text
