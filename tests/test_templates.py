"""`mechopt new`: every template is a registry scene, copied with the files it reads; cli.py
names no template."""
import re
from pathlib import Path

import pytest

from mechopt import registry
from mechopt.cli import main
from mechopt.mechanisms import templates


@pytest.mark.parametrize("name", sorted(templates()))
def test_every_template_is_written_with_its_tables_and_loads(name, tmp_path, capsys):
    source = registry.find(templates()[name])
    tables = re.findall(r'csv = "([^"]+)"', source.path.read_text(encoding="utf-8"))
    path = tmp_path / "mine.toml"
    assert main(["new", name, str(path)]) == 0, capsys.readouterr().err
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written == sorted(["mine.toml", *(f"mine-{t.removeprefix(source.path.stem + '-')}" for t in tables)])
    for table in tables:              # the same rows, under the new scene's name
        copy = tmp_path / f"mine-{table.removeprefix(source.path.stem + '-')}"
        assert copy.read_text(encoding="utf-8") == (source.path.parent / table).read_text(encoding="utf-8")
    mine = registry.find(str(path))
    assert mine.id == "my/mine" and mine.params() == source.params()


def test_the_command_line_names_no_template():
    text = (Path(__file__).parents[1] / "src" / "mechopt" / "cli.py").read_text(encoding="utf-8")
    assert not [n for n in templates() if f'"{n}"' in text]
