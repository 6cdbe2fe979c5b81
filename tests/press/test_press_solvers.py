"""Press dynamics solvers: cross-checks against an independent reference, energy, events, hard cases."""
import dataclasses

import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Status, from_ivp, from_rootfinder
from mechopt.models.press import PressDrive
from mechopt.models.press_energy import mean_crank_inertia_kgm2
from mechopt.solvers import press as pd
from mechopt.solvers.press import problem
from mechopt.solvers.press.problem import initial_state, paper_U

PAPER, _ = registry.find("press/kd2322").build()
CUT_WORK_J = (90.93 * 3**5 / 5 - 4 * 3**4 / 4 - 406.8 * 3**3 / 3 + 1075.68 * 3**2 / 2) / 1000   # integral of eq. (1)


def _task(**changes):
    return dataclasses.replace(PAPER, **changes)


RIGID = _task(effects=tuple(e for e in PAPER.effects if e != "belt_elasticity"), belt_stiffness_Nm_rad=None,
              belt_damping_Nms_rad=None)


@pytest.fixture(scope="module")
def reference():
    """One revolution's time by scipy's DOP853 at rtol 1e-13 with its own event location: independent of CVODES."""
    result = pd.ivp(PAPER, method="DOP853", rtol=1e-13, atol=1e-13, duration_s=0.25)
    assert result.status is Status.SOLVED
    return result


def test_events_agree_with_the_independent_reference_to_1e_8(reference):
    got = pd.events(PAPER, tol=1e-12, duration_s=0.25)
    assert got.status is Status.SOLVED
    assert got.values["final_phi_rad"] == pytest.approx(reference.values["final_phi_rad"], abs=1e-8)
    assert got.values["final_omega_rad_s"] == pytest.approx(reference.values["final_omega_rad_s"], abs=1e-8)
    assert got.values["cut_work_J"] == pytest.approx(CUT_WORK_J, rel=1e-8)     # one whole cut, once


def test_every_solver_balances_energy_to_1e_6():
    for result in (pd.events(PAPER, duration_s=0.3), pd.steady_state(PAPER), pd.events(RIGID, duration_s=0.3)):
        assert result.status is Status.SOLVED, result.message
        v = result.values
        assert v["energy_residual"] < 1e-6
        # the terms themselves, independently: friction work = M_tr x angle turned
        turned = v["final_phi_rad"]          # every run starts at phi = 0
        assert v["friction_work_J"] == pytest.approx(PAPER.friction_torque_Nm * turned, rel=1e-8)


def test_rk4_stalls_at_first_order_across_the_jump_but_is_fourth_order_without_a_cut(reference):
    errors = []
    for step in (1e-3, 5e-4, 2.5e-4):
        r = pd.rk4(PAPER, step_s=step, duration_s=0.25, refine_tol_rad=0.0)
        errors.append(abs(r.values["final_phi_rad"] - reference.values["final_phi_rad"]))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(rates < 2.5), rates                     # first order (noisy: where the jump falls in a step)
    smooth = _task(effects=tuple(e for e in PAPER.effects if e != "cutting_force"),
                   **{k: None for k in PressDrive.EFFECTS["cutting_force"].params})
    ref = pd.ivp(smooth, method="DOP853", rtol=1e-13, atol=1e-13, duration_s=0.25).values["final_phi_rad"]
    err = [abs(pd.rk4(smooth, step_s=s, duration_s=0.25, refine_tol_rad=0.0).values["final_phi_rad"] - ref)
           for s in (1e-3, 5e-4)]     # h below a third of the 59 Hz belt mode's period / 2 pi: asymptotic
    assert err[0] / err[1] == pytest.approx(16, rel=0.15)     # O(h^4) when nothing jumps


