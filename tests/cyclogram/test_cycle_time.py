"""The least cycle time of a recurrent machine (solvers/cyclogram/cycle_time.py): recurrent operations
(cycles = k), the maximum cycle ratio on the graph, its critical circuits and floats, the LP in
(p, T) as certificate, and a max-plus example from the literature."""
import math

import networkx as nx
import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import least_cycle_time, plan_cyclogram
from mechopt.solvers.cyclogram.cycle_uniform import uniform_constraints


def op(x, y, d, k=0, unit="min_ms"):
    return {"from": x, "to": y, unit: d} | ({"cycles": k} if k else {})


def brute_force_ratio(task) -> float:
    """max D(C) / K(C) over the simple circuits with K > 0 (at least 0), by enumerating them
    (networkx.simple_cycles); the networks here have one arc per ordered pair of events."""
    u = uniform_constraints(task)
    g = nx.DiGraph()
    for t, h, d, k in zip(u.tails.tolist(), u.heads.tolist(), u.d.tolist(), u.k.tolist()):
        assert not g.has_edge(t, h), "brute force: one arc per pair"
        g.add_edge(t, h, d=d, k=k)
    best = 0.0
    for cycle in nx.simple_cycles(g):
        arcs = list(zip(cycle, cycle[1:] + cycle[:1]))
        D, K = math.fsum(g.edges[a]["d"] for a in arcs), sum(g.edges[a]["k"] for a in arcs)
        assert K > 0 or D <= 0, "brute force: a positive circuit of height 0"
        if K > 0:
            best = max(best, D / K)
    return best


def test_a_zero_height_positive_circuit_is_infeasible_and_named():
    # a -> b takes 5 ms but a window (in degrees: angle-based here) allows 3 between them: no T helps
    ops = [op("a", "b", 5.0, unit="min_deg"), op("b", "c", 1.0, unit="min_deg"), op("c", "a", 2.0, 1, "min_deg")]
    task = Cyclogram(operations=ops, windows=[{"from": "a", "to": "b", "max_deg": 3.0}])
    r = least_cycle_time(task, check=True)
    assert r.status is Status.INFEASIBLE
    circuit = r.diagnostics["conflict_circuit"]
    assert sorted(circuit["events"]) == ["a", "b"] and circuit["cycles"] == 0
    assert circuit["length_deg"] == pytest.approx(2.0)
    assert "a->b" in r.violated and any(v.startswith("window p(b) - p(a) <= 3") for v in r.violated)
    assert "a->b" in r.message and r.diagnostics["check"]["status"] == "INFEASIBLE"   # the LP agrees


def test_two_circuits_tying_for_critical_are_both_named():
    # a <-> b (3 + 3 over one cycle) and c <-> d (2 + 4 over one cycle) both need 6; b -> c joins them
    ops = [op("a", "b", 3.0), op("b", "a", 3.0, 1), op("b", "c", 1.0), op("c", "d", 2.0), op("d", "c", 4.0, 1)]
    r = least_cycle_time(Cyclogram(operations=ops), check=True)
    assert r.status is Status.SOLVED and r.values["cycle_time_ms"] == pytest.approx(6.0, rel=1e-12)
    named = sorted(sorted(c["events"]) for c in r.diagnostics["critical_circuits"])
    assert named == [["a", "b"], ["c", "d"]]
    assert "2 circuits tie for critical" in r.message
    assert sorted(r.diagnostics["critical_ops"]) == ["a->b", "b->a[+1]", "c->d", "d->c[+1]"]
    assert r.diagnostics["float_ms"]["b->c"] is None          # on no circuit


def test_two_critical_circuits_through_one_event_are_both_in_the_critical_operations():
    ops = [op("a", "b", 3.0), op("b", "a", 3.0, 1), op("a", "c", 4.0), op("c", "a", 2.0, 1)]
    r = least_cycle_time(Cyclogram(operations=ops))
    assert r.values["cycle_time_ms"] == pytest.approx(6.0, rel=1e-12)
    assert sorted(r.diagnostics["critical_ops"]) == ["a->b", "a->c", "b->a[+1]", "c->a[+1]"]
    assert all(r.diagnostics["float_ms"][k] == pytest.approx(0.0, abs=1e-12) for k in r.diagnostics["critical_ops"])


