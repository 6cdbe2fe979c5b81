"""Every check carries a verdict; a declared miss is shown and counted, and flagged when it starts to pass."""
import json
from pathlib import Path

import pytest

from mechopt import registry, verdicts
from mechopt.cli import main
from mechopt.kit.errors import SceneError

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


# -- verdicts counted once: rows that restate the status, readings that exclude each other ---------

FOLLOWS = '''[expect.c_free_N_per_mm]
value = 2848.3
rel = 1e-3
kind = "follows"
where = "restates the status: a made-up row"
'''


def test_a_row_that_restates_the_status_follows_and_is_counted_apart(tmp_path, capsys):
    scene = _scene(tmp_path, FOLLOWS)
    run = registry.run(scene)
    row = next(c for c in run.checks if c.name == "c_free_N_per_mm")
    assert row.verdict == "follows" and row.ok and row.label == "follows"
    assert "1 follows" in verdicts.summary_line(run.checks)
    assert main(["validate", str(scene.path)]) == 0 and ", 1 follows" in capsys.readouterr().out


def test_a_constraint_the_nlp_holds_follows_though_its_base_calibrated_it():
    """press/motor-design frees the gear ratio that press/kd2322 fits to omega = 25 rad/s and holds
    omega = 25 as a constraint: the row follows from the status, it is no calibration."""
    scene = registry.find("press/motor-design")
    row = scene.spec.expect["omega_mean_rad_s"]
    assert "omega_mean_rad_s" in verdicts.calibrated_on(scene.spec)          # the base's calibration is still inherited
    assert row.kind == "follows" and verdicts.verdict_of(row, True, calibrated=True) == "follows"


def test_of_two_readings_that_exclude_each_other_one_counts_and_the_other_is_an_alternative(capsys):
    chosen, other = "stop-impact/rebound-177rpm-paper-reading", "stop-impact/rebound-177rpm-restitution-paper-reading"
    checks = {(run.scene.id, c.name): c for run in map(registry.run, (chosen, other)) for c in run.checks}
    assert checks[chosen, "rebound_experiment_mm_177"].verdict == "reproduced"
    alternative = checks[other, "rebound_mm_177"]
    assert alternative.verdict == "alternative" and alternative.ok and alternative.alternative_to == chosen
    assert alternative.label == f"alternative (the reading taken: {chosen})"
    line = verdicts.summary_line(checks.values())
    assert "1 reproduced (1 with readings chosen after the figure)" in line and "1 alternative" in line
    assert main(["validate", chosen, other]) == 0
    assert "alternative reading, not counted as reproduced: rebound_mm_177" in capsys.readouterr().out


def test_a_variant_carries_its_base_readings_unless_a_row_names_its_own():
    base = registry.find("stop-impact/rebound-paper-reading").spec.expect["rebound_mm_280"].readings_after_figure
    variant = registry.find("stop-impact/rebound-177rpm-paper-reading").spec.expect
    assert base and variant["rebound_experiment_mm_177"].readings_after_figure == base
    assert variant["status"].readings_after_figure == []                   # a derived row has no readings
    own = registry.find("stop-impact/rebound-177rpm-restitution-paper-reading").spec.expect["rebound_mm_177"]
    assert own.readings_after_figure[-1] == "launch = restitution" and len(own.readings_after_figure) == 2


@pytest.mark.parametrize("extra, words", [
    ('kind = "follows"\nverdict = "not_reproduced"\nreason = "x"\n',
     "verdict is for a figure of the source .* not a follows"),
    ('kind = "derived"\nalternative_to = "stop-impact/frequencies"\n', "alternative_to is for a figure of the source"),
    ('kind = "published"\nalternative_to = "stop-impact/frequencies"\nverdict = "not_reproduced"\nreason = "x"\n',
     "a declared miss .* has no alternative reading"),
])
def test_follows_and_alternative_rows_are_refused_where_they_mean_nothing(tmp_path, extra, words):
    text = '[expect.c_free_N_per_mm]\nvalue = 330.0\nrel = 0.05\nwhere = "x"\n' + extra
    with pytest.raises(SceneError, match=words):
        _scene(tmp_path, text)


def test_an_alternative_to_no_scene_is_named_and_the_file_left_out(tmp_path, monkeypatch):
    folder = tmp_path / "mine"
    folder.mkdir()
    text = SOURCE.read_text(encoding="utf-8").replace('id = "stop-impact/frequencies"', 'id = "mine/frequencies"')
    row = ('[expect.c_free_N_per_mm]\nvalue = 2848.3\nrel = 1e-3\nkind = "published"\nwhere = "x"\n'
           'alternative_to = "stop-impact/frequences"\n')
    (folder / "frequencies.toml").write_text(text + "\n" + row, encoding="utf-8")
    monkeypatch.setenv(registry.ENV_CASES, str(folder))
    found = registry.catalogue()
    assert "mine/frequencies" not in {s.id for s in found.scenes}
    assert any("expect.c_free_N_per_mm.alternative_to = 'stop-impact/frequences': no such scene; did you mean "
               "stop-impact/frequencies" in p for p in found.problems)
