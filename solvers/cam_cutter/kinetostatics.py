"""Joint reactions and driving torque of the torch-guiding linkage over a cycle (paper 000, Sec. V,
re-derived: the printed 9x9 has rank 8, see tests/cam_cutter/test_cam_cutter_loads.py).

At each crank angle the nine d'Alembert equations of crank, wing link and swivel block are one
linear system A(phi) x = b(phi) in the nine unknowns `LOAD_UNKNOWNS`; velocities and
accelerations are CasADi derivatives of the position equations (5)-(7). The check is separate:
by virtual work the driving power M omega equals dE/dt minus the torch force's power, with E the
energy (`linkage_energy`) differentiated by CasADi along the cycle, never from the reactions.
"""

import casadi as ca
import numpy as np

from mechopt.kit.cache import BuildCache
from mechopt.kit.result import Clock, Result, Status
from mechopt.kit.settings import Annotated, Interval, check_settings
from mechopt.models.cam_cutter import LOAD_UNKNOWNS, LinkageLoads, linkage_energy, linkage_positions

__all__ = ["joint_loads", "load_system"]

Angles = Annotated[int, Interval(ge=8, le=200_000)]      # A alone is 648 bytes an angle
ConditionLimit = Annotated[float, Interval(ge=1e3, le=1e15)]

_POINTS = ("P", "C1", "C2", "T")
_KINEMATICS = BuildCache("cam_cutter.kinetostatics", maxsize=64)


def _build(task: LinkageLoads):
    """CasADi function phi -> positions, their first and second phi-derivatives (AD), energy
    and its time derivative at the task's constant crank speed."""
    phi = ca.SX.sym("phi")
    pos = linkage_positions(phi, task.H_mm / 1000, task.L_mm / 1000, task.crank_centre_mm / 1000,
                            task.link_centre_mm / 1000, m=ca)
    q = ca.vertcat(*[c for name in _POINTS for c in pos[name]], pos["theta"])
    dq = ca.jacobian(q, phi)
    ddq = ca.jacobian(dq, phi)
    w = task.crank_speed_rad_s

    def unpack(v):
        return {**{name: (v[2 * k], v[2 * k + 1]) for k, name in enumerate(_POINTS)}, "theta": v[8]}
    velocities = {**unpack(dq * w), "phi": w}
    energy = linkage_energy(unpack(q), velocities, task)
    energy_rate = ca.jacobian(energy, phi) * w        # dE/dt at constant crank speed
    return ca.Function("linkage_kinematics", [phi], [q, dq, ddq, energy, energy_rate])


def _kinematics(task, phi):
    """Positions q, dq/dphi, d2q/dphi2 (each n x 9: P, C1, C2, T as x, y, then theta), E, dE/dt."""
    f, build_s = _KINEMATICS.get(task, lambda: _build(task))
    out = f.map(phi.size)(phi.reshape(1, -1))
    return [np.asarray(o).T for o in out[:3]] + [np.asarray(o).ravel() for o in out[3:]] + [build_s]


