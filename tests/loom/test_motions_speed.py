"""The highest speed of a machine with an indexing cam of a fixed angle (min_deg = max_deg) and
acceleration-limited strokes: the turret-and-die machine without overlap (Mechanical Design
Handbook blog, "Timing Diagram", parts 1-2, 2009: turret index 150 deg, die strokes 55 deg, dwell
100 deg). The graph's Newton step used to stop on the kink g n = phi of the fixed-angle operation
and call the machine infeasible with an empty conflict."""
import math

import pytest

from mechopt.kit.result import Status
from mechopt.models.loom import Cyclogram
from mechopt.solvers.loom import max_machine_speed

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