def test_rk4_refines_its_step_until_two_runs_agree():
    r = pd.rk4(PAPER, step_s=1e-3, duration_s=0.25, refine_tol_rad=1e-5, max_halvings=6)
    assert r.diagnostics["last_change_rad"] <= 1e-5 and r.values["step_s"] < 1e-3
    # phi has settled, yet the step across the jump still mis-counts the cutting work: that is flagged
    if abs(r.values["cuts"] - 1) > 1e-3:
        assert r.status is Status.INACCURATE and r.violated == ("cut_work",)
    else:
        assert r.status is Status.SOLVED
    short = pd.rk4(PAPER, step_s=1e-3, duration_s=0.25, refine_tol_rad=1e-12, max_halvings=1)
    assert short.status is Status.INACCURATE and "still moved phi" in short.message


def test_steady_state_is_the_limit_of_the_start_up():
    steady = pd.steady_state(PAPER)
    run = registry.run(registry.find("press/start-up")).result
    for key in ("omega_mean_rad_s", "speed_fluctuation", "peak_belt_torque_Nm"):
        if key == "peak_belt_torque_Nm":
            assert run.values[key] > steady.values[key]          # start-up torque exceeds the running one
        else:
            assert run.values[key] == pytest.approx(steady.values[key], rel=1e-5), key
    assert steady.values["periodicity_residual"] < 1e-8


def test_events_are_located_on_the_cut_window_angles():
    r = pd.events(PAPER, duration_s=0.6)
    start, end = np.degrees(PAPER.cut_window_rad())
    kinds = [e[0] for e in r.diagnostics["events"]]
    assert kinds[:3] == ["cut_start", "cut_end", "revolution"]
    for kind, _, deg in r.diagnostics["events"]:
        expect = {"cut_start": start, "cut_end": end, "revolution": 0.0}[kind]
        assert (deg - expect) % 360 == pytest.approx(0.0, abs=1e-9) or (deg - expect) % 360 == pytest.approx(360.0)
    assert r.values["cuts"] == pytest.approx(r.values["cut_windows"], abs=1e-6)


# --- a missed cut must be caught -------------------------------------------------------------------

def test_a_loose_adaptive_solver_that_steps_over_the_cut_is_caught():
    missed = pd.ivp(PAPER, method="BDF", rtol=0.1, atol=1e-2, duration_s=1.0, locate_events=False)
    assert missed.values["cuts"] < 0.5 and missed.values["cut_windows"] == 4     # it never saw the ~12 ms pulse
    assert missed.status is Status.INACCURATE and missed.violated == ("cut_work",)
    assert "a cut was missed" in missed.message


def test_events_cannot_step_over_the_cut_even_with_one_long_piece():
    r = pd.events(PAPER, tol=1e-6, duration_s=1.0, max_step_s=1.0)
    assert r.values["cut_windows"] == 4 and r.values["cuts"] == pytest.approx(4, abs=1e-3)
    assert [e[0] for e in r.diagnostics["events"]].count("cut_end") == 4


# --- hard cases ----------------------------------------------------------------------------------

def test_a_belt_a_million_times_stiffer_behaves_as_the_rigid_drive():
    stiff = _task(belt_stiffness_Nm_rad=PAPER.belt_stiffness_Nm_rad * 1e6)
    a, b = pd.events(stiff, duration_s=0.3), pd.events(RIGID, duration_s=0.3)
    assert a.status is Status.SOLVED and a.values["energy_residual"] < 1e-6
    assert a.values["final_phi_rad"] == pytest.approx(b.values["final_phi_rad"], abs=1e-7)
    assert a.values["final_omega_rad_s"] == pytest.approx(b.values["final_omega_rad_s"], abs=1e-5)
    unstable = pd.rk4(stiff, step_s=1e-4, duration_s=0.25, refine_tol_rad=0.0)
    assert unstable.status is Status.FAILED and "stability limit" in unstable.message


def test_zero_belt_damping_has_a_periodic_motion_with_no_damping_work():
    r = pd.steady_state(_task(belt_damping_Nms_rad=0.0))
    assert r.status is Status.SOLVED and r.values["damping_work_J"] == 0.0
    assert r.values["energy_residual"] < 1e-6
    assert r.values["cut_work_J"] == pytest.approx(CUT_WORK_J, rel=1e-6)


