"""A machine's highest speed on networks of its own: the graph, the LP in (p, n) and bisection on n
agree on random networks with windows and syncs; a time floor is an angle at the speed; a cycle only
a machine at rest fits is infeasible; a limiting cycle a window closes gives no speed per degree of
cycle."""
import dataclasses

import numpy as np
import pytest

from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import max_machine_speed, plan_cyclogram


def random_machine(seed, events=30, windows=3, syncs=1):
    """A random DAG of operations (some time-based, some under contact stress) from e0 to e{n-1},
    with windows and syncs, in a 360 deg cycle."""
    rng = np.random.default_rng(seed)
    names = [f"e{i}" for i in range(events)]
    ops, seen, stress = [], set(), {}
    for i in range(events - 1):                    # a spine keeps every event between the ends
        ops.append({"from": names[i], "to": names[i + 1], "min_deg": float(rng.uniform(0, 8))})
        seen.add((i, i + 1))
    for _ in range(events):
        i, j = sorted(rng.choice(events, 2, replace=False).tolist())
        if (i, j) not in seen:
            seen.add((i, j))
            ops.append({"from": names[i], "to": names[j], "min_deg": float(rng.uniform(0, 30))})
    for op in ops:
        u = rng.random()
        if u < 0.15:
            op["min_ms"] = float(rng.uniform(1, 20))
        elif u < 0.3:
            stress[f"s{len(stress)}"] = {"sigma_ref_MPa": float(rng.uniform(500, 900)), "t_ref_deg": float(rng.uniform(5, 30))}
            op["stress"] = f"s{len(stress) - 1}"
    wins = []
    for _ in range(windows):
        i, j = sorted(rng.choice(events, 2, replace=False).tolist())
        wins.append({"from": names[i], "to": names[j], "max_deg": float(rng.uniform(20, 200))})
    sync = [{"events": sorted(rng.choice(names[1:-1], 2, replace=False).tolist())} for _ in range(syncs)]
    return Cyclogram(events={v: {} for v in names}, operations=ops, stress_models=stress, windows=wins, syncs=sync,
                     cycle_deg=360.0, sigma_H_limit_MPa=800.0, speed_rpm=420.0)


def test_random_networks_with_windows_and_syncs_graph_lp_and_bisection_agree():
    solved = infeasible = 0
    for seed in range(40):
        task = random_machine(seed, windows=seed % 4, syncs=seed % 2)
        graph, lp = max_machine_speed(task, method="graph"), max_machine_speed(task, method="lp")
        assert graph.status is lp.status, (seed, graph.message, lp.message)
        if graph.status is Status.SOLVED:
            solved += 1
            assert graph.values["max_speed_rpm"] == pytest.approx(lp.values["max_speed_rpm"], rel=1e-9), seed
            assert graph.values["span_deg"] <= 360.0 + 1e-7
            if seed % 8 == 0:                      # bisection is slow: a few
                bis = max_machine_speed(task, method="bisection", rtol=1e-9)
                assert bis.values["max_speed_rpm"] == pytest.approx(graph.values["max_speed_rpm"], rel=1e-8), seed
        else:
            infeasible += 1
            assert graph.status is Status.INFEASIBLE and graph.message.startswith("no speed fits")
    assert solved >= 12 and infeasible >= 3            # both outcomes exercised (16 and 24 with these seeds)


def test_a_cycle_only_a_machine_at_rest_fits_is_infeasible():
    ops = [{"from": "a", "to": "b", "min_deg": 10.0}, {"from": "b", "to": "c", "min_deg": 0.0, "min_ms": 10.0}]
    task = Cyclogram(events={"a": {}, "b": {}, "c": {}}, operations=ops, speed_rpm=100.0, cycle_deg=10.0)
    for method in ("graph", "lp", "bisection"):
        r = max_machine_speed(task, method=method)
        assert r.status is Status.INFEASIBLE and r.message.startswith("no speed fits: conflicting chain t(a->b)")


def test_a_time_floor_is_an_angle_at_the_task_s_speed():
    ops = [{"from": "a", "to": "b", "min_deg": 10.0, "min_ms": 50.0}, {"from": "b", "to": "c", "min_deg": 5.0}]
    task = Cyclogram(events={"a": {}, "b": {}, "c": {}}, operations=ops, speed_rpm=300.0)
    r = plan_cyclogram(task)
    assert r.values["t_a_b_deg"] == pytest.approx(300 / 60 * 360 * 0.050)        # 90 deg in 50 ms
    assert r.diagnostics["bound_source"]["a->b"] == "min_time"
    with pytest.raises(ModelError, match=r"min_ms=-1\.0: a minimum duration must be in \[0"):
        Cyclogram(events={"a": {}, "b": {}}, operations=[{"from": "a", "to": "b", "min_deg": 1.0, "min_ms": -1.0}])


def _flight_machine(windows):
    """a -> b -> c in 10 ms each (0.06 n deg at n rpm), c -> d 10 deg, a 360 deg cycle."""
    ops = [{"from": "a", "to": "b", "min_deg": 0.0, "min_ms": 10.0}, {"from": "b", "to": "c", "min_deg": 0.0,
                                                                      "min_ms": 10.0},
           {"from": "c", "to": "d", "min_deg": 10.0}]
    return Cyclogram(events={v: {} for v in "abcd"}, operations=ops, speed_rpm=100.0, cycle_deg=360.0,
                     windows=windows)


@pytest.mark.parametrize("method", ["graph", "lp", "bisection"])
def test_a_limiting_cycle_closed_by_a_window_gives_no_speed_per_degree_of_cycle(method):
    """The window p(c) - p(a) <= 70 deg holds the speed at 70 / 0.12 = 583.3 rpm; the cycle
    (0.12 n + 10 <= 360: 2917 rpm) is far: a longer cycle gives no speed, dn/dcycle = 0 (the slope of
    the chain, 1 / 0.12 rpm/deg, is dn/dwindow)."""
    limited = _flight_machine([{"from": "a", "to": "c", "max_deg": 70.0}])
    r = max_machine_speed(limited, method=method)
    assert r.values["max_speed_rpm"] == pytest.approx(70.0 / 0.12, rel=1e-6)
    assert max_machine_speed(dataclasses.replace(limited, cycle_deg=361.0), method=method).values[
        "max_speed_rpm"] == pytest.approx(r.values["max_speed_rpm"], rel=1e-6)
    assert r.diagnostics["sens_cycle_rpm_per_deg"] == 0.0
    free = max_machine_speed(_flight_machine([]), method=method)      # the cycle closes it: 350 / 0.12 rpm
    assert free.values["max_speed_rpm"] == pytest.approx(350.0 / 0.12, rel=1e-6)
    assert free.diagnostics["sens_cycle_rpm_per_deg"] == pytest.approx(1.0 / 0.12, rel=1e-6)
