"""`mechopt new`: every template is a registry scene, copied with the files it reads; cli.py
names no template."""
import re
from pathlib import Path

import pytest

from mechopt import registry
from mechopt.cli import main
from mechopt.mechanisms import templates


@pytest.mark.parametrize("name", sorted(templates()))
def test_every_template_is_written_with_the_files_it_reads_and_loads(name, tmp_path, capsys):
    source = registry.find(templates()[name])
    own = source.path.read_text(encoding="utf-8")
    tables = re.findall(r'csv = "([^"]+)"', own)
    bases = re.findall(r'scene = "([^"]+)"', own)
    path = tmp_path / "mine.toml"
    assert main(["new", name, str(path)]) == 0, capsys.readouterr().err
    copies = {f"mine-{t.removeprefix(source.path.stem + '-')}": source.path.parent / t for t in tables}
    copies |= {f"mine-{Path(b).stem}.toml": source.path.parent / b for b in bases}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["mine.toml", *copies])
    for copy, original in copies.items():
        if copy.endswith(".csv"):         # the same rows, under the new scene's name
            assert (tmp_path / copy).read_text(encoding="utf-8") == original.read_text(encoding="utf-8")
        else:                             # a base: the user's scene now, read from beside the new one
            assert registry.find(str(tmp_path / copy)).params() == registry.find(str(original)).params()
            assert f'scene = "{copy}"' in path.read_text(encoding="utf-8")
    mine = registry.find(str(path))
    assert mine.id == "my/mine" and mine.params() == source.params()
    assert str(registry.cases_dir()) not in path.read_text(encoding="utf-8")       # nothing read from the package


def test_the_command_line_names_no_template():
    text = (Path(__file__).parents[2] / "src" / "mechopt" / "cli.py").read_text(encoding="utf-8")
    assert not [n for n in templates() if f'"{n}"' in text]