def test_start_up_breaks_away_once_without_chattering():
    r = pd.events(PAPER, start="rest", duration_s=0.5)
    kinds = [e[0] for e in r.diagnostics["events"]]
    assert kinds[0] == "slip" and kinds.count("slip") == 1 and "stop" not in kinds and "stick" not in kinds
    # it breaks away when the belt torque first exceeds friction (at TDC the weights give no moment)
    t_slip = r.diagnostics["events"][0][1]
    assert 0 < t_slip < 0.01 and r.values["energy_residual"] < 1e-6


def test_a_motor_too_weak_to_cut_stalls_as_a_status():
    # a 25 kg slide: the scene's 55 kg one swings the crank on past the cut and it sticks at ~180 deg instead
    weak = _task(flywheel_inertia_kgm2=1e-4, crank_mass_kg=0.0, motor_breakdown_torque_Nm=1.0, motor_inertia_kgm2=1e-4,
                 tool_mass_kg=25.0)
    r = pd.events(weak, duration_s=0.5)
    assert r.status is Status.INFEASIBLE and r.violated == ("stall",)
    assert "stalls in the cut" in r.message
    start, end = np.degrees(PAPER.cut_window_rad())
    assert start < r.diagnostics["events"][-1][2] < end and r.diagnostics["events"][-1][0] == "stop"


def test_a_crank_that_swings_half_a_turn_and_stops_says_how_far_it_got():
    """The 55 kg slide of the scene falls past the cut with a motor too weak to lift it again."""
    weak = _task(flywheel_inertia_kgm2=1e-4, crank_mass_kg=0.0, motor_breakdown_torque_Nm=1.0, motor_inertia_kgm2=1e-4)
    r = pd.events(weak, duration_s=0.5)
    assert r.status is Status.INFEASIBLE and r.violated == ("stall",)
    turned = float(np.degrees(r.values["final_phi_rad"] - r.arrays["phi_rad"][0]))
    assert 90 < turned < 360 and f"turned only {turned:.1f} deg" in r.message


def test_a_motor_below_friction_never_turns_the_crank():
    r = pd.events(_task(motor_breakdown_torque_Nm=0.3), start="rest", duration_s=0.3)
    assert r.status is Status.INFEASIBLE and r.violated == ("stall",) and "never turned" in r.message
    assert r.values["final_phi_rad"] == 0.0 and r.values["friction_work_J"] == 0.0


def test_a_run_ending_exactly_on_the_jump_counts_the_cut_once():
    first = pd.events(PAPER, duration_s=0.2)
    t_end = next(t for kind, t, _ in first.diagnostics["events"] if kind == "cut_end")
    r = pd.events(PAPER, duration_s=t_end)
    assert r.values["cuts"] == pytest.approx(1.0, abs=1e-7) and r.values["cut_windows"] == 1
    assert r.values["peak_force_N"] == pytest.approx(6823.17, rel=1e-9)     # F(Z) just before the jump
    assert [e[0] for e in r.diagnostics["events"]] == ["cut_start", "cut_end"]


def test_the_papers_switching_function_is_closed_at_the_end_of_the_cut():
    _, end = PAPER.cut_window_rad()
    x = initial_state(PAPER, "nominal")
    at = x.copy()
    at[2] = end
    after = x.copy()
    after[2] = end + 1e-9
    assert paper_U(PAPER, np.vstack([at, after])).tolist() == [1.0, 0.0]


def test_a_blank_of_zero_thickness_gives_a_cycle_with_no_cut():
    r = pd.events(_task(blank_thickness_mm=0.0), duration_s=0.3)
    assert r.status is Status.SOLVED and r.values["cut_work_J"] == 0.0 and r.values["peak_force_N"] == 0.0
    assert r.values["energy_residual"] < 1e-6


def test_blank_thicker_than_the_stroke_allows_is_refused():
    with pytest.raises(ModelError, match=r"blank_thickness_mm=50\.0 plus shortfall_mm=1\.0 is 51\.0 mm, more than"):
        _task(blank_thickness_mm=50.0)


# --- settings and status words --------------------------------------------------------------------

