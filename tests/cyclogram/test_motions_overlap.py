"""Clearances between motions and the least angle maximised in one LP (cyclogram.plan_motions), on the
turret-and-die machine with overlap (Mechanical Design Handbook blog, "Timing Diagram" parts 1-4,
2009: turret 100 mm on a cycloid over 150 deg, die 50 mm down, 100 deg dwell, up; overlapping the
die's strokes with the index makes its acceleration "5 times lower"). The hand calculation below
solves the cycloid's S(x) = c on its own closed form, not through the law library."""
import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from mechopt import registry
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram import max_machine_speed, plan_cyclogram, plan_motions

NO_OVERLAP_STROKE_DEG = (360.0 - 150.0 - 100.0) / 2      # 55 deg (source, part 1)


def cycloid_fraction(c):
    """x with x - sin(2 pi x) / (2 pi) = c (the cycloid's displacement, Rothbart eq. 2.57)."""
    return brentq(lambda x: x - math.sin(2 * math.pi * x) / (2 * math.pi) - c, 0.0, 1.0, xtol=1e-15)


def cycloid(x):
    return x - math.sin(2 * math.pi * x) / (2 * math.pi)


@pytest.fixture(scope="module")
def solved():
    task = registry.find("loom/turret-die-overlap").build()[0]
    return task, plan_motions(task)


def test_the_overlap_is_the_hand_calculation(solved):
    """Between the turret's stop and its next start (210 deg) lie the die's descent after 0.6 of
    its stroke, the dwell and its rise up to 0.4: (1 - x(0.6)) beta + 100 + x(0.4) beta = 210, and
    x(0.4) = 1 - x(0.6) by the cycloid's symmetry: beta = 55 / x(0.4) = 55 / 0.44958 = 122.336 deg."""
    task, r = solved
    x = cycloid_fraction(0.4)
    assert x == pytest.approx(0.44958, abs=1e-5)
    beta = NO_OVERLAP_STROKE_DEG / x
    assert r.status is Status.SOLVED, r.message
    assert r.values["least_angle_deg"] == pytest.approx(beta, rel=1e-9)
    assert r.values["t_top_bottom_deg"] == pytest.approx(beta, rel=1e-9)
    assert r.values["t_lift_up_deg"] == pytest.approx(beta, rel=1e-9)
    # the same speed, the same law and stroke: a ~ 1 / beta^2; the source's "about 5 times lower"
    no_overlap = max_machine_speed(registry.find("loom/turret-die-speed").build()[0])
    ratio = no_overlap.values["accel_stopped_bottom_m_s2"] / r.values["accel_top_bottom_m_s2"]
    assert ratio == pytest.approx((beta / NO_OVERLAP_STROKE_DEG) ** 2, rel=1e-9)
    assert round(ratio) == 5 and ratio == pytest.approx(4.9475, abs=1e-4)


def test_the_die_is_clear_of_the_turret_where_the_table_says(solved):
    """At the turret's stop the die is 0.6 of the way down; at the next index's start (360 deg on)
    it has risen 0.4 of the way: the displacements read off the closed form at the solved times."""
    _, r = solved
    v = r.values
    down = cycloid((v["p_stopped_deg"] - v["p_top_deg"]) / v["t_top_bottom_deg"])
    up = cycloid((v["p_start_deg"] + 360.0 - v["p_lift_deg"]) / v["t_lift_up_deg"])
    assert down == pytest.approx(0.6, abs=1e-9) and up == pytest.approx(0.4, abs=1e-9)
    assert v["p_up_deg"] > 360.0          # the rise runs into the next cycle: posed, not unrolled
    assert "clearance 'turret index' at 1 before 'die down' at 0.6" in r.message


def test_the_other_reading_of_the_face(solved):
    """The face 20 mm into the stroke (c = 0.4 down, 0.6 up): beta = 55 / (1 - x(0.4)), 3.30 times."""
    task, _ = solved
    rows = [dict(row) for row in task.clearances]
    rows[0]["other_at"], rows[1]["at"] = 0.4, 0.6
    r = plan_motions(dataclasses.replace(task, clearances=rows))
    beta = NO_OVERLAP_STROKE_DEG / (1.0 - cycloid_fraction(0.4))
    assert r.values["least_angle_deg"] == pytest.approx(beta, rel=1e-9)
    assert (beta / NO_OVERLAP_STROKE_DEG) ** 2 == pytest.approx(3.3007, abs=1e-4)


def test_the_graph_and_the_speed_solvers_refuse_a_clearance(solved):
    task, _ = solved
    for solve in (plan_cyclogram, lambda t: plan_cyclogram(t, method="lp"), max_machine_speed):
        with pytest.raises(ModelError, match="solved by cyclogram.plan_motions"):
            solve(task)


OPS = [{"from": "a", "to": "b", "min_deg": 90.0, "law": "cycloidal", "name": "push"},
       {"from": "a", "to": "c", "min_deg": 10.0, "name": "wait"},
       {"from": "c", "to": "d", "min_deg": 60.0, "law": "harmonic", "name": "lift"},
       {"from": "b", "to": "e", "min_deg": 0.0}, {"from": "d", "to": "e", "min_deg": 0.0}]


def test_an_after_clearance_is_the_hand_fraction():
    """The lift may reach its half (harmonic: x = 1/2) only after the push reached 0.9 (cycloid):
    the span is then the push's x(0.9) 90 + the lift's half 30 + 30 when the wait is not longer."""
    rows = [{"operation": "lift", "at": 0.5, "relation": "after", "other": "push", "other_at": 0.9}]
    r = plan_motions(Cyclogram(operations=OPS, clearances=rows))
    x = cycloid_fraction(0.9)
    assert r.status is Status.SOLVED
    assert r.values["span_deg"] == pytest.approx(x * 90.0 + 30.0, rel=1e-9)


