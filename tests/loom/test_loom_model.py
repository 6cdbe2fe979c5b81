"""The loom cyclogram model (paper 004, Podgorny et al. 2018): the loom's scenes as networks, their
errors named, the stress and amplitude laws (the network's own checks: tests/cyclogram/test_network.py).
Published: a(3,7) = -0.003 t(3,7) + 0.208 mm, limit 0.1 mm (Results and discussion; Research methodology)."""
import dataclasses

import networkx as nx
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mechopt import registry
from mechopt.kit.errors import ModelError, SceneError
from mechopt.models.loom_limits import amplitude_bound_deg, amplitude_mm, stress_bound_deg, stress_MPa
from mechopt.scene import load
from mechopt.solvers.cyclogram import least_cycle_time

SLOPE_MM_PER_DEG, INTERCEPT_MM, LIMIT_MM = -0.003, 0.208, 0.1      # Podgorny et al. (2018), Results and discussion; Research methodology


def test_published_amplitude_law_gives_36_deg_at_the_transfer_accuracy():
    bound = amplitude_bound_deg(SLOPE_MM_PER_DEG, INTERCEPT_MM, LIMIT_MM)
    assert bound == pytest.approx((0.208 - 0.1) / 0.003, rel=1e-12) == pytest.approx(36.0)
    assert amplitude_mm(SLOPE_MM_PER_DEG, INTERCEPT_MM, bound) == pytest.approx(LIMIT_MM, abs=1e-15)
    assert amplitude_mm(SLOPE_MM_PER_DEG, INTERCEPT_MM, 0.0) == INTERCEPT_MM


def test_stress_bound_exact_meets_the_limit_and_falls_as_one_over_t():
    assert stress_MPa(900.0, 30.0, 60.0) == pytest.approx(450.0)      # sigma ~ 1/t: double t, half sigma
    t = stress_bound_deg(900.0, 30.0, 800.0, "exact")
    assert t == pytest.approx(33.75) and stress_MPa(900.0, 30.0, t) == pytest.approx(800.0)
    assert stress_bound_deg(900.0, 30.0, 800.0, "linear") == pytest.approx(30.0 * (2 - 800 / 900))
    with pytest.raises(ModelError, match=r"stress_form='quadratic': allowed exact, linear"):
        stress_bound_deg(900.0, 30.0, 800.0, "quadratic")


@settings(max_examples=50, deadline=None)
@given(sigma_ref=st.floats(100, 2000), t_ref=st.floats(1, 180), sigma_H=st.floats(100, 2000))
def test_tangent_bound_never_exceeds_the_exact_bound(sigma_ref, t_ref, sigma_H):
    # sigma_max = K/t is convex: its tangent lies below, so the linear bound is looser (smaller)
    exact = stress_bound_deg(sigma_ref, t_ref, sigma_H, "exact")
    linear = stress_bound_deg(sigma_ref, t_ref, sigma_H, "linear")
    assert linear <= exact + 1e-9 * exact
    if abs(sigma_H - sigma_ref) < 1e-9 * sigma_ref:
        assert linear == pytest.approx(exact)


def test_group1_scene_builds_the_network_with_groups_and_published_law():
    task, _ = registry.find("loom/group1").build()
    assert isinstance(task.graph, nx.DiGraph) and task.graph.number_of_nodes() == 10
    assert task.graph.edges["3", "7"]["amplitude"] == "linear" and task.first_event == "1" and task.last_event == "10"
    assert (task.amplitude_slope_mm_per_deg, task.amplitude_intercept_mm, task.amplitude_limit_mm) == \
        (SLOPE_MM_PER_DEG, INTERCEPT_MM, LIMIT_MM)
    lb, why = task.lower_bounds_deg("exact")
    k = task.arcs.index(("3", "7"))
    assert lb[k] == pytest.approx(36.0) and why[k] == "amplitude"
    k = task.arcs.index(("9", "10"))
    assert lb[k] == pytest.approx(900.0 * 30.0 / 800.0) and why[k] == "contact_stress"