def test_an_event_on_no_circuit_has_its_float_reported():
    # a -> b -> a[+1] (3 + 2 = 5) is critical; b -> c -> a[+2] (3 + 4 + 1 = 8 over 2 = 4) has float
    # 2 * 5 - 8 = 2 on each of its operations; d hangs off c on no circuit
    ops = [op("a", "b", 3.0), op("b", "c", 4.0), op("c", "a", 1.0, 2), op("b", "a", 2.0, 1), op("c", "d", 5.0)]
    r = least_cycle_time(Cyclogram(operations=ops), check=True)
    assert r.status is Status.SOLVED and r.values["cycle_time_ms"] == pytest.approx(5.0, rel=1e-12)
    floats = r.diagnostics["float_ms"]
    assert floats["b->c"] == pytest.approx(2.0) and floats["c->a[+2]"] == pytest.approx(2.0)
    assert floats["a->b"] == pytest.approx(0.0, abs=1e-12) and floats["c->d"] is None
    assert r.values["p_d_ms"] - r.values["p_c_ms"] >= 5.0 - 1e-12       # d still scheduled after c
    assert r.diagnostics["critical_circuit"]["events"] == ["a", "b"]


@pytest.mark.parametrize("long_d, expected, height", [(10.0, 5.0, 2), (16.0, 16.0 / 3.0, 3)])
def test_recurrence_heights_2_and_3(long_d, expected, height):
    # circuit x: a -> b -> a[+2] of 4 + 6 = 10 over two cycles (5); circuit y: b -> c -> b[+3] of
    # 6 + (long_d - 6) over three cycles; circuit z: a -> a[+1] of 4.9 over one
    ops = [op("a", "b", 4.0, unit="min_deg"), op("b", "a", 6.0, 2, "min_deg"), op("b", "c", 6.0, unit="min_deg"),
           op("c", "b", long_d - 6.0, 3, "min_deg"), op("a", "a", 4.9, 1, "min_deg")]
    task = Cyclogram(operations=ops)
    r = least_cycle_time(task, check=True)
    assert r.status is Status.SOLVED
    assert r.values["cycle_deg"] == pytest.approx(expected, rel=1e-12) == brute_force_ratio(task)
    assert r.diagnostics["critical_circuit"]["cycles"] == height
    assert r.values["check_rel"] <= 1e-9


def _random_network(rng, mixed=False):
    """Angles only, or (`mixed`) each floor and window an angle or a duration at random (time-based)."""
    n = int(rng.integers(3, 12))
    names = [f"e{i}" for i in range(n)]
    unit = (lambda: "min_ms" if rng.random() < 0.5 else "min_deg") if mixed else (lambda: "min_deg")
    ops, seen = [], set()
    for i in range(n - 1):                     # a chain keeps every event linked, then more forward arcs
        first = "min_ms" if mixed and i == 0 else unit()        # mixed: one duration at least (time-based)
        ops.append(op(names[i], names[i + 1], float(rng.uniform(0, 10)), unit=first))
        seen.add((i, i + 1))
    for _ in range(int(rng.integers(0, 2 * n))):
        i, j = sorted(rng.choice(n, 2, replace=False).tolist())
        if (i, j) not in seen:
            seen.add((i, j))
            ops.append(op(names[i], names[j], float(rng.uniform(0, 10)), unit=unit()))
    recurrent = set()
    for _ in range(int(rng.integers(1, n + 2))):
        i, j, k = int(rng.integers(n)), int(rng.integers(n)), int(rng.integers(1, 4))
        if (i, j, k) not in recurrent:
            recurrent.add((i, j, k))
            ops.append(op(names[i], names[j], float(rng.uniform(0, 30)), k, unit()))
    windows = [{"from": names[i], "to": names[j], "max_" + unit()[4:]: float(rng.uniform(5, 40))}
               for i, j in sorted(seen)[:int(rng.integers(0, 3))]]
    syncs = [{"events": [names[0], names[-1]]}] if rng.random() < 0.1 else []
    return Cyclogram(operations=ops, windows=windows, syncs=syncs)


