"""The highest speed of a machine with an indexing cam of a fixed angle (min_deg = max_deg) and
acceleration-limited strokes: the turret-and-die machine without overlap (Mechanical Design
Handbook blog, "Timing Diagram", parts 1-2, 2009: turret index 150 deg, die strokes 55 deg, dwell
100 deg). The graph's Newton step used to stop on the kink g n = phi of the fixed-angle operation
and call the machine infeasible with an empty conflict."""
import math

import pytest

from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import max_machine_speed

STROKE_M = 0.050            # the die's stroke (source, part 1)
ACCEL_M_S2 = 20.0           # assumed limit: the hand calculation (73.14 rpm)
CYCLOID_CA = 2 * math.pi    # peak acceleration coefficient of the cycloid (Rothbart, eq. 2.59)


def least_stroke_ms():
    """T >= sqrt(Ca h / a): a = Ca h / T^2 for a cycloidal rise of h over T [ms]."""
    return 1000.0 * math.sqrt(CYCLOID_CA * STROKE_M / ACCEL_M_S2)


def hand_speed_rpm(index_deg=150.0, dwell_deg=100.0):
    """The two strokes share what the index and the dwell leave of 360 deg; a stroke of T ms at
    n rpm spans 6 n T / 1000 deg."""
    return (360.0 - index_deg - dwell_deg) / 2 / (6.0 * least_stroke_ms() / 1000.0)


def turret(index_ms=None, timed_strokes=True):
    index = {"from": "start", "to": "turret.stop", "min_deg": 150.0, "max_deg": 150.0, "name": "turret index"}
    if index_ms is not None:
        index["min_ms"] = index_ms
    stroke = {"min_ms": least_stroke_ms()} if timed_strokes else {"min_deg": 55.0}
    return [index,
            {"from": "turret.stop", "to": "die.bottom", "name": "die down"} | stroke,
            {"from": "die.bottom", "to": "die.lift", "min_deg": 100.0, "max_deg": 100.0, "name": "die dwell"},
            {"from": "die.lift", "to": "die.top", "name": "die up"} | stroke]


@pytest.mark.parametrize("index_ms", [None, 50.0, 300.0])
@pytest.mark.parametrize("method", ["graph", "lp", "bisection"])
def test_a_fixed_angle_with_a_time_floor_has_the_hand_speed(method, index_ms):
    # index_ms = 300: the index's own time floor 1.8 n deg reaches its fixed 150 deg at 83.3 rpm,
    # above the strokes' 73.14: the strokes still limit
    task = Cyclogram(operations=turret(index_ms), cycle_deg=360.0)
    r = max_machine_speed(task, method=method)
    assert r.status is Status.SOLVED, r.message
    assert r.values["max_speed_rpm"] == pytest.approx(hand_speed_rpm(), rel=1e-6)
    assert r.values["max_speed_rpm"] == pytest.approx(73.1394, abs=1e-4)


@pytest.mark.parametrize("method", ["graph", "lp"])
def test_the_fixed_angle_s_own_time_floor_limits_at_its_kink(method):
    """The index's time floor 0.006 n T reaches its fixed angle first: n = 150 / (0.006 T), the
    root on the kink itself."""
    ops = turret(index_ms=1000.0, timed_strokes=False)
    r = max_machine_speed(Cyclogram(operations=ops, cycle_deg=360.0), method=method)
    assert r.status is Status.SOLVED, r.message
    assert r.values["max_speed_rpm"] == pytest.approx(150.0 / (0.006 * 1000.0), rel=1e-9)


def test_a_conflict_names_the_operations_in_the_table_s_words():
    ops = turret()
    ops[2] = ops[2] | {"min_deg": 250.0, "max_deg": 250.0}       # index 150 + dwell 250 > 360 at any speed
    r = max_machine_speed(Cyclogram(operations=ops, cycle_deg=360.0), method="graph")
    assert r.status is Status.INFEASIBLE and r.message.startswith("no speed fits: conflicting chain")
    assert '"turret index"' in r.message and '"die dwell"' in r.message