@pytest.mark.parametrize("row, words", [
    ({"operation": "shove", "at": 1, "relation": "before", "other": "lift", "other_at": 0}, "no such operation"),
    ({"operation": "push", "at": 1.5, "relation": "before", "other": "lift", "other_at": 0}, "allowed [0, 1]"),
    ({"operation": "wait", "at": 0.5, "relation": "before", "other": "lift", "other_at": 0}, "needs the motion law"),
    ({"operation": "push", "at": 1, "relation": "while", "other": "lift", "other_at": 0}, "allowed before, after"),
    ({"operation": "push", "at": 1, "relation": "before", "other": "lift"}, "missing other_at"),
    ({"operation": "push", "at": 1, "relation": "before", "other": "lift", "other_at": 0, "cycles": 1},
     "cycle_deg: a clearance"),
])
def test_a_bad_clearance_is_named(row, words):
    with pytest.raises(ModelError) as exc:
        Cyclogram(operations=OPS, clearances=[row])
    assert words in str(exc.value)


def test_least_angle_needs_its_operations():
    with pytest.raises(ModelError, match="least_angle_of"):
        Cyclogram(operations=OPS, maximize="least_angle")
    with pytest.raises(ModelError, match="maximize='longest': allowed least_angle"):
        Cyclogram(operations=OPS, maximize="longest", least_angle_of=["push"])


def test_the_timing_diagram_draws_the_overlapped_motions():
    """A panel per mechanism; the die's curve over one cycle is the closed-form cycloid folded from
    the next cycle: 30 mm at the turret's stop (150 deg) and at 0/360 deg, 50 mm at the dwell."""
    from mechopt.figures.cyclogram import motions

    run = registry.run(registry.find("loom/turret-die-overlap"))
    figures = motions(run)
    assert set(figures) == {"cyclogram", "timing_diagram"}
    turret_ax, die_ax = figures["timing_diagram"].axes
    theta, die = (die_ax.lines[0].get_xdata(), die_ax.lines[0].get_ydata())
    assert "die" in die_ax.get_ylabel() and "turret" in turret_ax.get_ylabel()
    for angle, mm in ((150.0, 30.0), (0.0, 30.0), (360.0, 30.0), (250.0, 50.0)):
        assert float(np.interp(angle, theta, die)) == pytest.approx(mm, abs=0.05)
    rows = [t.get_text() for t in figures["cyclogram"].axes[0].get_yticklabels()]
    assert not any("die done" in r for r in rows)          # a zero-angle link row is not drawn


def test_an_infeasible_plan_names_the_rows_that_conflict(solved):
    """Die strokes of at least 125 deg, past the 122.34 the clearances allow: the two clearances
    conflict (either dropped leaves a schedule); the die's own repetition (350 deg) still fits."""
    task, _ = solved
    ops = [dict(op) for op in task.operations]
    for op in ops:
        if op.get("name") in ("die down", "die up"):
            op["min_deg"] = 125.0
    r = plan_motions(dataclasses.replace(task, operations=ops))
    assert r.status is Status.INFEASIBLE
    assert r.message.startswith("infeasible: the operations' bounds with the rows ")
    assert "clearance 'turret index' at 1 before 'die down' at 0.6" in r.message
    assert "clearance 'die up' at 0.4 before 'turret index' at 0 of 1 cycle later" in r.message


def test_the_cyclogram_marks_the_rows_that_bind():
    """At the answer the two clearances, the index's fixed 150 deg and the dwell's 100 deg bind:
    the bars of the turret's index, the dwell and both die strokes (the clearances' other sides)
    are marked binding, the die strokes also as the objective's; the die's wait is not."""
    from mechopt.figures.cyclogram import motions

    run = registry.run(registry.find("loom/turret-die-overlap"))
    ax = motions(run)["cyclogram"].axes[0]
    gids = {p.get_gid().split()[1]: set(p.get_gid().split()[2:]) for p in ax.patches
            if (p.get_gid() or "").startswith("operation ")}
    assert gids == {"start->stopped": {"binding"}, "bottom->lift": {"binding"}, "top->bottom": {"binding", "objective"},
                    "lift->up": {"binding", "objective"}, "start->top": set(), "stopped->end": set()}
    marked = [p for p in ax.patches if "binding" in (p.get_gid() or "")]
    assert all(p.get_linewidth() == 2.5 for p in marked)
    assert [t.get_text() for t in ax.get_legend().get_texts()][0] == "bound at the answer"


def test_a_binding_window_between_events_is_drawn_over_its_span():
    """A window from the push's start to the lift's end (no operation joins them) binds: an orange
    line from p(a) to p(c)."""
    from types import SimpleNamespace

    from mechopt.figures.cyclogram import gantt

    ops = [{"from": "a", "to": "b", "min_deg": 10.0, "name": "push", "law": "cycloidal", "stroke_mm": 50.0},
           {"from": "b", "to": "c", "min_deg": 10.0, "name": "lift", "law": "harmonic", "stroke_mm": 30.0}]
    task = Cyclogram(operations=ops, windows=[{"from": "a", "to": "c", "max_deg": 200.0}],
                     maximize="least_angle", least_angle_of=["push", "lift"])
    r = plan_motions(task)
    fig = gantt(SimpleNamespace(task=task, result=r, scene=SimpleNamespace(id="test/window")))["cyclogram"]
    line = next(ln for ln in fig.axes[0].lines if ln.get_gid() == "window a->c binding")
    assert list(line.get_xdata()) == pytest.approx([0.0, 200.0])