@pytest.mark.parametrize("mixed", [False, True], ids=["angles", "angles-and-durations"])
def test_against_the_lp_on_random_recurrent_networks(mixed):
    rng = np.random.default_rng(20261129)
    statuses = []
    for _ in range(50):
        task = _random_network(rng, mixed)
        r = least_cycle_time(task, check=True)
        statuses.append(r.status)
        assert r.status in (Status.SOLVED, Status.INFEASIBLE), r.message
        assert r.diagnostics["check"]["status"] == r.status.value
        if r.status is Status.SOLVED:
            unit = r.diagnostics["unit"]
            T = r.values["cycle_deg" if unit == "deg" else "cycle_time_ms"]
            assert r.values["check_rel"] <= 1e-9
            u = uniform_constraints(task)         # the times meet every constraint at T (the upper bound) ...
            p = np.array([r.values[f"p_{v}_{unit}"] for v in u.names])
            assert np.all(p[u.heads] - p[u.tails] >= u.d - u.k * T - 1e-9 * max(1.0, T))
            circuit = r.diagnostics["critical_circuit"]         # ... and a circuit needs it (the lower bound)
            if circuit is not None:
                assert circuit[f"length_{unit}"] / circuit["cycles"] == pytest.approx(T, rel=1e-12)
    assert Status.SOLVED in statuses and Status.INFEASIBLE in statuses


def test_the_max_plus_textbook_example_has_the_printed_cycle_time():
    """Subiono and van der Woude (2000), the 6 x 6 irreducible example of the Max-Plus Algebra
    toolbox for Scilab (help page maxplusmaxalgol), which prints the eigenvalue l = 8: as recurrent
    operations p(i) + T >= p(j) + a_ij, its least cycle time (scene loom/recurrent-maxplus)."""
    run = registry.run(registry.find("loom/recurrent-maxplus"))
    assert run.ok and run.values["cycle_time_ms"] == 8.0
    assert run.diagnostics["critical_circuit"]["operations"] == ["3->3[+1]"]      # a33 = 8 alone
    task = run.task
    assert brute_force_ratio(task) == 8.0                       # the largest cycle mean, enumerated
    # the printed eigenvector v = (15, 15, 17, 10, 16, 13) is a schedule repeating every 8: A v = 8 + v
    v = {"1": 15, "2": 15, "3": 17, "4": 10, "5": 16, "6": 13}
    for row in task.recurrences:
        assert v[row["to"]] + 8 >= v[row["from"]] + row["min_ms"]


def test_a_reducible_max_plus_system_takes_its_slowest_circuit():
    # the toolbox's reducible example A = [7 -inf; 0 3]: x2 follows x1, whose own circuit (7) sets T
    ops = [op("1", "1", 7.0, 1), op("1", "2", 0.0, 1), op("2", "2", 3.0, 1)]
    r = least_cycle_time(Cyclogram(operations=ops), check=True)
    assert r.values["cycle_time_ms"] == 7.0 and r.diagnostics["critical_circuit"]["operations"] == ["1->1[+1]"]
    assert r.diagnostics["float_ms"]["2->2[+1]"] == pytest.approx(4.0)


def test_no_recurrent_circuit_needs_no_time():
    r = least_cycle_time(Cyclogram(operations=[op("a", "b", 3.0), op("b", "c", 2.0), op("c", "d", 1.0, 1)]))
    assert r.status is Status.SOLVED and r.values["cycle_time_ms"] == 0.0
    assert r.diagnostics["critical_circuit"] is None and "any cycle time fits" in r.message


@pytest.mark.parametrize("cycles", [1.5, -1, True, "2", math.nan])
def test_cycles_must_be_a_whole_number_named_by_its_row(cycles):
    with pytest.raises(ModelError, match=r"operations\[b->a\]\.cycles=.*whole number") as err:
        Cyclogram(operations=[op("a", "b", 3.0), {"from": "b", "to": "a", "min_ms": 1.0, "cycles": cycles}])
    assert err.value.key == "operations[b->a].cycles"