@pytest.mark.parametrize("call, match", [
    (lambda: pd.rk4(PAPER, step_s=3e-4, duration_s=0.25), r"step_s=0\.0003 does not divide duration_s=0\.25"),
    # the ranges the signatures declare, worded as a scene's setting is refused
    (lambda: pd.rk4(PAPER, step_s=0.0), r"^step_s=0\.0: allowed > 0$"),
    (lambda: pd.events(PAPER, tol=0.0), r"^tol=0\.0: allowed > 0 \.\.\. 0\.1$"),
    (lambda: pd.events(PAPER, max_step_s=-1.0), r"^max_step_s=-1\.0: allowed > 0$"),
    (lambda: pd.events(PAPER, samples=0), r"^samples=0: allowed 1 \.\.\. 10,000$"),
    (lambda: pd.events(PAPER, duration_s=0.0), r"^duration_s=0\.0: allowed > 0 \.\.\. 3,600$"),
    (lambda: pd.steady_state(PAPER, tol=-1.0), r"^tol=-1\.0: allowed > 0 \.\.\. 0\.1$"),
])
def test_bad_settings_are_refused(call, match):
    with pytest.raises(SettingError, match=match):
        call()


def test_a_task_that_is_no_press_is_refused():
    with pytest.raises(ModelError, match=r"task=str: expected a PressDrive"):
        pd.events("press")


def test_too_many_events_is_a_limit_not_a_crash():
    r = pd.events(PAPER, duration_s=1.0, max_events=2)
    assert r.status is Status.LIMIT and "max_events=2" in r.message


def test_status_words_map_without_passing_failure_as_success():
    assert from_ivp(0) is Status.SOLVED and from_ivp(1) is Status.SOLVED and from_ivp(-1) is Status.FAILED
    assert from_rootfinder("success") is Status.SOLVED
    assert from_rootfinder("max_iteration_reached") is Status.LIMIT and from_rootfinder("x") is Status.FAILED


# --- figure and benchmark helpers -------------------------------------------------------------------

def test_figure_of_a_press_scene_is_written(tmp_path):
    from mechopt.figures import plot_run
    paths = plot_run(registry.run(registry.find("press/kd2322-rigid-belt")), tmp_path)
    assert [p.name for p in paths] == ["press_kd2322-rigid-belt_cycle.png"] and paths[0].stat().st_size > 20_000


def test_benchmark_interpolates_time_to_accuracy_in_log_log():
    from mechopt.benchmarks.press import at_accuracy, observed_order
    rows = [{"method": "m", "knob": k, "phi_error_rad": e, "wall_s_median": w}
            for k, e, w in ((1e-4, 1e-6, 0.01), (1e-6, 1e-10, 0.04))]
    seconds, extrapolated = at_accuracy(rows)["m"]
    assert seconds == pytest.approx(0.02, rel=1e-12) and not extrapolated      # half-way in log error -> sqrt(0.01*0.04)
    first = [{"method": "rk4 (paper)", "knob": h, "phi_error_rad": 3 * h, "wall_s_median": 1e-6 / h}
             for h in (1e-3, 1e-4, 1e-5)]
    assert observed_order(first) == pytest.approx(1.0)
    seconds, extrapolated = at_accuracy(first)["rk4 (paper)"]
    assert extrapolated and seconds == pytest.approx(1e-6 / (1e-8 / 3), rel=1e-9)


def test_cvodes_running_out_of_steps_is_a_limit_not_a_crash(monkeypatch):
    def exhausted(*args, **kwargs):
        raise RuntimeError("Error in Function::call for 'piece' [IntegratorInternal]: CV_TOO_MUCH_WORK")
    monkeypatch.setattr(problem, "run_piece", exhausted)
    r = pd.events(PAPER, duration_s=0.1)
    assert r.status is Status.LIMIT and "CV_TOO_MUCH_WORK" in r.message
    assert r.values["duration_s"] == 0.0          # what was integrated before the failure: nothing


# --- stalls, stiff belts and sizes: said in the user's terms, before the work ------------------------