def test_machine_groups_are_subgraphs():
    task, _ = registry.find("loom/machine").build()
    assert set(task.groups) == {"group1", "group2", "flight", "sley"}
    g1 = task.group_graph("group1")
    assert set(g1.nodes) == {str(k) for k in range(1, 11)} and g1.number_of_edges() == 11
    with pytest.raises(ModelError, match=r"group='group9': no such group; known: group1"):
        task.group_graph("group9")


def test_every_scene_entry_marked_assumed_says_why():
    # honesty: the reconstructed network carries its reasoning with it
    for case in ("loom/group1", "loom/machine"):
        task, _ = registry.find(case).build()
        for op in task.operations:
            assert op.get("mark") == "assumed" and op["why"].strip(), op


def test_bad_scene_network_is_refused_naming_file_and_key(tmp_path):
    good = registry.cases_dir() / "loom" / "group1.toml"
    bad = tmp_path / "bad.toml"
    bad.write_text(good.read_text().replace('from = "9"\nto = "10"', 'from = "9"\nto = "99"'))
    with pytest.raises(SceneError, match=r"bad\.toml: structure\.operations\[9->99\]: operations\[9->99\]: unknown event '99'"):
        load(bad)


@pytest.mark.parametrize("override, match", [
    ({"windows": 1.0}, r"machine\.toml: params\.windows: windows: expected a list of tables, got 1\.0"),
    ({"operations[from=12,to=13].min_deg": 1e300}, r"operations\[12->13\]\.min_deg=1e\+300: a minimum phase angle"),
    ({"sigma_H_limit_MPa": 1e-300}, r"its contact_stress bound .* is outside the allowed \+-1e\+06 deg"),
])
def test_a_bad_override_of_the_machine_is_one_error_naming_the_key(override, match):
    with pytest.raises(SceneError, match=match):
        registry.run(registry.find("loom/machine"), override)


def test_a_selector_by_one_key_picks_its_one_operation_and_a_malformed_one_is_refused():
    """`--set 'operations[from=9].min_deg=50'` (one key, one matching operation) works as documented;
    a part without '=' or a key no operation has is refused, naming the allowed form."""
    from mechopt.scene import parse_overrides
    scene = registry.find("loom/group1")
    task, _ = scene.build(parse_overrides(["operations[from=9].min_deg=50"]))
    assert task.min_angles_deg()[task.arcs.index(("9", "10"))] == 50.0
    assert scene.build()[0].min_angles_deg()[task.arcs.index(("9", "10"))] == 30.0       # the file is intact
    for pair, match in (("operations[9].min_deg=50", r"'9' is not key=value; allowed: operations\[from=1,to=2\]"),
                        ("operations[form=9].min_deg=50", r"'form' is no key of its entries \(they have from, to"),
                        ("operations[from=99].min_deg=50", r"matches 0 entries .*none has those values")):
        with pytest.raises(SceneError, match=match):
            scene.build(parse_overrides([pair]))


def test_a_stress_bound_does_not_enter_a_time_based_cycle():
    task = registry.find("loom/group1").build()[0]
    assert task.stress_arcs()       # the loom's group 1 names stress models: a duration makes it time-based
    first, second = task.arcs[0]
    timed = dataclasses.replace(task, operations=[dict(o) | ({"min_ms": 5.0} if (str(o["from"]), str(o["to"])) ==
                                                              (first, second) else {}) for o in task.operations],
                                speed_rpm=None)
    with pytest.raises(ModelError, match=r"\.stress: the least cycle time of a time-based network"):
        least_cycle_time(timed)


def test_group1_from_its_csv_is_group1():
    csv_run, toml_run = (registry.run(registry.find(i)) for i in ("loom/group1-csv", "loom/group1"))
    assert csv_run.result.values["span_deg"] == pytest.approx(toml_run.result.values["span_deg"], abs=1e-12)
    task = csv_run.task
    assert task.events["7"] == {"group": "group1", "mechanism": "microshuttle lift"}
    assert task.events["8"] == {"group": "group1"}      # ends three mechanisms' operations: theirs, no one's
    assert set(task.arcs) == set(toml_run.task.arcs)
