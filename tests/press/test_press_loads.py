"""Loads over the steady revolution: each against a computation written here
from the crank-slider's geometry, not from the model's code."""
import dataclasses

import numpy as np
import pytest

from mechopt import load
from mechopt.solvers.press import loads


@pytest.fixture(scope="module")
def paper_task():
    return load("press/kd2322").build()[0]          # the press/loads scene's parameters


@pytest.fixture(scope="module")
def exact_task(paper_task):
    return dataclasses.replace(paper_task, kinematics="exact")


def kinematics(task, phi):
    """X', X'' and the rod middle's (x', x'', y', y'') by hand: closed forms of the task's X."""
    r, lam = task.r_m, task.rod_ratio
    s, c = np.sin(phi), np.cos(phi)
    if task.kinematics == "paper":
        d1, d2 = r * (s + lam / 2 * np.sin(2 * phi)), r * (c + lam * np.cos(2 * phi))
    else:
        D = np.sqrt(1 - (lam * s) ** 2)
        d1 = r * s + r * lam * s * c / D
        d2 = r * c + r * lam * ((c**2 - s**2) / D + lam**2 * s**2 * c**2 / D**3)
    return d1, d2, (r * c / 2, -r * s / 2, (r * s + d1) / 2, (r * c + d2) / 2)


def rates(task, a):
    phi, w, acc = a["phi_rad"], a["omega_rad_s"], a["alpha_rad_s2"]
    d1, d2, (xm1, xm2, ym1, ym2) = kinematics(task, phi)
    g = task.gravity_m_s2
    v_tool, a_tool = d1 * w, d2 * w**2 + d1 * acc
    vm = np.array([xm1 * w, ym1 * w])
    P = task.rod_mass_kg * np.array([xm2 * w**2 + xm1 * acc, ym2 * w**2 + ym1 * acc - g])
    return v_tool, a_tool, vm, P


@pytest.mark.parametrize("which", ["paper_task", "exact_task"])
def test_crank_power_is_the_power_into_tool_and_rod_to_1e_9_at_every_sample(which, request):
    """Virtual work: crank torque x omega = Q dX/dt + m_rod (a_mid - g) . v_mid."""
    task = request.getfixturevalue(which)
    result = loads(task)
    assert result.status.value == "SOLVED"
    a = result.arrays
    v_tool, a_tool, vm, P = rates(task, a)
    Q = a["force_N"] + task.tool_mass_kg * (a_tool - task.gravity_m_s2)      # the tool's Newton, by hand
    np.testing.assert_allclose(a["Q_N"], Q, rtol=0, atol=1e-9 * np.max(np.abs(Q)))
    crank_power = a["crank_torque_Nm"] * a["omega_rad_s"]
    into = Q * v_tool + np.sum(P * vm, axis=0)
    np.testing.assert_allclose(crank_power, into, rtol=0, atol=1e-9 * np.max(np.abs(crank_power)))