def _no_stack(message):
    """A message a user reads: one line, no CasADi call stack, nothing that reads like success."""
    assert "\n" not in message and "Function::" not in message and ".cpp" not in message
    assert not any(word in message.lower() for word in ("solved", "success", "converged to the", "periodic orbit by"))


@pytest.fixture
def integrates_nothing(monkeypatch):
    """Every way the press's solvers integrate or build a revolution fails the test: what is refused
    "at once" is refused before any of them runs (a count of work, where a clock would measure load)."""
    from mechopt.solvers.press import event_driven, fixed_step, periodic, scipy_peer

    def integrated(*args, **kwargs):
        raise AssertionError("integrated before refusing")
    for module, name in ((fixed_step, "_rk4_trace"), (scipy_peer, "solve_ivp"), (scipy_peer, "dynamics_of"),
                         (event_driven, "piece_by_time"), (event_driven, "march"),
                         (periodic, "revolution"), (periodic, "dynamics_of")):
        monkeypatch.setattr(module, name, integrated)


@pytest.mark.parametrize("override, cut_work", [
    ({"motor_breakdown_torque_Nm": 0.5}, CUT_WORK_J),
    ({"blank_thickness_mm": 20.0},
     (90.93 * 20**5 / 5 - 4 * 20**4 / 4 - 406.8 * 20**3 / 3 + 1075.68 * 20**2 / 2) / 1000),
])
def test_a_motor_that_cannot_deliver_the_cycles_work_is_an_infeasible_stall_at_once(override, cut_work,
                                                                                      integrates_nothing):
    run = registry.run(registry.find("press/kd2322"), override)
    r = run.result
    need = cut_work / (2 * np.pi) + 5.0                          # cut work per turn over 2 pi, plus friction
    most = 6.2608 * override.get("motor_breakdown_torque_Nm", 33.0)    # breakdown torque times i
    assert need > most
    assert r.status is Status.INFEASIBLE and r.violated == ("stall",)
    assert r.values["required_mean_torque_Nm"] == pytest.approx(need, rel=1e-12)
    assert r.values["breakdown_torque_at_crank_Nm"] == pytest.approx(most, rel=1e-12)
    assert r.message.startswith(f"the motor cannot deliver the cycle's work: mean load torque {need:.4g} N m at the "
                                f"crank (cut work {cut_work:.4g} J per turn")
    assert f"against breakdown torque {most:.4g} N m (reduced to the crank" in r.message
    _no_stack(r.message)


def test_a_flywheel_that_cannot_carry_the_cut_is_a_stall_not_a_casadi_stack():
    # the motor covers the mean (166 N m of 207) but a 9 mm blank takes 1013 J in 17 degrees of crank angle, more
    # than a 2 kg m2 flywheel can give (625 J from 25 rad/s to rest; the scene's 5 kg m2 would carry it)
    thick = _task(blank_thickness_mm=9.0, flywheel_inertia_kgm2=2.0)
    r = pd.steady_state(thick)
    assert r.values["required_mean_torque_Nm"] < r.values["breakdown_torque_at_crank_Nm"]
    assert r.status is Status.INFEASIBLE and r.violated == ("stall",)
    assert r.message.startswith("no periodic motion: started at the Newton guess") and "stalls in the cut" in r.message
    _no_stack(r.message)
    assert "CV_TOO_MUCH_WORK" in r.diagnostics["casadi_error"]        # the raw text is kept, out of the message
    start, end = np.degrees(thick.cut_window_rad())
    assert start < float(r.message.split("crank angle ")[1].split(" deg")[0]) < end
    # the transient from the nominal speed stalls in the cut too (events' own stall detection)
    transient = pd.events(thick, duration_s=0.5)
    assert transient.status is Status.INFEASIBLE and "stalls in the cut" in transient.message


def test_a_cvodes_failure_keeps_its_stack_out_of_the_message(monkeypatch):
    raw = ("Error in Function::call for 'piece' [IntegratorInternal] at .../casadi/core/function.cpp:1736:\n"
           ".../casadi/interfaces/sundials/cvodes_interface.cpp:403: CVode returned \"CV_CONV_FAILURE\".")
    monkeypatch.setattr(problem, "run_piece", lambda *a, **k: (_ for _ in ()).throw(RuntimeError(raw)))
    r = pd.events(PAPER, duration_s=0.1)
    assert r.status is Status.FAILED and r.diagnostics["casadi_error"] == raw
    assert r.message == "CVODES gave up (CV_CONV_FAILURE: the corrector did not converge) at t = 0 s of 0.1 s"
    _no_stack(r.message)


