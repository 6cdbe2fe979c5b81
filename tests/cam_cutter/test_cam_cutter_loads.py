"""Kinetostatics of the torch-guiding linkage (paper 000, Sec. V re-derived)."""
import dataclasses

import numpy as np
import pytest

from mechopt.kit.errors import ModelError, SettingError
from mechopt.kit.result import Status
from mechopt.models.cam_cutter import LinkageLoads, linkage_energy, linkage_positions, real_point, real_velocity
from mechopt.solvers.cam_cutter.kinetostatics import joint_loads, load_system

H, L = 59.45, 47.52


def loads(**changes):
    base = LinkageLoads(H_mm=H, L_mm=L, force_N=100.0, crank_speed_rad_s=1.01, crank_mass_kg=0.078,
                        crank_centre_mm=14.86, crank_inertia_kgm2=1.87e-5, link_mass_kg=0.159,
                        link_centre_mm=-5.97, link_inertia_kgm2=2.18e-4, block_mass_kg=0.047,
                        block_inertia_kgm2=5.1e-6)
    return dataclasses.replace(base, **changes)


def test_positions_run_the_limacon_and_the_link_passes_through_the_block():
    phi = np.linspace(0, 4 * np.pi, 97)
    pos = linkage_positions(phi, H, L, 10.0, -5.0)
    # eq. (10) is eq. (7) shifted by L + H: the torch runs on the package's real path
    x, y = real_point(phi / 2, H, L)
    assert np.allclose(pos["T"][0] - (H + L), x, atol=1e-12) and np.allclose(pos["T"][1], y, atol=1e-12)
    # loop closure: O, P and the link's axis are collinear (P x u = 0), and |TP| = L
    theta = pos["theta"]
    assert np.allclose(pos["P"][0] * np.sin(theta) - pos["P"][1] * np.cos(theta), 0, atol=1e-12)
    assert np.allclose(np.hypot(pos["T"][0] - pos["P"][0], pos["T"][1] - pos["P"][1]), L)


def test_torque_without_inertia_is_force_times_torch_lever():
    # massless links: virtual work gives M = F |dT/dphi| = F |dT/dt| / 2 against the torch's velocity
    task = loads(crank_mass_kg=0.0, crank_inertia_kgm2=0.0, link_mass_kg=0.0, link_inertia_kgm2=0.0,
                 block_mass_kg=0.0, block_inertia_kgm2=0.0)
    r = joint_loads(task, count=101)
    t = r.arrays["phi_rad"] / 2
    lever_m = np.hypot(*real_velocity(t, H, L)) / 2 / 1000
    assert r.status is Status.SOLVED
    assert np.allclose(r.arrays["M_N_m"], 100.0 * lever_m, rtol=1e-12)
    assert r.values["max_driving_torque_N_m"] == pytest.approx(100.0 * (H + L) / 2 / 1000, rel=1e-12)
    # and the force normal to the link pulls at the lever L about P, that is (L + H cos t) about O
    r = joint_loads(dataclasses.replace(task, force_direction="normal_to_link"), count=101)
    assert np.allclose(r.arrays["M_N_m"], 100.0 * (L + H * np.cos(t)) / 2 / 1000, rtol=1e-12)


def test_power_balance_and_global_equilibrium_of_a_fast_heavy_linkage():
    task = loads(crank_speed_rad_s=80.0, gravity_m_s2=9.81, link_mass_kg=1.5, link_centre_mm=40.0, crank_mass_kg=0.6)
    r = joint_loads(task, count=203)
    assert r.status is Status.SOLVED and r.values["power_balance_residual"] <= 1e-9
    # inertia matters here: the torque is far from the massless one
    assert r.values["max_driving_torque_N_m"] > 1.2 * 100.0 * (H + L) / 2 / 1000
    # the frame's reactions balance the torch force, the weights and the inertia forces (a sum the
    # solve never forms): R01 + R03 + F + sum m (g - a) = 0
    phi = r.arrays["phi_rad"]
    _, _, force, _, _, _ = load_system(task, phi)
    h = 1e-5
    acc = {}
    for name, centre_mm in (("C1", task.crank_centre_mm), ("C2", task.link_centre_mm)):
        def x(p, name=name):
            pos = linkage_positions(p, H / 1000, L / 1000, task.crank_centre_mm / 1000, task.link_centre_mm / 1000)
            return np.array(pos[name])
        acc[name] = (x(phi + h) - 2 * x(phi) + x(phi - h)).T / h**2 * task.crank_speed_rad_s**2
    g = np.array([0.0, -9.81])
    total = (np.stack([r.arrays["R01x_N"] + r.arrays["R03x_N"], r.arrays["R01y_N"] + r.arrays["R03y_N"]], axis=1)
             + force + (task.crank_mass_kg + task.link_mass_kg + task.block_mass_kg) * g
             - task.crank_mass_kg * acc["C1"] - task.link_mass_kg * acc["C2"])
    assert np.max(np.abs(total)) < 1e-4 * np.max(np.abs(force))


