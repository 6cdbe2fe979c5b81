"""The lift cam as a groove (closure "groove"): N < 0 is a crossover to the other wall across the
backlash, located, with its flight and impact, not a lift-off; the hybrid model with the backlash."""
import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mechopt import registry
from mechopt.kit.errors import MechoptError
from mechopt.kit.result import Status
from mechopt.models.cam_follower import rise_duration_s
from mechopt.models.cam_law import SplineBasis
from mechopt.solvers.stop_impact.cam_follower import follow_cam
from mechopt.solvers.stop_impact.groove import (
    follow_groove,
    follow_groove_exact,
    follow_groove_ivp,
    rebound_with_backlash_mm,
)
from mechopt.solvers.stop_impact.law import CHAIN_RELTOL, approach_velocity_m_s, rebound_amplitude_mm

BACKLASH_MM = 0.05


@pytest.fixture(scope="module")
def force():
    return registry.find("stop-impact/amplitude-law").build()[0]     # the cycloid, closure 1500 N, "force"


@pytest.fixture(scope="module")
def groove(force):
    return dataclasses.replace(force, closure="groove", backlash_mm=BACKLASH_MM)


def cycloid(xi):
    """S, S', S'' of the cycloid by hand (not the library's)."""
    w = 2 * math.pi
    return xi - math.sin(w * xi) / w, 1 - math.cos(w * xi), w * math.sin(w * xi)


def hand_groove(task, speed_rpm, delta_mm, law=cycloid):
    """By hand in physical time [s] and absolute x [m]: C driven through the link c, b by the wall
    it rides (the inner wall s, the outer s + delta) while N = F + m x'' has that wall's sign
    (DOP853 events on N); in flight m x'' = -F and the massless roller r follows through the link,
    c (r - x) + b (r' - x') = -F, until r meets a wall (events); to the plate x = H - preload.
    Returns ([(leave xi, land xi, wall landed on, impact m/s), ...], contact xi, v0 [m/s])."""
    T = float(rise_duration_s(speed_rpm, task.t_deg))
    H, m, F = task.stroke_mm * 1e-3, task.mass_kg, task.closure_force_N
    c = task.c_free_N_per_m
    b = 2 * task.damping_ratio * math.sqrt(c * m)
    delta, plate_x = delta_mm * 1e-3, H - task.preload_mm * 1e-3

    def wall(t):
        if t >= T:
            return H, 0.0
        S, dS, _ = law(t / T)
        return H * S, H * dS / T

    def driven(offset):
        def f(t, y):
            s, ds = wall(t)
            return [y[1], (c * (s + offset - y[0]) + b * (ds - y[1])) / m]
        return f

    def free(t, y):          # x, x', r
        return [y[1], -F / m, y[1] + (-F - c * (y[2] - y[0])) / b]

    def plate(t, y):
        return y[0] - plate_x
    plate.terminal, plate.direction = True, 1
    t, y, on, flights = 0.0, np.zeros(2), 1, []
    while True:
        offset = 0.0 if on == 1 else delta
        if on * (F + m * driven(offset)(t, y)[1]) >= 0:

            def off(u, z, o=offset):
                return F + m * driven(o)(u, z)[1]
            off.terminal, off.direction = True, -on
            run = solve_ivp(driven(offset), (t, 3 * T), y, method="DOP853", rtol=1e-12, atol=1e-16,
                            events=(plate, off), first_step=1e-9)
            if run.t_events[0].size:
                return flights, run.t_events[0][0] / T, run.y_events[0][0][1]
            t, y = run.t_events[1][0], run.y_events[1][0]

        def outer(u, z, o=delta if on == 1 else 0.0):
            return z[2] - wall(u)[0] - o
        outer.terminal, outer.direction = True, on

        def back(u, z, o=offset):
            return z[2] - wall(u)[0] - o
        back.terminal, back.direction = True, -on
        fly = solve_ivp(free, (t, 3 * T), [*y, wall(t)[0] + offset], method="DOP853", rtol=1e-12, atol=1e-16,
                        events=(plate, outer, back), first_step=1e-9)
        k = min((e[0], i) for i, e in enumerate(fly.t_events) if e.size)[1]
        if k == 0:
            return flights, fly.t_events[0][0] / T, fly.y_events[0][0][1]
        t1, z = fly.t_events[k][0], fly.y_events[k][0]
        landed = -on if k == 1 else on
        flights.append((t / T, t1 / T, ("outer", "inner")[landed == 1], abs(free(t1, z)[2] - wall(t1)[1])))
        t, y, on = t1, z[:2], landed