def _belt_hz(task):
    """The belt mode from the two-inertia eigenproblem (independent of the model's formula)."""
    from scipy.linalg import eigh

    from mechopt.models.press_energy import mean_crank_inertia_kgm2
    M = np.diag([task.motor_inertia_kgm2 * task.gear_ratio**2, mean_crank_inertia_kgm2(task)])
    K = task.belt_stiffness_Nm_rad * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return float(np.sqrt(eigh(K, M, eigvals_only=True).max()) / (2 * np.pi))


def test_a_belt_a_million_times_stiffer_fails_fast_naming_the_mode_and_the_rigid_limit(integrates_nothing):
    stiff = _task(belt_stiffness_Nm_rad=PAPER.belt_stiffness_Nm_rad * 1e6)
    hz = _belt_hz(stiff)
    assert hz == pytest.approx(59017, rel=1e-3)
    run = registry.run(registry.find("press/kd2322"), {"belt_stiffness_Nm_rad": 5e10})
    r = run.result
    assert r.status is Status.LIMIT
    assert r.values["belt_mode_Hz"] == pytest.approx(hz, rel=1e-9)
    assert r.values["step_needed_s"] == pytest.approx(0.1 / hz, rel=1e-9)       # a tenth of the mode's period
    assert r.message.startswith(f"the belt mode at {hz:.4g} Hz needs steps below {0.1 / hz:.3g} s")
    assert "the rigid-belt model (drop effect `belt_elasticity`) is its limit" in r.message
    _no_stack(r.message)
    # RK4 diverges past h |lambda| = 2.83 (undamped; 2.85 with this 5 % damping): refused before the run
    r = pd.rk4(stiff, step_s=1e-4, duration_s=0.25)
    assert r.status is Status.FAILED and "would diverge (beyond its stability limit)" in r.message
    assert 2.8 / (2 * np.pi * hz) < r.values["step_needed_s"] < 2.9 / (2 * np.pi * hz)
    r = pd.ivp(stiff, method="DOP853", duration_s=1.0)
    assert r.status is Status.LIMIT and "more than the 20000 DOP853 can afford" in r.message
    _no_stack(r.message)


def test_the_paper_belt_passes_the_stiffness_guards_with_room():
    assert _belt_hz(PAPER) == pytest.approx(59.02, abs=0.01)
    r = pd.rk4(PAPER, step_s=1e-3, duration_s=0.25, refine_tol_rad=0.0)     # 1 ms: 0.37 rad of the mode per step
    assert r.status is not Status.FAILED and "belt mode" not in r.message and r.values["energy_residual"] < 1e-3
    assert pd.steady_state(PAPER, samples=4).status is Status.SOLVED


@pytest.mark.parametrize("call, match", [
    # pieces per second: one per max_step_s = 0.02 s, three events per turn at 157.08 / 6.2608 rad/s: 61.98
    (lambda: pd.events(PAPER, duration_s=3600.0), r"duration_s=3600\.0 means about 2\.23e\+05 CVODES pieces .*more "
                                                  r"than the 50000 allowed \(duration_s <= 806\.7 s with max_step_s"),
    (lambda: pd.events(PAPER, duration_s=10.0, samples=10_000), r"samples=10000 means about 6\.2e\+06 samples in "
                                                               r"memory, more than the 1e\+06 allowed \(samples <= 1613 "),
    (lambda: pd.rk4(PAPER, step_s=1e-9), r"step_s=1e-09 with duration_s=1\.0 means 1e\+09 RK4 steps; allowed at most "
                                         r"500000 \(step_s >= 2e-06 s\)"),
    (lambda: pd.ivp(PAPER, duration_s=3600.0), r"duration_s=3600\.0 means about 1\.44e\+04 revolutions .* "
                                               r"\(duration_s <= 25\.04 s; `events` goes further\)"),
    (lambda: pd.ivp(PAPER, max_step_s=1e-9), r"max_step_s=1e-09 means about 1e\+09 steps, more than the 20000 allowed \(max_step_s >= 5e-05 s"),
])
def test_work_past_the_stated_limits_is_refused_before_it_starts(call, match, integrates_nothing):
    with pytest.raises(SettingError, match=match):
        call()