def _cross(r, f):
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def load_system(task: LinkageLoads, phi):
    """A (n x 9 x 9), b (n x 9) of the kinetostatics at crank angles phi, with the torch force
    (n x 2) [N], the torch velocity (n x 2) [m/s] and dE/dt (n) [W]. Rows: crank x, y, moment
    about O1; link x, y, moment about P; block x, y, moment about O; moment rows and couple
    unknowns divided by H (dimensionless A)."""
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    q, dq, ddq, _, energy_rate, build_s = _kinematics(task, phi)
    w, H, n = task.crank_speed_rad_s, task.H_mm / 1000, phi.size
    pt = {name: q[:, 2 * k:2 * k + 2] for k, name in enumerate(_POINTS)}
    acc = {name: ddq[:, 2 * k:2 * k + 2] * w**2 for k, name in enumerate(_POINTS)}     # constant crank speed
    theta_acc = ddq[:, 8] * w**2
    v_torch = dq[:, 6:8] * w
    g = np.array([0.0, -task.gravity_m_s2])
    speed = np.hypot(*v_torch.T)
    moving = speed > 1e-12 * w * (task.H_mm + task.L_mm) / 1000        # none only at a cardioid's cusp
    if task.force_direction == "against_velocity":
        force = -task.force_N * np.divide(v_torch, speed[:, None], out=np.zeros_like(v_torch), where=moving[:, None])
    else:       # normal to the link: -F n, Sec. V's F (sin, -cos) of the link angle
        theta = q[:, 8]
        force = task.force_N * np.stack([np.sin(theta), -np.cos(theta)], axis=1)
    normal = np.stack([-np.sin(q[:, 8]), np.cos(q[:, 8])], axis=1)
    O1 = np.array([H / 2, 0.0])
    r_p = pt["P"] - O1                     # crank pin from O1
    r_c1 = pt["C1"] - O1
    r_op = -pt["P"]                        # block centre O from P
    r_tp, r_c2p = pt["T"] - pt["P"], pt["C2"] - pt["P"]
    m1, m2, m3 = task.crank_mass_kg, task.link_mass_kg, task.block_mass_kg
    A, b = np.zeros((n, 9, 9)), np.zeros((n, 9))
    # crank: frame at O1 (x0, x1), link at P (-x2, -x3), driving torque x8 * H
    A[:, 0, 0] = A[:, 1, 1] = 1.0
    A[:, 0, 2] = A[:, 1, 3] = -1.0
    b[:, 0:2] = m1 * (acc["C1"] - g)
    A[:, 2, 2], A[:, 2, 3], A[:, 2, 8] = r_p[:, 1] / H, -r_p[:, 0] / H, 1.0
    b[:, 2] = (-_cross(r_c1, m1 * (g - acc["C1"]))) / H            # the crank turns uniformly: no J1 term
    # link: crank at P (x2, x3), block's normal force x4 at O, couple x5 * H, torch force, weight, inertia
    A[:, 3, 2] = A[:, 4, 3] = 1.0
    A[:, 3, 4], A[:, 4, 4] = normal[:, 0], normal[:, 1]
    b[:, 3:5] = m2 * (acc["C2"] - g) - force
    A[:, 5, 4], A[:, 5, 5] = _cross(r_op, normal) / H, 1.0
    b[:, 5] = (task.link_inertia_kgm2 * theta_acc - _cross(r_tp, force) - _cross(r_c2p, m2 * (g - acc["C2"]))) / H
    # block at O: frame (x6, x7), the link's -x4 n and -x5 * H; its centre O stays put
    A[:, 6, 6] = A[:, 7, 7] = 1.0
    A[:, 6, 4], A[:, 7, 4] = -normal[:, 0], -normal[:, 1]
    b[:, 6:8] = -m3 * g
    A[:, 8, 5] = -1.0
    b[:, 8] = task.block_inertia_kgm2 * theta_acc / H
    return A, b, force, v_torch, energy_rate, build_s