def test_a_recurrent_row_carries_a_floor_only_and_one_cycle_solvers_refuse_it():
    with pytest.raises(ModelError, match=r"operations\[b->a\]\.cycles=1: a recurrent operation carries .* max_deg"):
        Cyclogram(operations=[op("a", "b", 3.0, unit="min_deg"),
                              {"from": "b", "to": "a", "min_deg": 1.0, "cycles": 1, "max_deg": 5.0}])
    task = Cyclogram(operations=[op("a", "b", 3.0, unit="min_deg"), op("b", "a", 1.0, 1, "min_deg")], cycle_deg=360.0)
    with pytest.raises(ModelError, match=r"operations\[b->a\]\.cycles=1: plan_cyclogram.*cyclogram\.least_cycle_time"):
        plan_cyclogram(task)


def test_angles_and_durations_mix_in_one_cycle_time():
    """An angle is a fraction of the cycle: a -> b 3 ms, then b -> a of the next cycle at least 10 deg,
    so T >= 3 + 10 T / 360, T = 3 * 360 / 350 ms; the brute force over circuits and the LP agree."""
    task = Cyclogram(operations=[op("a", "b", 3.0), op("b", "a", 10.0, 1, "min_deg")])
    r = least_cycle_time(task, check=True)
    assert r.status is Status.SOLVED and r.values["cycle_time_ms"] == pytest.approx(3.0 * 360.0 / 350.0, rel=1e-12)
    assert brute_force_ratio(task) == pytest.approx(r.values["cycle_time_ms"], rel=1e-12)
    assert r.values["check_rel"] <= 1e-9 and r.diagnostics["critical_circuit"]["cycles"] == pytest.approx(35 / 36)


def test_an_operation_with_an_angle_and_a_duration_takes_the_larger():
    """c -> d at least 90 deg and 50 ms between 30 ms and 20 ms: T >= 100 by the durations, T >= 50 + T / 4
    (66.7) by the angle, so 100; at 270 deg the angle rules: T >= 50 + 3 T / 4, T = 200 ms."""
    ops = [op("a", "c", 30.0), {"from": "c", "to": "d", "min_deg": 90.0, "min_ms": 50.0}, op("d", "a", 20.0, 1)]
    r = least_cycle_time(Cyclogram(operations=ops), check=True)
    assert r.values["cycle_time_ms"] == pytest.approx(100.0, rel=1e-12) and r.values["check_rel"] <= 1e-9
    ops[1] = {"from": "c", "to": "d", "min_deg": 270.0, "min_ms": 50.0}
    r = least_cycle_time(Cyclogram(operations=ops), check=True)
    assert r.values["cycle_time_ms"] == pytest.approx(200.0, rel=1e-12) and r.values["check_rel"] <= 1e-9


def test_a_window_in_degrees_bounds_a_time_based_cycle():
    """a -> b 100 ms inside a window of 90 deg: 100 <= T / 4, T >= 400 ms (the recurrence asks 150 only)."""
    ops = [op("a", "b", 100.0), op("b", "a", 50.0, 1)]
    r = least_cycle_time(Cyclogram(operations=ops, windows=[{"from": "a", "to": "b", "max_deg": 90.0}]), check=True)
    assert r.values["cycle_time_ms"] == pytest.approx(400.0, rel=1e-12) and r.values["check_rel"] <= 1e-9
    assert "window p(b) - p(a) <= 90 deg" in r.diagnostics["critical_circuit"]["operations"]


def test_angles_that_overfill_their_window_fit_no_cycle_time():
    ops = [{"from": "a", "to": "b", "min_deg": 200.0}, op("b", "c", 10.0), op("c", "a", 0.0, 1)]
    r = least_cycle_time(Cyclogram(operations=ops, windows=[{"from": "a", "to": "b", "max_deg": 100.0}]), check=True)
    assert r.status is Status.INFEASIBLE
    assert "asks for 100 deg more than its cycles hold" in r.message and "a->b" in r.message


def test_a_recurrent_machine_from_its_timing_table():
    """loom/recurrent-indexer: a CSV with a cycles column; the glue's cure two indexes on sets T."""
    run = registry.run(registry.find("loom/recurrent-indexer"))
    assert run.ok and run.values["cycle_time_ms"] == pytest.approx(1390.0 / 3.0, rel=1e-12)
    circuit = run.diagnostics["critical_circuit"]
    assert circuit["cycles"] == 3 and "feed.down->press.down[+2]" in circuit["operations"]
    assert brute_force_ratio(run.task) == pytest.approx(1390.0 / 3.0, rel=1e-12)
    # the feeder's retract lies on its own circuit (120 + 150 + 60 + 20 = 350 ms over one cycle)
    assert run.diagnostics["float_ms"]["feed.down->feed.up"] == pytest.approx(1390.0 / 3.0 - 350.0)


