"""An oscillating output's motion (a lever's swing, `stroke_deg`): its limits in rad/s^2 and
rad/s become least durations T >= sqrt(Ca h / a_max), Cv h / v_max with h in rad, its peaks are
reported in rad/s^2 and rad/s, and the timing diagram draws it on a panel in deg. The hand
values use the cycloid's closed-form coefficients Ca = 2 pi, Cv = 2 (Rothbart (ed.), Cam Design
Handbook, 2004, eqs. 2.57-2.59), not the law library."""
import math
from types import SimpleNamespace

import pytest

from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import plan_motions

SWING_DEG = 30.0            # the lever's swing (assumed, a round number)
CYCLOID_CA, CYCLOID_CV = 2 * math.pi, 2.0


def ops(**lever):
    return [{"from": "a", "to": "b", "min_deg": 90.0, "name": "slide out", "group": "feed", "law": "cycloidal",
             "stroke_mm": 40.0},
            {"from": "b", "to": "c", "min_deg": 60.0, "name": "lever swing", "group": "feed", "law": "cycloidal",
             "stroke_deg": SWING_DEG} | lever]


def test_an_angular_acceleration_limit_is_a_least_duration():
    """T >= sqrt(Ca h / a_max) = sqrt(2 pi (pi / 6) / 100) s = pi / sqrt(300) s = 181.38 ms."""
    task = Cyclogram(operations=ops(max_accel_rad_s2=100.0), cycle_deg=360.0)
    k = task.arcs.index(("b", "c"))
    by_hand = 1000.0 * math.sqrt(CYCLOID_CA * math.radians(SWING_DEG) / 100.0)
    assert by_hand == pytest.approx(1000.0 * math.pi / math.sqrt(300.0), rel=1e-12)
    assert task.arc_data(k)["min_ms"] == pytest.approx(by_hand, rel=1e-12)
    assert task.arc_data(k)["motion_limit"] == "max_accel"


def test_an_angular_velocity_limit_is_a_least_duration():
    """T >= Cv h / v_max = 2 (pi / 6) / 5 s = pi / 15 s = 209.44 ms: above the acceleration's 181.38."""
    task = Cyclogram(operations=ops(max_accel_rad_s2=100.0, max_velocity_rad_s=5.0), cycle_deg=360.0)
    k = task.arcs.index(("b", "c"))
    assert task.arc_data(k)["min_ms"] == pytest.approx(1000.0 * math.pi / 15.0, rel=1e-12)
    assert task.arc_data(k)["motion_limit"] == "max_velocity"


def test_the_peaks_are_reported_in_rad():
    """At 60 rpm (6 n = 360 deg/s) the swing over its 60 deg lasts 1/6 s: a = Ca h / T^2 =
    2 pi (pi / 6) 36 = 12 pi^2 rad/s^2, v = Cv h / T = 2 pi rad/s; the slide's stay in m/s^2."""
    r = plan_motions(Cyclogram(operations=ops(), cycle_deg=360.0, speed_rpm=60.0))
    assert r.status is Status.SOLVED, r.message
    assert r.values["t_b_c_deg"] == pytest.approx(60.0)
    assert r.values["accel_b_c_rad_s2"] == pytest.approx(12 * math.pi**2, rel=1e-12)
    assert r.values["velocity_b_c_rad_s"] == pytest.approx(2 * math.pi, rel=1e-12)
    assert "accel_b_c_m_s2" not in r.values
    assert r.values["accel_a_b_m_s2"] == pytest.approx(CYCLOID_CA * 0.040 * (360.0 / 90.0) ** 2, rel=1e-12)
    assert CYCLOID_CV == pytest.approx(r.values["velocity_b_c_rad_s"] / (math.radians(SWING_DEG) * 6.0), rel=1e-12)


@pytest.mark.parametrize("cells, words", [
    ({"stroke_mm": 10.0}, "stroke_mm and stroke_deg are exclusive"),
    ({"max_accel_m_s2": 20.0}, "max_accel_m_s2: a linear limit with stroke_deg; allowed with stroke_deg: "
                               "max_accel_rad_s2, max_velocity_rad_s"),
    ({"max_velocity_m_s": 1.0}, "max_velocity_m_s: a linear limit with stroke_deg"),
    ({"stroke_deg": 400.0}, "stroke_deg=400.0: allowed (0, 360] deg"),
    ({"max_accel_rad_s2": -1.0}, "max_accel_rad_s2=-1.0: allowed (0, 1e+06] rad/s^2"),
])
def test_a_mixed_or_bad_angular_cell_is_named(cells, words):
    with pytest.raises(ModelError) as exc:
        Cyclogram(operations=ops(**cells), cycle_deg=360.0)
    assert words in str(exc.value) and "operations[b->c]" in str(exc.value)


def test_an_angular_limit_on_a_slide_is_named():
    rows = ops()
    rows[0] = rows[0] | {"max_accel_rad_s2": 50.0}
    with pytest.raises(ModelError, match=r"max_accel_rad_s2: an angular limit with stroke_mm; allowed with stroke_mm: max_accel_m_s2"):
        Cyclogram(operations=rows, cycle_deg=360.0)
    rows = ops()
    del rows[1]["stroke_deg"]
    with pytest.raises(ModelError, match=r"needs the stroke \(stroke_deg\)"):
        Cyclogram(operations=ops()[:1] + [rows[1] | {"max_velocity_rad_s": 5.0}], cycle_deg=360.0)