def test_the_groove_gives_a_crossover_where_the_force_closure_leaves_the_cam(force, groove):
    """At 600 rpm the 1500 N closure is short (force: INFEASIBLE, the roller leaves the cam); in the
    groove the same point is a crossover: SOLVED, C meets its plate, the rebound computed."""
    left = follow_cam(force, 600.0)
    assert left.status is Status.INFEASIBLE and "leaves the cam" in left.message
    rise = follow_cam(groove, 600.0)
    assert rise.status is Status.SOLVED and rise.contact_xi is not None
    assert rise.crossovers and rise.crossovers[0].xi == pytest.approx(left.leaves_cam_xi, abs=1e-12)
    assert "crossover" in rise.message and "leaves the cam" not in rise.message
    assert rebound_amplitude_mm(groove, 600.0, groove.t_deg) > 0.1      # computed, not refused


@pytest.mark.parametrize("speed, closure_N", [(600.0, None), (520.0, None), (420.0, 0.0)])
def test_the_crossover_and_its_impact_agree_with_a_hand_flight(groove, speed, closure_N):
    """The chain's first crossover (CVODES, bisection) and its flight (closed form) against a hand
    DOP853 in physical time (the cycloid by hand, events on N and on the walls): the crossover's
    angle, where the roller lands, on which wall, and its impact speed. 600 rpm lands on the outer
    wall, 520 rpm falls back on its own wall; 420 rpm in a bare groove (F = 0) crosses mid-rise."""
    task = groove if closure_N is None else dataclasses.replace(groove, closure_force_N=closure_N)
    first = follow_cam(task, speed).crossovers[0]
    flights, _, _ = hand_groove(task, speed, BACKLASH_MM)
    xi_c, xi_land, wall, impact = flights[0]
    assert first.xi == pytest.approx(xi_c, abs=1e-8)          # CVODES at reltol 1e-10
    assert first.lands_xi == pytest.approx(xi_land, abs=1e-7)
    assert first.lands_on == wall
    assert first.impact_m_s == pytest.approx(impact, rel=1e-5)


@pytest.mark.parametrize("speed", [520.0, 600.0])
def test_the_hybrid_rise_with_the_backlash_agrees_with_a_hand_one(groove, speed):
    """The hybrid model (solvers/stop_impact/groove.py, in the rise's own time) against the hand
    DOP853 in physical time: every flight (where, which wall, impact) and C's approach at its plate."""
    real = follow_groove(groove, speed)
    flights, contact, v0 = hand_groove(groove, speed, BACKLASH_MM)
    assert real.status is Status.SOLVED and len(real.flights) == len(flights)
    for (x0, x1, _, landed, impact), hand in zip(real.flights, flights):
        assert (x0, x1) == pytest.approx(hand[:2], abs=1e-8)
        assert ("outer", "inner")[landed == 1] == hand[2] and impact == pytest.approx(hand[3], rel=1e-6)
    assert real.contact_xi == pytest.approx(contact, abs=1e-9)
    assert real.approach_velocity_m_s == pytest.approx(v0, rel=1e-7)


def spline_cycloid():
    """A synthesised-type law: a cubic B-spline on 16 intervals through the cycloid at its
    Greville abscissae (S's third derivative jumps at its knots, the batch path's joins)."""
    basis = SplineBasis(16)
    t, p, fixed = basis.knots, basis.degree, basis.continuity + 1
    grev = np.array([t[i + 1:i + p + 1].mean() for i in range(t.size - p - 1)])
    return basis.law([cycloid(x)[0] for x in grev[fixed:grev.size - fixed]])


@pytest.mark.parametrize("backlash_mm, closure_N, speed, spline, flights", [
    (0.05, 1500.0, 400.0, False, 0), (0.05, 1500.0, 520.0, False, 1), (0.2, 300.0, 800.0, False, 1),
    (0.5, 1500.0, 600.0, False, 1), (0.05, 1500.0, 520.0, True, 0), (0.05, 1500.0, 600.0, True, 1)])