def test_a_duration_at_the_machine_s_speed_is_an_angle():
    # at 60 rpm the shaft turns 36 deg in 100 ms: with speed_rpm the network is angle-based
    ops = [op("a", "b", 10.0, unit="min_deg"), op("b", "c", 100.0), op("c", "a", 50.0, 1)]
    r = least_cycle_time(Cyclogram(operations=ops, speed_rpm=60.0), check=True)
    assert r.values["cycle_deg"] == pytest.approx(10.0 + 36.0 + 18.0, rel=1e-12) and r.values["check_rel"] <= 1e-9


def test_a_task_table_gives_the_cycle_time_and_each_task_s_float():
    """loom/recurrent-tasks: tasks with durations and the tasks they wait for ("b@k": k cycles before)."""
    run = registry.run(registry.find("loom/recurrent-tasks"))
    assert run.ok and run.values["cycle_time_ms"] == pytest.approx(1450.0 / 3.0, rel=1e-12)
    tasks = run.diagnostics["tasks"]
    assert [t for t, row in tasks.items() if row["critical"]] == ["index", "feed", "cure", "press"]
    assert tasks["feed.back"]["float_ms"] == pytest.approx(1450.0 / 3.0 - (120.0 + 150.0 + 60.0))
    assert tasks["eject"]["float_ms"] == pytest.approx(1450.0 / 3.0 - (120.0 + 90.0))
    assert tasks["feed"]["start_ms"] == pytest.approx(120.0)


def test_a_task_table_becomes_its_event_network():
    task = Cyclogram(tasks=[{"task": "a", "min_ms": 3.0}, {"task": "b", "min_ms": 2.0, "after": "a; b@1"}])
    assert sorted(task.arcs) == [("a.end", "b.start"), ("a.start", "a.end"), ("b.end", "end"), ("b.start", "b.end"),
                                 ("start", "a.start")]
    assert [(r["from"], r["to"], r["cycles"]) for r in task.recurrences] == [("b.end", "b.start", 1)]
    assert least_cycle_time(task).values["cycle_time_ms"] == 2.0          # b waits for its own last run


@pytest.mark.parametrize("tasks, match", [
    ([{"task": "a", "min_ms": 1.0}, {"task": "b", "min_ms": 1.0, "after": "a;c"}],
     r"tasks\[b\]\.after: unknown task 'c'; tasks: a, b"),
    ([{"task": "a", "min_ms": 1.0}, {"task": "b", "min_ms": 1.0, "after": "a@x"}],
     r"tasks\[b\]\.after: 'a@x': the cycles after '@' must be a whole number"),
    ([{"task": "a", "min_ms": 1.0}, {"task": "a", "min_ms": 2.0}], r"tasks\[1\]\.task='a': given twice"),
    ([{"task": "a"}], r"tasks\[a\]: give its duration, min_ms or min_deg"),
    ([{"task": "a", "min_ms": 1.0, "colour": "red"}], r"tasks\[0\]: unknown colour"),
])
def test_a_bad_task_table_is_refused_naming_the_row(tasks, match):
    with pytest.raises(ModelError, match=match):
        Cyclogram(tasks=tasks)


def test_a_network_is_given_by_operations_or_by_tasks():
    with pytest.raises(ModelError, match="operations or by its tasks, not both"):
        Cyclogram(operations=[op("x", "y", 1.0)], tasks=[{"task": "a", "min_ms": 1.0}])
    with pytest.raises(ModelError, match=r"operations: missing \(give the operations, or a task table"):
        Cyclogram()


def test_the_iteration_is_count_limited(monkeypatch):
    from mechopt.solvers.cyclogram import cycle_time
    monkeypatch.setattr(cycle_time, "MAX_STEPS", 0)
    r = least_cycle_time(Cyclogram(operations=[op("a", "b", 3.0), op("b", "a", 3.0, 1)]))
    assert r.status is Status.LIMIT and "no answer after 0 Dinkelbach steps" in r.message


