"""Bad input is refused when the scene is loaded or the override given, before any work, with
one line naming the file, the key and what is allowed; the scene is left as it was."""
import pytest

from mechopt import registry
from mechopt.kit.errors import SceneError
from mechopt.scene import load


def scene_file(tmp_path, case_id, old, new):
    path = tmp_path / "bad.toml"
    text = registry.find(case_id).path.read_text(encoding="utf-8")
    assert old in text, old
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


@pytest.mark.parametrize("case_id, old, new, match", [
    ("press/kd2322", "tol = 1e-10", "tol = 0", r"bad\.toml: solver_settings\.tol=0: allowed > 0 \.\.\. 0\.1"),
    ("press/kd2322", "tol = 1e-10", "tol = nan", r"solver_settings\.tol=nan: expected a finite number"),
    ("press/kd2322", "samples = 60", "samples = 1000000", r"solver_settings\.samples=1000000: allowed 1 \.\.\. 10,000"),
    ("press/kd2322", "samples = 60", "samples = 6.5", r"solver_settings\.samples=6\.5: expected int"),
    ("loom/group1", 'value = "SOLVED"', 'value = "SOLVD"', r"status 'SOLVD' is not a status word; allowed: SOLVED, INACCURATE"),
    ("loom/group1", "value = 36.0 ", "value = inf ", r"expect\.t_3_7_deg: .*value = inf: expected a finite number"),
    ("loom/group1", "amplitude_limit_mm = { value = 0.1,", "amplitude_limit_mm = { value = inf,",
     r"params\.amplitude_limit_mm: .*expected a finite number"),
])
def test_a_bad_value_in_a_scene_file_is_refused_at_load(tmp_path, case_id, old, new, match):
    with pytest.raises(SceneError, match=match):
        load(scene_file(tmp_path, case_id, old, new))


@pytest.mark.parametrize("case_id, overrides, match", [
    ("cam-cutter/minimax", {"max_rounds": 0}, r"solver_settings\.max_rounds=0: allowed 1 \.\.\. 10,000"),
    ("cam-cutter/minimax", {"count": 10**8}, r"solver_settings\.count=100000000: allowed 2 \.\.\. 1,000,000"),
    ("cam-cutter/minimax", {"a_mm": float("inf")}, r"params\.a_mm=inf: expected a finite number"),
    ("press/kd2322", {"duration_s": 1.0}, r"duration_s: unknown key"),
    ("loom/group1", {"tol_deg": -1.0}, r"solver_settings\.tol_deg=-1\.0: allowed > 0"),
    ("loom/machine", {"operations[from=10.1,to=99].min_deg": 5.0}, r"matches 0 entries of 'operations', not one"),
    ("cam-cutter/readjustable", {"a_count": 2.5}, r"params\.a_count=2\.5: expected a whole number"),
    ("cam-cutter/readjustable", {"a_min_mm": 26.0}, r"params\.a_max_mm=25\.1: allowed >= a_min_mm=26"),
    ("cam-cutter/readjustable", {"h_values_mm": [2.0, 30.0]}, r"structure\.h_values_mm=\[2\.0, 30\.0\]: allowed each >= 0 and < a_min_mm"),
    ("cam-cutter/readjustable", {"h_values_mm": [2.0, 2.0]}, r"h_values_mm=.*must not repeat a value"),
    ("cam-cutter/readjustable", {"count": 5}, r"solver_settings\.count=5: allowed 20 \.\.\. 100,000"),
    ("cam-cutter/other-profile", {"x_expr": "__import__('os')"}, r"structure\.x_expr=.*is not allowed"),
    ("cam-cutter/other-profile", {"constants.B_mm.value": "wide"}, r"constants\.B_mm='wide': expected a finite number"),
    ("cam-cutter/other-profile", {"placement": "centred"}, r"placement='centred': allowed start_at_origin, as_given"),
    ("cam-cutter/other-profile", {"t1_rad": -1.0}, r"params\.t1_rad=-1\.0: allowed > t0_rad=0"),
    # each input in range, together a lever of 56 MHz: refused at once (it ran past a minute before)
    ("stop-impact/rebound-177rpm", {"b_mm": 1e-3}, r"params\.b_mm: f_free_Hz = 5\.635e\+07 Hz .* above 100000 Hz"),
])
def test_a_bad_override_is_refused_before_work_and_changes_nothing(case_id, overrides, match):
    scene = registry.find(case_id)
    before = (scene.params(), scene.settings(), dict(scene.spec.structure))
    with pytest.raises(SceneError, match=match):
        registry.run(scene, overrides)
    assert (scene.params(), scene.settings(), dict(scene.spec.structure)) == before


def test_a_scene_file_that_is_no_text_is_named(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes('title = "Kurbelpresse für Dichtungen"'.encode("latin-1"))
    with pytest.raises(SceneError, match=r"latin1\.toml: not UTF-8 text"):
        load(path)
    with pytest.raises(SceneError, match=r"a folder, not a scene file"):
        load(tmp_path)
