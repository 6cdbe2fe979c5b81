"""The loom cyclogram model (paper 004, Podgorny et al. 2018): the network, its validation, the
stress and amplitude laws. Published: a(3,7) = -0.003 t(3,7) + 0.208 mm, limit 0.1 mm (Results and discussion; Research methodology)."""
import networkx as nx
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mechopt import registry
from mechopt.kit.errors import ModelError, SceneError
from mechopt.models.cyclogram import Cyclogram
from mechopt.models.loom_limits import amplitude_bound_deg, amplitude_mm, stress_bound_deg, stress_MPa
from mechopt.scene import load

SLOPE_MM_PER_DEG, INTERCEPT_MM, LIMIT_MM = -0.003, 0.208, 0.1      # Podgorny et al. (2018), Results and discussion; Research methodology


def chain(*angles, **kw):
    """Events 1..n+1 in a row, operation k -> k+1 with min angle angles[k-1]."""
    events = {str(k): {"mechanism": "m"} for k in range(1, len(angles) + 2)}
    ops = [{"from": str(k), "to": str(k + 1), "min_deg": a} for k, a in enumerate(angles, start=1)]
    return Cyclogram(events=events, operations=ops, **kw)


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


EVENTS = {"1": {}, "2": {}, "3": {}}
OPS = [{"from": "1", "to": "2", "min_deg": 10.0}, {"from": "2", "to": "3", "min_deg": 5.0}]