def test_driving_power_is_the_energy_rate_by_numpy_differences():
    # the same balance as power_balance_residual, with dE/dt by central differences of the energy
    # in numpy instead of CasADi: M w = dE/dt - F . v_torch
    task = loads(crank_speed_rad_s=80.0, gravity_m_s2=9.81)
    w, k = task.crank_speed_rad_s, 1e-4
    r = joint_loads(task, count=101)
    phi = r.arrays["phi_rad"]

    def energy(p):
        geometry = (H / 1000, L / 1000, task.crank_centre_mm / 1000, task.link_centre_mm / 1000)
        pos, ahead, behind = (linkage_positions(q, *geometry) for q in (p, p + k, p - k))
        vel = {n: tuple((a - b) / (2 * k) * w for a, b in zip(ahead[n], behind[n])) for n in ("C1", "C2")}
        return linkage_energy(pos, {**vel, "phi": w, "theta": w / 2}, task)
    energy_rate = (energy(phi + k) - energy(phi - k)) / (2 * k) * w
    _, _, force, v_torch, _, _ = load_system(task, phi)
    expected = energy_rate - np.einsum("ni,ni->n", force, v_torch)
    assert np.allclose(r.arrays["M_N_m"] * w, expected, atol=1e-6 * np.max(np.abs(expected)))


def test_singular_position_gives_a_status_and_finite_numbers():
    r = joint_loads(loads(), count=720)          # phi = pi and 3 pi on the grid
    assert r.status is Status.UNBOUNDED
    assert np.allclose(r.diagnostics["singular_phi_rad"], [np.pi, 3 * np.pi])
    assert all(np.isfinite(v) for v in r.values.values())
    assert all(np.all(np.isfinite(a)) for a in r.arrays.values()) and r.arrays["phi_rad"].size == 718
    assert "crank pin P passes through the swivel block's pivot O" in r.message
    A, *_ = load_system(loads(), [np.pi, 0.3])
    assert [np.linalg.matrix_rank(a) for a in A] == [8, 9]


def test_condition_number_grows_as_the_pin_nears_the_block_pivot():
    eps = np.array([1e-2, 1e-3, 1e-4])
    A, *_ = load_system(loads(), np.pi - eps)
    cond = np.linalg.cond(A)
    # arm |OP| = H |cos(phi/2)| ~ H eps / 2: the condition number grows as 1 / eps
    assert np.allclose(cond * eps, cond[-1] * eps[-1], rtol=0.02)
    r = joint_loads(loads(), count=721)
    assert abs(np.cos(r.diagnostics["max_condition_at_phi_rad"] / 2)) < 0.01


def papers_A(phi, H):
    """Sec. V's A(phi) as printed; h1 = H cos(phi), h2 = H sin(phi)."""
    s, c, h1, h2 = np.sin(phi), np.cos(phi), H * np.cos(phi), H * np.sin(phi)
    return np.array([
        [-1, 0, -s, 0, 0, 0, 0, 0, 0],
        [0, -1, c, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 1, 0, 0, 0, 0, -1],
        [0, 0, 0, 0, c, 0, 1, 0, 0],
        [0, 0, 0, 0, s, 0, 0, 1, 0],
        [0, 0, 0, 0, 0, 0, 1, 0, 0],
        [0, 0, s, 0, -c, 0, 0, 0, 0],
        [0, 0, -c, 0, -s, 0, 0, 0, 0],
        [0, 0, h1, -1, -h2, 1, 0, 0, 0]], dtype=float)


@pytest.mark.parametrize("phi", [0.0, 0.4, 1.3, np.pi / 2, 2.9, 4.4])
def test_papers_9x9_has_rank_8(phi):
    A = papers_A(phi, H)
    assert np.linalg.matrix_rank(A) == 8
    # row 6 (x7 = 0) repeats row 4 given rows 7-8: row6 = row4 + cos(phi) (cos(phi) row7 + sin(phi) row8)
    c, s = np.cos(phi), np.sin(phi)
    assert np.allclose(A[5], A[3] + c * (c * A[6] + s * A[7]))
    assert np.linalg.matrix_rank(np.delete(A, 5, axis=0)) == 8
    # so x4, x6, x9 (two couples and the torque) meet only rows 3 and 9: one of them is left free
    assert np.allclose(A @ np.array([0, 0, 0, 1, 0, 1, 0, 0, 1.0]), 0)


def test_bad_input_is_refused_by_name():
    with pytest.raises(ModelError, match=r"H_mm=-1\.0: allowed > 0 \.\.\. 1e\+06"):
        loads(H_mm=-1.0)
    with pytest.raises(ModelError, match=r"link_mass_kg=nan: expected a finite number"):
        loads(link_mass_kg=float("nan"))
    with pytest.raises(ModelError, match=r"force_direction='up': allowed against_velocity, normal_to_link"):
        loads(force_direction="up")
    with pytest.raises(SettingError, match=r"count=4: allowed"):
        joint_loads(loads(), count=4)


def test_scene_speed_is_the_papers_cutting_speed_and_its_figure_draws(tmp_path):
    from mechopt import registry
    from mechopt.figures import plot_run
    run = registry.run(registry.find("cam-cutter/joint-reactions"))
    # the crank speed was chosen (assumed) so that the torch averages 2.1 m/min (Sec. II); the mean of
    # |dT/dt| = sqrt(H^2 + L^2 + 2 H L cos t) over a cycle, by quadrature apart from the solver
    t = np.linspace(0, 2 * np.pi, 200_001)
    speed_mm_rad = np.hypot(*real_velocity(t, H, L))
    mean_m_min = np.trapezoid(speed_mm_rad, t) / (2 * np.pi) * run.task.crank_speed_rad_s / 2 / 1000 * 60
    assert mean_m_min == pytest.approx(2.1, abs=0.01)
    assert run.result.diagnostics["mean_torch_speed_m_min"] == pytest.approx(mean_m_min, rel=1e-3)
    paths = plot_run(run, tmp_path)
    assert [p.name for p in paths] == ["cam-cutter_joint-reactions_loads.png"] and paths[0].stat().st_size > 10_000