def test_a_set_override_past_the_limits_is_refused_naming_the_key():
    with pytest.raises(SettingError, match=r"duration_s=3600\.0 means about"):
        registry.run(registry.find("press/start-up"), {"duration_s": 3600.0})
    from mechopt.kit.errors import SceneError
    with pytest.raises(SceneError, match=r"max_events"):
        registry.run(registry.find("press/start-up"), {"max_events": 10**7})


def test_a_press_that_coasts_to_a_stop_is_a_stall_with_the_torques_that_explain_it():
    # 35 turns on the energy of a 2 kg m2 flywheel; with a 25 kg slide, whose weight cannot swing the stopped crank
    # past friction (the scene's 55 kg one rocks it back into the cut: a stall in the cut, tested above)
    r = pd.events(_task(motor_breakdown_torque_Nm=0.5, flywheel_inertia_kgm2=2.0, tool_mass_kg=25.0), duration_s=20.0)
    kinds = [e[0] for e in r.diagnostics["events"]]
    assert kinds[-2:] == ["stop", "stick"] and r.values["final_omega_rad_s"] == 0.0
    assert r.status is Status.INFEASIBLE and r.violated == ("stall",)
    assert r.message.startswith("the press coasted to a stop: static friction holds the crank at")
    assert "; the motor cannot deliver the cycle's work: mean load torque 5.878 N m" in r.message
    assert r.values["breakdown_torque_at_crank_Nm"] == pytest.approx(6.2608 * 0.5, rel=1e-12)


def test_rk4_and_ivp_name_the_same_stall_in_the_cut():
    thick = _task(blank_thickness_mm=9.0, flywheel_inertia_kgm2=2.0)       # as in the steady_state stall above
    a = pd.rk4(thick, step_s=1e-5, duration_s=0.2, refine_tol_rad=0.0)
    b = pd.ivp(thick, duration_s=0.2)
    angles = []
    for r in (a, b):
        assert r.status is Status.INFEASIBLE and r.violated == ("stall",)
        assert r.message.startswith("the press stalls in the cut at crank angle")
        angles.append(float(r.message.split("crank angle ")[1].split(" deg")[0]))
    start, end = np.degrees(thick.cut_window_rad())
    assert start < angles[1] < end and angles[0] == pytest.approx(angles[1], abs=0.01)


def test_events_refuses_a_belt_it_would_follow_for_minutes_before_any_work(integrates_nothing):
    """Formerly belt_stiffness 1e12 under `events` took 94 s; the estimate (10 steps a period of the
    264 kHz belt mode over 3 s: 7.9e6) refuses it at once, naming the key and the stiffest belt that fits."""
    task = dataclasses.replace(registry.find("press/start-up").build()[0], belt_stiffness_Nm_rad=1e12)
    with pytest.raises(ModelError, match=r"belt_stiffness_Nm_rad <= 3.99e\+09 at duration_s=3") as refused:
        pd.events(task, duration_s=3.0, start="rest")
    assert refused.value.key == "belt_stiffness_Nm_rad"
    hz = np.sqrt(1e12 * (1 / mean_crank_inertia_kgm2(task) + 1 / (task.motor_inertia_kgm2 * task.gear_ratio**2)))
    assert f"{hz / (2 * np.pi):.4g} Hz" in str(refused.value)       # undamped; damping 15 moves it < 1e-6