def joint_loads(task: LinkageLoads, *, count: Angles = 721, max_condition: ConditionLimit = 1e8) -> Result:
    """Reactions in every pair and the driving torque at `count` crank angles over a full cycle
    (two crank turns: the link turns once), each by a direct solve of the 9x9 system.

    Values: `max_driving_torque_N_m`, `max_joint_reaction_N` (largest force in any pair),
    `max_condition_number` of the regular angles, `power_balance_residual` (driving power against
    virtual work, relative to the largest power in the balance). An angle whose system is rank
    deficient or has condition number above `max_condition` is singular: it is left out of the
    arrays and values, listed in diagnostics, and the status is UNBOUNDED (the reactions grow
    without bound there). Otherwise SOLVED.
    """
    check_settings(joint_loads, count=count, max_condition=max_condition)
    clock = Clock()
    phi_all = np.linspace(0.0, 4 * np.pi, count, endpoint=False)
    A, b, force, v_torch, energy_rate, clock.build_s = load_system(task, phi_all)
    direct = Clock()            # the 9x9 solves alone (diagnostics)
    sv = np.linalg.svd(A, compute_uv=False)
    rank = np.count_nonzero(sv > sv[:, :1] * 9 * np.finfo(float).eps, axis=1)
    with np.errstate(divide="ignore"):
        cond = sv[:, 0] / sv[:, -1]
    regular = (rank == 9) & (cond <= max_condition)
    phi = phi_all[regular]
    x = np.linalg.solve(A[regular], b[regular][..., None])[..., 0]
    H, w = task.H_mm / 1000, task.crank_speed_rad_s
    x[:, 5] *= H
    x[:, 8] *= H
    solve_residual = float(np.max(np.abs(np.einsum("nij,nj->ni", A[regular], _scaled(x, H)) - b[regular]), initial=0.0))

    # virtual work, independent of the reactions: M w = dE/dt - F . v_torch
    drive_power = x[:, 8] * w
    force_power = np.einsum("ni,ni->n", force[regular], v_torch[regular])
    balance = drive_power - (energy_rate[regular] - force_power)
    scale = max(np.max(np.abs(energy_rate[regular]) + np.abs(force_power), initial=0.0), np.finfo(float).tiny)
    power_residual = float(np.max(np.abs(balance), initial=0.0) / scale)

    reactions = {"O1": np.hypot(x[:, 0], x[:, 1]), "P": np.hypot(x[:, 2], x[:, 3]),
                 "O_slide": np.abs(x[:, 4]), "O": np.hypot(x[:, 6], x[:, 7])}
    solve_s = direct.elapsed()
    singular = phi_all[~regular]
    worst = {}
    values = {}
    if phi.size:
        every = np.max(np.stack(list(reactions.values())), axis=0)
        k_r, k_m, k_c = int(np.argmax(every)), int(np.argmax(np.abs(x[:, 8]))), int(np.argmax(cond[regular]))
        values = {"max_driving_torque_N_m": float(abs(x[k_m, 8])), "max_joint_reaction_N": float(every[k_r]),
                  "max_condition_number": float(cond[regular][k_c]), "power_balance_residual": power_residual}
        worst = {"max_driving_torque_at_phi_rad": float(phi[k_m]), "max_joint_reaction_at_phi_rad": float(phi[k_r]),
                 "max_joint_reaction_pair": max(reactions, key=lambda j: reactions[j][k_r]),
                 "max_condition_at_phi_rad": float(phi[k_c]),
                 "max_reaction_by_pair_N": {j: float(np.max(r)) for j, r in reactions.items()},
                 # grid-independent: the reactions' 1 / |cos(phi/2)| growth times the vanishing arm
                 "max_reaction_times_cos_half_phi_N": float(np.max(every * np.abs(np.cos(phi / 2))))}
    # why the system degrades: the link's moment about P is held only by the block's normal force,
    # whose arm |OP| = H |cos(phi/2)| vanishes where the crank pin passes the block's pivot
    gap = float(np.min(np.abs(np.cos(phi / 2)), initial=1.0))
    message = (f"{phi.size} of {count} angles regular; condition number {np.min(cond[regular], initial=np.inf):.3g} .. "
               f"{np.max(cond[regular], initial=0.0):.3g}, worst near phi = pi, 3 pi (t = pi/2, 3 pi/2), where the "
               f"crank pin P passes through the swivel block's pivot O: the link's moment about P is held only by the "
               f"block's force, whose arm |OP| = H |cos(phi/2)| vanishes (here down to {gap:.3g} H), so the reactions "
               f"there grow as 1 / |cos(phi/2)| and their maximum depends on how close the grid comes "
               f"(reaction x |cos(phi/2)| stays below {worst.get('max_reaction_times_cos_half_phi_N', 0.0):.4g} N)")
    status = Status.SOLVED
    if singular.size:
        status = Status.UNBOUNDED
        message = (f"singular at phi = {', '.join(f'{p:.6g}' for p in singular[:6])} rad (rank 8 or condition number "
                   f"> max_condition={max_condition:g}): the reactions there are unbounded and left out; " + message)
    if not phi.size:
        status = Status.FAILED
    arrays = {"phi_rad": phi, "t_rad": phi / 2, "condition_number": cond[regular],
              **{name: x[:, k] for k, name in enumerate(LOAD_UNKNOWNS)},
              **{f"R_{j}_N": r for j, r in reactions.items()},
              "power_balance_W": balance}
    torch_speed = np.hypot(*v_torch.T)
    return clock.result(status, values, message=message,
                        diagnostics={**worst, "angles": count, "singular_phi_rad": [float(p) for p in singular],
                                     "solve_residual": solve_residual, "solve_s": solve_s,
                                     "mean_torch_speed_m_min": float(np.mean(torch_speed) * 60)},
                        arrays=arrays)


def _scaled(x, H):
    """The solution in the system's own units (couples / H), for its residual."""
    y = x.copy()
    y[:, 5] /= H
    y[:, 8] /= H
    return y