def test_the_exact_groove_rise_is_the_dop853_hybrid(groove, backlash_mm, closure_N, speed, spline, flights):
    """follow_groove (each phase by its exact solution) against follow_groove_ivp (DOP853 with
    events, here at rtol 1e-13; at its own 1e-11 it errs by ~1e-9 in v0, ~1e-6 on a synthesised
    law): the same flights, walls landed on, impacts and contact, on the cycloid and a spline."""
    task = dataclasses.replace(groove, backlash_mm=backlash_mm, closure_force_N=closure_N,
                               **({"law": spline_cycloid()} if spline else {}))
    exact, ivp = follow_groove(task, speed), follow_groove_ivp(task, speed, rtol=1e-13)
    assert exact.status is ivp.status is Status.SOLVED and exact.message == ivp.message
    assert len(exact.flights) == len(ivp.flights) == flights
    for a, b in zip(exact.flights, ivp.flights):
        assert a[2:4] == b[2:4] and a[:2] == pytest.approx(b[:2], abs=1e-10)
        assert a[4] == pytest.approx(b[4], rel=1e-8)
    assert exact.contact_xi == pytest.approx(ivp.contact_xi, abs=1e-10)
    assert exact.approach_velocity_m_s == pytest.approx(ivp.approach_velocity_m_s, rel=1e-9)


def test_the_exact_groove_rise_leaves_what_it_cannot_take_to_dop853(groove):
    """Past the exact path's limits (here zeta >= 1: no oscillatory Duhamel kernel) follow_groove
    is the DOP853 hybrid itself."""
    task = dataclasses.replace(groove, damping_ratio=1.2)
    assert follow_groove(task, 600.0) == follow_groove_ivp(task, 600.0)


def test_the_hybrid_with_a_vanishing_backlash_is_the_chain(groove):
    """The hybrid model (DOP853, walls offset by the backlash) tends to the chain's backlash-free
    approach as the backlash shrinks; at 0.05 mm it moves the approach at 520 rpm."""
    chain = follow_cam(groove, 520.0).approach_velocity_m_s
    tiny = follow_groove(dataclasses.replace(groove, backlash_mm=1e-6), 520.0)
    assert tiny.status is Status.SOLVED and tiny.approach_velocity_m_s == pytest.approx(chain, rel=1e-5)
    rebound, real = rebound_with_backlash_mm(groove, 520.0)
    assert real.flights and abs(real.approach_velocity_m_s / chain - 1) > 0.01
    assert rebound > 0


def test_the_groove_needs_its_backlash_and_only_it(force):
    with pytest.raises(MechoptError, match="backlash_mm"):
        dataclasses.replace(force, closure="groove")
    with pytest.raises(MechoptError, match="backlash_mm=0.05 belongs to closure='groove'"):
        dataclasses.replace(force, backlash_mm=0.05)
    with pytest.raises(MechoptError, match="closure"):
        dataclasses.replace(force, closure="spring")
    with pytest.raises(MechoptError, match="backlash_mm"):
        dataclasses.replace(force, closure="groove", backlash_mm=50.0)


def test_the_scenes_crossovers_are_the_hand_flights():
    """stop-impact/cam-dynamics-groove's crossovers against the hand DOP853 (physical time, the
    cycloid by hand): their count, the first's cam angle and the largest impact at 520 and 600 rpm."""
    run = registry.run("stop-impact/cam-dynamics-groove").result
    task = registry.find("stop-impact/cam-dynamics-groove").build()[0]
    assert run.status is Status.SOLVED, run.message
    for speed in (520.0, 600.0):
        flights, contact, _ = hand_groove(task, speed, task.backlash_mm)
        before = [f for f in flights if f[0] < contact]
        tag = f"{speed:g}"
        assert run.values[f"crossovers_{tag}"] == len(before) == 1
        assert run.values[f"crossover_angle_deg_{tag}"] == pytest.approx(before[0][0] * task.t_deg, rel=1e-8)
        assert run.values[f"crossover_impact_max_m_s_{tag}"] == pytest.approx(before[0][3], rel=1e-5)