@pytest.mark.parametrize("turns", [224, 257, 5000])
def test_events_far_from_phi_zero_are_located_relative_to_the_angle(monkeypatch, turns):
    """A minute of start-up reaches 1445 rad, where doubles are 2.3e-13 apart and an absolute
    1e-12 rad was at times out of Newton's reach (LIMIT). From these turns (each a LIMIT under the old
    absolute rule, the first check below) the events are located relative to the angle."""
    iphi = PAPER.state_names.index("phi_rad")
    x = initial_state(PAPER, "nominal")
    x[iphi] = turns * 2 * np.pi + 0.5
    piece = problem.piece_by_time(PAPER, 1e-10, 8)
    with monkeypatch.context() as absolute:
        absolute.setattr(problem, "ANGLE_ULPS", 0)
        with pytest.raises(problem.Limit, match="not located"):
            problem.march(PAPER, piece, problem.Trace(), x.copy(), 0.3, 0.02, 1000)
    trace = problem.Trace()
    problem.march(PAPER, piece, trace, x, 0.3, 0.02, 1000)
    kinds = [e[0] for e in trace.events]
    assert kinds.count("revolution") == 1 and kinds.count("cut_start") == kinds.count("cut_end") == 1
    assert trace.t[-1][-1] == pytest.approx(0.3, rel=1e-12)
    assert problem.angle_tol(1445.0) == pytest.approx(64 * np.spacing(1445.0)) and problem.angle_tol(1.0) == 1e-12


def test_the_nominal_speed_under_a_motor_is_said_to_be_a_start_guess_only():
    fast = dataclasses.replace(PAPER, nominal_speed_rad_s=1000.0)
    same, said = pd.steady_state(PAPER), pd.steady_state(fast)
    assert said.values["omega_mean_rad_s"] == pytest.approx(same.values["omega_mean_rad_s"], rel=1e-9)
    assert "nominal_speed_rad_s=1000 is a start speed and guess only" in said.message
    assert "nominal_speed_rad_s" not in same.message          # 25 rad/s lies in the motor's working range


def test_a_what_if_re_solves_on_the_structures_build_from_the_last_orbit():
    """Other numbers, same structure: no new build (equations, revolution), the orbit
    warm-started from the last one by chord steps, and the same orbit as a cold solve."""
    from mechopt.kit.cache import clear
    from mechopt.models.press_equations import equations
    pd.steady_state(PAPER)
    builds = len(equations.cache), len(problem.revolution.cache)
    what = dataclasses.replace(PAPER, belt_stiffness_Nm_rad=6e4, flywheel_inertia_kgm2=5.5)
    warm = pd.steady_state(what)
    assert warm.status is Status.SOLVED and warm.diagnostics["warm_start"]
    assert (len(equations.cache), len(problem.revolution.cache)) == builds
    assert warm.values["periodicity_residual"] <= 100 * 1e-10 and "chord steps" in warm.message
    clear()
    cold = pd.steady_state(what)
    assert cold.status is Status.SOLVED and not cold.diagnostics["warm_start"]
    for key in ("omega_mean_rad_s", "speed_fluctuation", "peak_belt_torque_Nm", "motor_work_J"):
        assert warm.values[key] == pytest.approx(cold.values[key], rel=1e-8), key


def test_a_far_what_if_converges_by_broyden_steps_instead_of_a_cold_newton_solve():
    """A flywheel 50 % heavier than the last orbit's: with the old monodromy alone the chord steps
    contract by ~0.08 each and ran out (CHORD_STEPS) into the cold solve; Broyden's update of the
    Jacobian from each step's secant converges within them, to the cold solve's orbit."""
    from mechopt.kit.cache import clear
    pd.steady_state(PAPER)
    heavier = dataclasses.replace(PAPER, flywheel_inertia_kgm2=7.5)
    warm = pd.steady_state(heavier)
    assert warm.status is Status.SOLVED and warm.diagnostics["warm_start"], warm.message
    assert warm.diagnostics["newton_iterations"] <= 3
    clear()
    cold = pd.steady_state(heavier)
    assert not cold.diagnostics["warm_start"]
    for key in ("omega_mean_rad_s", "speed_fluctuation", "peak_belt_torque_Nm"):
        assert warm.values[key] == pytest.approx(cold.values[key], rel=1e-8), key