def test_the_turret_scene_s_speed_is_the_hand_calculation():
    """The scene's table gives laws, strokes and an acceleration limit, no hand-converted min_ms:
    the engine's speed is the hand calculation, and the die's peak acceleration there is its limit."""
    from mechopt import registry

    task = registry.find("loom/turret-die-speed").build()[0]
    assert task.arc_data(task.arcs.index(("stopped", "bottom")))["min_ms"] == pytest.approx(least_stroke_ms())
    for method in ("graph", "lp"):
        r = max_machine_speed(task, method=method)
        assert r.status is Status.SOLVED, r.message
        assert r.values["max_speed_rpm"] == pytest.approx(hand_speed_rpm(), rel=1e-9)
        omega = 2 * math.pi * r.values["max_speed_rpm"] / 60
        beta = math.radians(r.values["t_stopped_bottom_deg"])
        assert r.values["accel_stopped_bottom_m_s2"] == pytest.approx(CYCLOID_CA * STROKE_M * omega**2 / beta**2)
        assert r.values["accel_stopped_bottom_m_s2"] == pytest.approx(ACCEL_M_S2, rel=1e-9)
        assert "max_accel[stopped->bottom]" in r.message


@pytest.mark.parametrize("cells, words", [
    ({"stroke_mm": 50.0}, "needs the operation's motion law"),
    ({"law": "cycloid"}, "unknown motion law"),
    ({"law": "cycloidal", "max_accel_m_s2": 20.0}, "needs the stroke (stroke_mm)"),
    ({"law": "cycloidal", "stroke_mm": -5.0}, "stroke_mm=-5.0: allowed (0, 100000] mm"),
    ({"law": "cycloidal", "stroke_mm": 5.0, "max_velocity_m_s": 0.0}, "max_velocity_m_s=0.0: allowed"),
])
def test_a_bad_motion_cell_is_named(cells, words):
    from mechopt.kit.errors import ModelError

    ops = turret(timed_strokes=False)
    ops[1] = ops[1] | cells
    with pytest.raises(ModelError, match=None) as exc:
        Cyclogram(operations=ops, cycle_deg=360.0)
    assert words in str(exc.value) and "operations[turret.stop->die.bottom]" in str(exc.value)


def test_a_velocity_limit_is_a_least_duration():
    """v = Cv h / T <= v_max: T >= Cv h / v_max (cycloid Cv = 2): 2 x 0.05 / 0.5 = 200 ms."""
    ops = turret(timed_strokes=False)
    ops[1] = ops[1] | {"law": "cycloidal", "stroke_mm": 50.0, "max_velocity_m_s": 0.5}
    task = Cyclogram(operations=ops, cycle_deg=360.0, speed_rpm=60.0)
    k = task.arcs.index(("turret.stop", "die.bottom"))
    assert task.arc_data(k)["min_ms"] == pytest.approx(200.0)
    lb, why = task.lower_bounds_deg()
    assert lb[k] == pytest.approx(0.006 * 60.0 * 200.0) and why[k] == "max_velocity"


def test_the_limiting_group_is_the_operation_s_own():
    """The die's strokes start at the turret's stop (an event of group turret): the speed is the
    die's (its acceleration limit), and the report and the limiting cycle name group die, the operations' own."""
    from mechopt import registry

    r = max_machine_speed(registry.find("loom/turret-die-speed").build()[0])
    assert r.status is Status.SOLVED, r.message
    assert r.diagnostics["limiting_group"] == "die"
    assert {row["group"] for row in r.diagnostics["limiting"]} == {"die"}
    down = [line for line in r.diagnostics["limiting_cycle"] if '"die down"' in line]
    assert len(down) == 1 and "(die, " in down[0]            # the limiting cycle's words say so too