def test_the_synthesis_keeps_the_roller_on_its_driving_wall_in_a_groove_too(force, groove):
    """The window LP's rows holding N >= 5 % of the closure are the same under both closures,
    named for what they prevent (lift-off / a crossover, whose flight the LP's linear lever does
    not hold): one LP, one law."""
    from mechopt.solvers.stop_impact import window_lp
    lp_lever = window_lp.linear_lever(16, 2)
    lines = window_lp.rebound_envelope(force, 4 * window_lp.v0_limit_m_s(dataclasses.replace(force, amplitude_limit_mm=0.1), 0.1))
    built = {}
    for task in (force, groove):
        speeds = [window_lp.speed_response(task, lp_lever, n, 31.0) for n in (280.0, 420.0)]
        lp = window_lp.WindowLP(task, lp_lever, speeds, 31.0, objective="least_rebound", limit_mm=0.1,
                         bounds={"max_acceleration_mm_per_rad2": 570.0}, lines=lines)
        built[task.closure] = (np.array(lp.rows.family), lp.rows.bounds(), lp.solve(0.85))
    (fam_f, bounds_f, solved_f), (fam_g, bounds_g, solved_g) = built["force"], built["groove"]
    assert (fam_f == "cam_contact").sum() == (fam_g == "no_crossover").sum() > 0
    assert not (fam_g == "cam_contact").any()
    assert np.array_equal(np.where(fam_f == "cam_contact", "held", fam_f), np.where(fam_g == "no_crossover", "held", fam_g))
    assert all(np.array_equal(a, b) for a, b in zip(bounds_f, bounds_g))
    assert solved_f[0] is solved_g[0] is Status.SOLVED and np.array_equal(solved_f[1], solved_g[1])


def test_the_chain_takes_a_crossing_rise_from_the_exact_hybrid_where_cvodes_would_send_it():
    """law._rise_velocity asks the exact hybrid first in a groove: a flight before its contact
    stands for the chain's crossover before the plate (CVODES, follow_cam), which hands the point
    to the same hybrid; on stop-impact/cam-dynamics-groove over speeds and phase angles the two
    tests agree, and v0 is the DOP853 hybrid's where they cross (rtol 1e-13)."""
    task = registry.find("stop-impact/cam-dynamics-groove").build()[0]
    crossing = 0
    for speed in (300.0, 520.0, 700.0):
        for t in (28.0, task.t_deg, 50.0):
            rise, exact = follow_cam(task, speed, t, reltol=CHAIN_RELTOL), follow_groove_exact(task, speed, t)
            chain = bool(rise.crossovers) and (rise.contact_xi is None or rise.crossovers[0].xi < rise.contact_xi)
            assert chain == bool(exact.flights) and exact.status is rise.status is Status.SOLVED
            if chain:
                crossing += 1
                v0 = follow_groove_ivp(task, speed, t, rtol=1e-13).approach_velocity_m_s
                assert approach_velocity_m_s(task, speed, t) == pytest.approx(v0, rel=1e-9)
    assert 0 < crossing < 9, crossing


def test_a_groove_without_a_crossing_takes_the_exact_rise_and_runs_no_cvodes(monkeypatch):
    """Where the exact hybrid has no flight before its contact the roller rides its driving wall
    all the way, the chain's CVODES rise (follow_cam) itself: v0 is the exact rise's, CVODES is
    not run, and the two agree to CVODES' error (rtol 1e-9; stop-impact/cam-dynamics-groove)."""
    import mechopt.solvers.stop_impact.law as law
    task = registry.find("stop-impact/cam-dynamics-groove").build()[0]
    plain = [(n, t) for n in (300.0, 520.0) for t in (task.t_deg, 50.0) if not follow_groove_exact(task, n, t).flights]
    assert plain
    cvodes = {p: follow_cam(task, *p, reltol=CHAIN_RELTOL).approach_velocity_m_s for p in plain}
    law._rise_velocity.cache.clear()

    def refused(*args, **kwargs):
        raise AssertionError("CVODES run where the exact rise has no flight")
    monkeypatch.setattr(law, "follow_cam", refused)
    for n, t in plain:
        v0 = approach_velocity_m_s(task, n, t)
        assert v0 == follow_groove_exact(task, n, t).approach_velocity_m_s
        assert v0 == pytest.approx(cvodes[(n, t)], rel=1e-9)
    law._rise_velocity.cache.clear()
