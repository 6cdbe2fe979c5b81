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
    from mechopt.figures.loom import timing_diagram

    task = Cyclogram(operations=ops(), cycle_deg=360.0)
    run = SimpleNamespace(task=task, result=plan_motions(task), scene=SimpleNamespace(id="test/angular"))
    fig = timing_diagram(run)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["feed [mm]", "feed [deg]"]
    assert max(fig.axes[1].lines[0].get_ydata()) == pytest.approx(SWING_DEG, abs=1e-9)
    assert max(fig.axes[0].lines[0].get_ydata()) == pytest.approx(40.0, abs=1e-9)