def test_the_timing_diagram_draws_the_swing_in_deg_on_its_own_panel():
    """One group, a slide [mm] and a lever [deg]: two panels, the lever's curve peaking at its swing."""
    from mechopt.figures.cyclogram import timing_diagram

    task = Cyclogram(operations=ops(), cycle_deg=360.0)
    run = SimpleNamespace(task=task, result=plan_motions(task), scene=SimpleNamespace(id="test/angular"))
    fig = timing_diagram(run)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["feed [mm]", "feed [deg]"]
    assert max(fig.axes[1].lines[0].get_ydata()) == pytest.approx(SWING_DEG, abs=1e-9)
    assert max(fig.axes[0].lines[0].get_ydata()) == pytest.approx(40.0, abs=1e-9)


# the least of several peak accelerations (maximize = "least_scaled_angle"): two motions, different
# laws and strokes, one after the other in a 200 deg window (assumed numbers, round)
BALANCE_OPS = [{"from": "a", "to": "b", "min_deg": 10.0, "name": "push", "law": "cycloidal", "stroke_mm": 50.0},
               {"from": "b", "to": "c", "min_deg": 10.0, "name": "lift", "law": "harmonic", "stroke_mm": 30.0},
               {"from": "c", "to": "d", "min_deg": 20.0, "name": "rest"}]
HARMONIC_CA = math.pi**2 / 2     # the simple harmonic law's peak acceleration coefficient (Rothbart, eq. 2.49)


def balanced(ops=BALANCE_OPS):
    return Cyclogram(operations=ops, windows=[{"from": "a", "to": "c", "max_deg": 200.0}],
                     maximize="least_scaled_angle", least_angle_of=["push", "lift"], speed_rpm=60.0)


def test_the_largest_peak_acceleration_is_minimised_in_closed_form():
    """t1 + t2 = 200 deg with a1 = a2, a_i = Ca_i h_i (6 n)^2 / t_i^2: t_i = 200 r_i / (r_1 + r_2),
    r_i = sqrt(Ca_i h_i) (h in m); at 60 rpm both peaks are (360 (r_1 + r_2) / 200)^2 m/s^2."""
    r1, r2 = math.sqrt(CYCLOID_CA * 0.050), math.sqrt(HARMONIC_CA * 0.030)
    t1, t2 = 200.0 * r1 / (r1 + r2), 200.0 * r2 / (r1 + r2)
    peak = (360.0 * (r1 + r2) / 200.0) ** 2
    r = plan_motions(balanced())
    assert r.status is Status.SOLVED, r.message
    v = r.values
    assert v["t_a_b_deg"] == pytest.approx(t1, rel=1e-9) and v["t_b_c_deg"] == pytest.approx(t2, rel=1e-9)
    assert v["accel_a_b_m_s2"] == pytest.approx(peak, rel=1e-9)
    assert v["accel_b_c_m_s2"] == pytest.approx(peak, rel=1e-9)
    assert v["highest_peak_accel_m_s2"] == pytest.approx(peak, rel=1e-9)
    assert v["least_scaled_angle_deg_per_sqrt_m"] == pytest.approx(200.0 / (r1 + r2), rel=1e-9)
    # what stops it: the window, named; both motions' rows bind (their peaks equal)
    assert [row["constraint"] for row in r.diagnostics["limited_by"]] == ["window p(c) - p(a) <= 200 deg"]
    assert sorted(r.diagnostics["objective_binds"]) == ["a->b", "b->c"]
    assert "limited by window p(c) - p(a) <= 200 deg" in r.message


def test_a_floor_that_binds_leaves_the_others_equal():
    """The lift at least 120 deg (its floor binds): the push takes the rest, 80 deg, and is the
    largest peak; the floor is named with the window."""
    ops = [dict(op) for op in BALANCE_OPS]
    ops[1]["min_deg"] = 120.0
    r = plan_motions(balanced(ops))
    assert r.status is Status.SOLVED, r.message
    assert r.values["t_a_b_deg"] == pytest.approx(80.0, rel=1e-9)
    assert r.values["highest_peak_accel_m_s2"] == pytest.approx(CYCLOID_CA * 0.050 * (360.0 / 80.0) ** 2, rel=1e-9)
    named = [row["constraint"] for row in r.diagnostics["limited_by"]]
    assert sorted(named) == ['min_angle["lift"] t >= 120 deg', "window p(c) - p(a) <= 200 deg"]


@pytest.mark.parametrize("ops, words", [
    (BALANCE_OPS[:2] + [{"from": "c", "to": "d", "min_deg": 20.0, "name": "rest"}], None),
    ([BALANCE_OPS[0], {"from": "b", "to": "c", "min_deg": 10.0, "name": "lift", "law": "harmonic"}, BALANCE_OPS[2]],
     "least_angle_of[1]='lift': maximize = 'least_scaled_angle' needs its motion law and stroke"),
    ([BALANCE_OPS[0], BALANCE_OPS[1] | {"stroke_mm": None, "stroke_deg": 20.0}, BALANCE_OPS[2]],
     "compares m/s^2 with rad/s^2"),
])
def test_a_scaled_angle_over_motions_it_cannot_compare_is_named(ops, words):
    ops = [{k: v for k, v in op.items() if v is not None} for op in ops]
    if words is None:
        balanced(ops)
        return
    with pytest.raises(ModelError) as exc:
        balanced(ops)
    assert words in str(exc.value)
