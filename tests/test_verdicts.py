"""Every check carries a verdict; a declared miss is shown and counted, and flagged when it starts to pass."""
import json
from pathlib import Path

import pytest

from mechopt import registry
from mechopt.cli import main
from mechopt.errors import SceneError

SOURCE = Path(registry.find("stop-impact/frequencies").path)


def _scene(tmp_path, extra):
    text = SOURCE.read_text(encoding="utf-8").replace('id = "stop-impact/frequencies"', 'id = "mine/frequencies"')
    path = tmp_path / "frequencies.toml"
    path.write_text(text + "\n" + extra, encoding="utf-8")
    return registry.find(str(path))


MISS = '''[expect.contact_time_ms]
value = 9.0
rel = 0.05
kind = "experimental"
where = "a made-up figure"
verdict = "{verdict}"
reason = "the test declares it missed"
'''


def test_a_declared_miss_is_shown_with_its_gap_and_does_not_fail(tmp_path):
    scene = _scene(tmp_path, MISS.format(verdict="not_reproduced").replace("contact_time_ms", "c_free_N_per_mm")
                   .replace("value = 9.0", "value = 3164.8"))
    run = registry.run(scene)
    check = {c.name: c for c in run.checks}
    miss = check["c_free_N_per_mm"]
    assert miss.verdict == "not_reproduced" and miss.ok and run.ok
    assert miss.gap == pytest.approx((2848.3 - 3164.8) / 3164.8, rel=1e-4)   # the model's own 2848.3 N/mm
    assert miss.label.startswith("not reproduced (-10.0%")


def test_a_declared_miss_that_passes_is_flagged(tmp_path):
    scene = _scene(tmp_path, MISS.format(verdict="not_reproduced").replace("contact_time_ms", "c_free_N_per_mm")
                   .replace("value = 9.0", "value = 2848.3"))
    run = registry.run(scene)
    miss = next(c for c in run.checks if c.name == "c_free_N_per_mm")
    assert miss.verdict == "unexpectedly_reproduced" and not miss.ok and not run.ok


def test_a_declared_miss_that_is_not_computed_is_a_failure(tmp_path):
    run = registry.run(_scene(tmp_path, MISS.format(verdict="not_reproduced")))
    miss = next(c for c in run.checks if c.name == "contact_time_ms")
    assert miss.verdict == "failed" and not run.ok


def test_not_reproducible_is_counted_and_listed_first(tmp_path, capsys):
    scene = _scene(tmp_path, MISS.format(verdict="not_reproducible"))
    out = tmp_path / "v.json"
    assert main(["validate", str(scene.path), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    table = [line for line in printed.splitlines() if line.startswith("mine/frequencies")]
    first_kept = next(i for i, line in enumerate(table) if "not reproduc" not in line)
    assert any("not reproducible" in line for line in table[:first_kept])     # the misses first
    assert "1 not reproducible" in printed and "the test declares it missed" in printed
    checks = json.loads(out.read_text())[0]["checks"]
    assert {c["name"]: c["verdict"] for c in checks}["contact_time_ms"] == "not_reproducible"


@pytest.mark.parametrize("extra, words", [
    ('verdict = "not_reproduced"\n', "'reason' goes with a declared verdict"),
    ('reason = "no verdict"\n', "'reason' goes with a declared verdict"),
])
def test_a_verdict_and_its_reason_go_together(tmp_path, extra, words):
    text = '[expect.c_free_N_per_mm]\nvalue = 330.0\nrel = 0.05\nkind = "published"\nwhere = "x"\n' + extra
    with pytest.raises(SceneError, match=words):
        _scene(tmp_path, text)