@pytest.mark.parametrize("change, match", [
    (dict(operations=[{"from": "1", "to": "9", "min_deg": 1.0}]), r"operations\[1->9\]: unknown event '9'; events: 1, 2, 3"),
    (dict(operations=OPS + [{"from": "3", "to": "1", "min_deg": 1.0}]), r"operations: precedence cycle 1 -> 2 -> 3 -> 1"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": -5.0}, OPS[1]]),
     r"operations\[1->2\]\.min_deg=-5\.0: a minimum phase angle must be >= 0"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1e300}, OPS[1]]),
     r"operations\[1->2\]\.min_deg=1e\+300: a minimum phase angle must be <= 1e\+06 deg"),
    (dict(operations=OPS, sigma_H_limit_MPa=1e300), r"sigma_H_limit_MPa=1e\+300: allowed > 0 \.\.\. 1e\+06"),
    (dict(operations=OPS, cycle_deg=float("inf")), r"cycle_deg=inf: expected a finite number"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=1e-300,
          stress_models={"cam": {"sigma_ref_MPa": 900.0, "t_ref_deg": 30.0}}),
     r"operations\[1->2\]: its contact_stress bound 2\.7e\+304 deg \(exact form\), set by stress_models\.cam and "
     r"sigma_H_limit_MPa, is outside the allowed \+-1e\+06 deg"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "amplitude": "linear"}, OPS[1]],
          amplitude_slope_mm_per_deg=-0.003, amplitude_intercept_mm=1e300, amplitude_limit_mm=0.1),
     r"operations\[1->2\]: its amplitude bound 3\.33333e\+302 deg \(exact form\), set by amplitude_slope_mm_per_deg, "
     r"amplitude_intercept_mm and amplitude_limit_mm"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0,
          stress_models={"cam": {"sigma_ref_MPa": 900.0, "t_ref_deg": 1e300}}),
     r"stress_models\.cam\.t_ref_deg=1e\+300 must be in \(0, 1e\+06\]"),
    (dict(operations=OPS, windows=[{"from": "1", "to": "3", "max_deg": 1e300}]),
     r"windows\[0\]\.max_deg=1e\+300: allowed within \+-1e\+06 deg"),
    (dict(operations=OPS, windows=1.0), r"windows: expected a list of tables, got 1\.0"),
    (dict(operations=OPS, syncs="2,3"), r"syncs: expected a list of tables, got '2,3'"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": "ten"}, OPS[1]]), r"operations\[1->2\]\.min_deg='ten': expected a finite number"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0),
     r"operations\[1->2\]\.stress='cam': no such stress model; defined: none"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]],
          stress_models={"cam": {"sigma_ref_MPa": 900.0, "t_ref_deg": 30.0}}),
     r"operations\[1->2\]\.stress='cam' needs sigma_H_limit_MPa \(effect contact_stress\)"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0,
          stress_models={"cam": {"sigma_ref_MPa": -900.0, "t_ref_deg": 30.0}}),
     r"stress_models\.cam\.sigma_ref_MPa=-900\.0 must be in \(0, 1e\+06\]"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "stress": "cam"}, OPS[1]], sigma_H_limit_MPa=800.0,
          stress_models={"cam": {"sigma_ref_MPa": 900.0}}), r"stress_models\.cam: missing t_ref_deg"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "amplitude": "cubic"}, OPS[1]]),
     r"operations\[1->2\]\.amplitude='cubic': no such amplitude model; known: linear"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "amplitude": "linear"}, OPS[1]]),
     r"amplitude='linear' needs amplitude_slope_mm_per_deg, amplitude_intercept_mm, amplitude_limit_mm"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "colour": "red"}, OPS[1]]),
     r"operations\[0\]: unknown colour; allowed: amplitude, cycles, direction, from, group, law, mark, max_accel_m_s2, max_accel_rad_s2, max_deg, max_velocity_m_s, max_velocity_rad_s, mechanism, min_deg, min_ms, name, stress, stroke_deg, stroke_mm, to, what, where, why"),
    (dict(operations=[{"from": "1", "min_deg": 1.0}]), r"operations\[0\]: missing to"),
    (dict(operations=OPS + [dict(OPS[0])]), r"operations\[1->2\]: given twice"),
    (dict(operations=[{"from": "1", "to": "1", "min_deg": 1.0}]), r"operations\[1->1\]: an operation must join two different events"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "mark": "assumed"}, OPS[1]]),
     r"operations\[0\]: marked 'assumed' needs a 'why'"),
    (dict(operations=[{"from": "1", "to": "2", "min_deg": 1.0, "mark": "guessed", "why": "x"}, OPS[1]]),
     r"operations\[0\]\.mark='guessed': allowed given, assumed, calibrated"),
    (dict(operations=OPS + [{"from": "1", "to": "3", "min_deg": 1.0}]), None),      # fine: a second chain
    (dict(operations=[OPS[0], {"from": "3", "to": "2", "min_deg": 1.0}]),
     r"a cyclogram needs one first and one last event; found first \['1', '3'\] and last \['2'\]"),
    (dict(operations=OPS, windows=[{"from": "1", "to": "7", "max_deg": 3.0}]), r"windows\[0\]: unknown event '7'"),
    (dict(events=EVENTS | {"spare": {}}, operations=OPS, syncs=[{"events": ["1", "spare"]}]),
     r"syncs\[0\]: event 'spare' has no operation; a window or sync needs events of the network"),
    (dict(operations=OPS, syncs=[{"events": ["1"]}]), r"syncs\[0\]\.events=\['1'\]: give a list of two or more events"),
    (dict(operations=OPS, limiting_op=["1", "3"]), r"limiting_op=\['1', '3'\]: must name an operation \[from, to\]"),
    (dict(operations=OPS, cycle_deg=-360.0), r"cycle_deg=-360\.0: allowed > 0 \.\.\. 1e\+06"),
    (dict(operations=OPS, amplitude_slope_mm_per_deg=0.003), r"amplitude_slope_mm_per_deg=0\.003: allowed < 0"),
    (dict(operations=OPS, amplitude_intercept_mm=float("nan")), r"amplitude_intercept_mm=nan: expected a finite number"),
    # formerly -1 mm gave a -1.09 mm amplitude reported as SOLVED
    (dict(operations=OPS, amplitude_intercept_mm=-1.0), r"amplitude_intercept_mm=-1\.0: allowed > 0"),
    (dict(events=[1, 2], operations=OPS), r"events: expected a table, got \[1, 2\]"),
    (dict(operations={"a": 1}), r"operations: expected a list of tables"),
    (dict(events={"1": "lift", "2": {}, "3": {}}, operations=OPS), r"events\.1: expected a table, got 'lift'"),
])
def test_bad_network_is_refused_naming_the_key(change, match):
    kwargs = {"events": EVENTS, "operations": OPS} | change
    if match is None:
        Cyclogram(**kwargs)
        return
    with pytest.raises(ModelError, match=match):
        Cyclogram(**kwargs)


def test_bad_scene_network_is_refused_naming_file_and_key(tmp_path):
    good = registry.cases_dir() / "loom" / "group1.toml"
    bad = tmp_path / "bad.toml"
    bad.write_text(good.read_text().replace('from = "9"\nto = "10"', 'from = "9"\nto = "99"'))
    with pytest.raises(SceneError, match=r"bad\.toml: structure\.operations\[9->99\]: operations\[9->99\]: unknown event '99'"):
        load(bad)


def test_isolated_event_is_kept_apart_and_not_a_first_event():
    task = Cyclogram(events=EVENTS | {"spare": {}}, operations=OPS)
    assert task.isolated_events == ["spare"] and task.first_event == "1" and task.last_event == "3"


def test_chain_helper_lower_bounds_are_the_min_angles():
    lb, why = chain(3.0, 0.0, 7.5).lower_bounds_deg()
    assert list(lb) == [3.0, 0.0, 7.5] and why == ["min_angle"] * 3


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