def test_a_window_in_time_bounds_a_time_based_cycle():
    """a -> b 100 ms, b -> a of the next cycle 50 ms: T = 150 ms; a window p(b) - p(a) <= 80 ms cannot
    hold the 100 ms step (INFEASIBLE, the window named), and at 120 ms it holds without moving T."""
    ops = [op("a", "b", 100.0), op("b", "a", 50.0, 1)]
    held = least_cycle_time(Cyclogram(operations=ops, windows=[{"from": "a", "to": "b", "max_ms": 120.0}]), check=True)
    assert held.status is Status.SOLVED and held.values["cycle_time_ms"] == pytest.approx(150.0, rel=1e-12)
    short = least_cycle_time(Cyclogram(operations=ops, windows=[{"from": "a", "to": "b", "max_ms": 80.0}]))
    assert short.status is Status.INFEASIBLE and "window p(b) - p(a) <= 80 ms spans no cycle" in short.message


def test_a_window_in_time_is_its_angle_at_the_machine_s_speed():
    """At 60 rpm the shaft turns 36 deg in 100 ms: a 100 ms window on a 40 deg step is 4 deg short."""
    ops = [op("a", "b", 40.0, unit="min_deg")]
    task = Cyclogram(operations=ops, speed_rpm=60.0, windows=[{"from": "a", "to": "b", "max_ms": 100.0}])
    assert task.window_arcs() == [("a", "b", pytest.approx(36.0, rel=1e-12))]
    assert plan_cyclogram(task).status is Status.INFEASIBLE
    wide = Cyclogram(operations=ops, speed_rpm=60.0, windows=[{"from": "a", "to": "b", "max_ms": 120.0}])
    assert plan_cyclogram(wide).values["span_deg"] == pytest.approx(40.0)
    with pytest.raises(ModelError, match=r"windows\[0\]\.max_ms needs speed_rpm"):
        plan_cyclogram(Cyclogram(operations=ops, windows=[{"from": "a", "to": "b", "max_ms": 100.0}]))


@pytest.mark.parametrize("window, match", [({"from": "a", "to": "b"}, r"windows\[0\]: give max_deg .* got neither"),
                                           ({"from": "a", "to": "b", "max_deg": 1.0, "max_ms": 1.0},
                                            r"got max_deg and max_ms"),
                                           ({"from": "a", "to": "b", "max_ms": 2e6}, r"windows\[0\]\.max_ms=2000000")])
def test_a_window_gives_one_limit_in_range(window, match):
    with pytest.raises(ModelError, match=match):
        Cyclogram(operations=[op("a", "b", 40.0, unit="min_deg")], windows=[window])


def test_the_highest_speed_refuses_a_window_in_time_by_name():
    from mechopt.solvers.cyclogram import max_machine_speed
    task = Cyclogram(operations=[op("a", "b", 40.0, unit="min_deg"), op("b", "c", 100.0)], cycle_deg=360.0,
                     windows=[{"from": "a", "to": "c", "max_ms": 300.0}])
    with pytest.raises(ModelError, match=r"windows\[0\]\.max_ms: the highest speed takes windows as angles"):
        max_machine_speed(task)


def test_the_least_cycle_time_refuses_a_clearance_by_name():
    task = registry.find("loom/turret-die-overlap").build()[0]
    assert task.clearances
    with pytest.raises(ModelError, match=r"clearances: not solved by cyclogram\.least_cycle_time .* cyclogram\.plan_motions"):
        least_cycle_time(task)


def test_the_least_cycle_time_s_csv_names_each_event_beside_its_start(tmp_path):
    """`--csv` of a cycle time: a row per event, its name and its start (a file that reads alone)."""
    import csv

    from mechopt.cli import main
    out = tmp_path / "indexer.csv"
    assert main(["run", "loom/recurrent-indexer", "--csv", str(out)]) == 0
    with out.open(newline="") as f:
        rows = list(csv.DictReader(f))
    run = registry.run(registry.find("loom/recurrent-indexer"))
    assert list(rows[0]) == ["event", "start_ms"] and len(rows) == len(run.arrays["event"])
    by_name = {r["event"]: float(r["start_ms"]) for r in rows}
    assert by_name == pytest.approx({v: run.values[f"p_{v}_ms"] for v in by_name}, rel=1e-12, abs=1e-9)