def test_with_a_massless_rod_crank_power_is_the_rod_force_projected_on_the_tool(exact_task):
    task = dataclasses.replace(exact_task, rod_mass_kg=0.0)
    a = loads(task).arrays
    beta = np.arcsin(task.rod_ratio * np.sin(a["phi_rad"]))        # exact geometry: sin beta = lambda sin phi
    v_tool = rates(task, a)[0]
    power = a["rod_force_N"] * np.cos(beta) * v_tool
    scale = np.max(np.abs(power))
    np.testing.assert_allclose(a["crank_torque_Nm"] * a["omega_rad_s"], power, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(a["rod_force_pin_N"], a["rod_force_N"], rtol=1e-12, atol=1e-9)


def test_rod_force_torque_and_bearing_load_agree_with_a_newton_euler_solve_of_the_linkage(exact_task):
    """Five unknowns (pin force, tool force on the rod, guide force) from the tool's and the rod's
    equations with the rod's ends at their exact positions; numpy solves them sample by sample."""
    task = exact_task
    a = loads(task).arrays
    phi = a["phi_rad"]
    r, l = task.r_m, task.r_m / task.rod_ratio
    v_tool, a_tool, vm, P = rates(task, a)
    A = np.stack([r * np.sin(phi), -r * np.cos(phi)])
    B = np.stack([0 * phi, -(r + l) + a["travel_mm"] / 1000])
    np.testing.assert_allclose(np.hypot(*(A - B)), l, rtol=1e-12)             # the rod keeps its length
    half = (A - B) / 2                                                        # middle to pin; tool: -half
    rows, rhs = [], []
    for k in range(len(phi)):
        # unknowns Ax, Ay, Bx, By, N (guide on tool, across)
        M = np.array([[0, 0, -1, 0, 1],                                      # tool across: -Bx + N = 0
                      [0, 0, 0, -1, 0],                                      # tool along: -By = m(a - g) + F
                      [1, 0, 1, 0, 0], [0, 1, 0, 1, 0],                      # rod: A + B = P
                      [-half[1, k], half[0, k], half[1, k], -half[0, k], 0]])  # moments about the middle
        rows.append(M)
        rhs.append([0, task.tool_mass_kg * (a_tool[k] - task.gravity_m_s2) + a["force_N"][k], P[0, k], P[1, k], 0])
    x = np.linalg.solve(np.array(rows), np.array(rhs)[..., None])[..., 0]
    Ax, Ay, Bx, By = x[:, 0], x[:, 1], x[:, 2], x[:, 3]
    u = (A - B) / l
    scale = np.max(np.abs(a["rod_force_N"]))
    np.testing.assert_allclose(a["rod_force_N"], -(Bx * u[0] + By * u[1]), rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(a["rod_force_pin_N"], Ax * u[0] + Ay * u[1], rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(a["main_bearing_load_N"], np.hypot(Ax, Ay), rtol=0, atol=1e-9 * scale)
    torque = r * (Ax * np.cos(phi) + Ay * np.sin(phi))                       # pin force . pin velocity / omega
    np.testing.assert_allclose(a["crank_torque_Nm"], torque, rtol=0, atol=1e-9 * np.max(np.abs(torque)))


def test_crank_torque_is_what_the_shaft_gives_after_its_own_inertia_and_friction(paper_task):
    """The crank shaft's equation: belt torque - friction - (J + r^2 m_k) alpha goes into the linkage."""
    task = paper_task
    a = loads(task).arrays
    own = task.flywheel_inertia_kgm2 + task.r_m**2 * task.crank_mass_kg
    shaft = a["belt_torque_Nm"] - task.friction_torque_Nm - own * a["alpha_rad_s2"]
    np.testing.assert_allclose(a["crank_torque_Nm"], shaft, rtol=0, atol=1e-9 * np.max(np.abs(shaft)))


def test_peaks_and_where_they_occur_agree_with_a_dense_run(paper_task):
    coarse = loads(paper_task, samples=60)
    dense = loads(paper_task, samples=1500).arrays
    phi_deg = np.degrees(dense["phi_rad"])
    for name, stem, rel in [("rod_force_N", "rod_force", 1e-8), ("main_bearing_load_N", "main_bearing_load", 1e-8),
                            ("crank_torque_Nm", "crank_torque", 1e-8), ("belt_torque_Nm", "belt_torque", 1e-4),
                            ("motor_torque_Nm", "motor_torque_at_crank", 1e-4)]:
        i = int(np.argmax(np.abs(dense[name])))
        unit = name.rsplit("_", 1)[1]
        assert coarse.values[f"peak_{stem}_{unit}"] == pytest.approx(abs(dense[name][i]), rel=rel), name
        assert coarse.values[f"peak_{stem}_at_deg"] == pytest.approx(phi_deg[i], abs=3.0), name
        assert coarse.values[f"peak_{stem}_at_mm"] == pytest.approx(dense["travel_mm"][i], abs=1.0), name
    assert coarse.values["peak_motor_torque_Nm"] == pytest.approx(
        coarse.values["peak_motor_torque_at_crank_Nm"] / paper_task.gear_ratio, rel=1e-12)


def test_q_readings_spread_between_the_force_alone_and_the_tools_equation(paper_task):
    """Q = F + m_tool (X'' - g) at the end of the cut, by hand; F alone is the largest reading."""
    v = loads(paper_task).values
    a = loads(paper_task).arrays
    end = np.argmax(a["force_N"])
    _, a_tool, _, _ = rates(paper_task, {k: a[k][end:end + 1] for k in a})
    q_end = 6823.17 + paper_task.tool_mass_kg * (a_tool[0] - paper_task.gravity_m_s2)   # F(Z), eq. (1)
    assert v["peak_Q_cut_N"] == pytest.approx(q_end, rel=1e-9)
    assert v["Q_reading_spread"] == pytest.approx((6823.17 - min(q_end, v["peak_rod_force_N"])) / q_end, rel=1e-9)


def test_a_failed_steady_state_comes_back_without_peaks(paper_task):
    weak = dataclasses.replace(paper_task, motor_breakdown_torque_Nm=0.1)
    result = loads(weak)
    assert result.status.value == "INFEASIBLE"
    assert not any(k.startswith("peak_rod") for k in result.values)


def test_the_loads_scene_draws_loads_against_crank_angle_and_tool_travel_with_units(tmp_path):
    from mechopt import registry
    from mechopt.figures import plot_run
    from mechopt.registry import Run
    scene = dataclasses.replace(registry.find("press/kd2322"), solver=loads)     # figures follow the solver
    task = scene.build()[0]
    run = Run(scene, loads(task), [], task=task)
    figures = run.figures()
    assert set(figures) == {"cycle", "loads"}
    axes = figures["loads"].axes
    labels = {ax.get_xlabel() for ax in axes}
    assert labels == {"crank angle from top dead centre [deg]", "tool travel X [mm]"}
    assert all(ax.get_ylabel() in ("force [N]", "torque [N m]") and ax.get_legend() is not None for ax in axes)
    rod = next(line for line in axes[0].lines if line.get_label() == "rod force, tool end")
    assert max(rod.get_ydata()) == pytest.approx(run.values["peak_rod_force_N"], rel=1e-12)
    assert [p.name for p in plot_run(run, tmp_path)] == ["press_kd2322_cycle.png", "press_kd2322_loads.png"]
    kd = registry.run(registry.find("press/kd2322"))      # a plain steady state keeps its one figure
    assert set(kd.figures()) == {"cycle"}
