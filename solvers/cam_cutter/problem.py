"""The minimax problem every linkage fit shares (one cam in `fit`, a family in `family`): the
constraints of a node against its limaçon, the NLP back ends' options, one exchange round's
solve and the node working set. Public, so that no solver module reaches into another's privates.
"""
import casadi as ca
import numpy as np

from mechopt.kit.result import Status, from_ipopt, from_sqpmethod
from mechopt.models.cam_cutter import real_point, real_velocity

__all__ = ["NLP_OPTIONS", "ROUND_VERTICES", "foot_and_band", "solve_round", "pad_nodes"]

# polyline vertices seeding Newton's foot points inside the exchange rounds: 4096 match 2^16 to
# 1e-13 mm on the paper's and other cardioids (2048 can seed the wrong branch); the reported
# max_deviation_mm keeps the finer default of `path_distance`
ROUND_VERTICES = 2**12

NLP_OPTIONS = {
    "ipopt": {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-10,
              "ipopt.max_iter": 300},
    # exact-Hessian SQP with CasADi's own active-set QP: ~4 iterations, no interior-point start-up.
    # At a minimax optimum more constraints are active than there are unknowns, and the gradient
    # of the Lagrangian stalls near 1e-6 (against the objective's gradient of 1) while the steps
    # shrink quadratically to zero: the dual tolerance is 1e-5, reached when the last step is
    # ~1e-7 mm. A round that still does not converge (delta = 0 exactly, h = 0) goes to IPOPT
    "sqp": {"print_time": False, "print_header": False, "print_iteration": False, "print_status": False,
            "qpsol": "qrqp", "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False,
                                               "error_on_fail": False, "constr_viol_tol": 1e-12,
                                               "dual_inf_tol": 1e-12},
            "convexify_strategy": "regularize", "tol_pr": 1e-10, "tol_du": 1e-5, "max_iter": 50},
}


def foot_and_band(s, H, L, px, py, a, delta):
    """The minimax constraints for nodes (px, py) and limaçon points s (CasADi symbols): the foot
    condition (= 0), then delta + and - the signed distance (>= 0). L may differ per node."""
    rx, ry = real_point(s, H, L, m=ca)
    vx, vy = real_velocity(s, H, L, m=ca)
    ex, ey = rx - px, ry - py
    # |R'| vanishes only at the plain cardioid's cusp, where the cross product does too
    signed = (ex * vy - ey * vx) / ca.sqrt(vx * vx + vy * vy + (1e-9 * a) ** 2)
    return ca.vertcat(ex * vx + ey * vy, delta + signed, delta - signed)


def solve_round(k, method, bounds, *, solver_of, cold=False):
    """One exchange round's NLP: (solution, Status, the back end's word, the back end, build s).
    SQP first when asked (and not `cold`); a round it does not solve is solved again by IPOPT from
    the same start. `solver_of(k, name)` gives the built NLP and the seconds its build took."""
    build_s = 0.0
    for name in (("sqp", "ipopt") if method == "sqp" and not cold else ("ipopt",)):
        solver, built_s = solver_of(k, name)
        build_s += built_s
        sol = solver(**bounds)
        stats = solver.stats()
        status = (from_sqpmethod(stats["return_status"], stats["success"]) if name == "sqp"
                  else from_ipopt(stats["return_status"]))
        if status is Status.SOLVED or name == "ipopt":
            return sol, status, stats["return_status"], name, build_s


def pad_nodes(working, k, count):
    """The working nodes plus spread nodes not yet in it, k in all (never a duplicate)."""
    chosen = list(dict.fromkeys(working))
    for i in np.linspace(0, count - 1, k + len(chosen)).round().astype(int):
        if len(chosen) >= min(k, count):
            break
        if i not in chosen:
            chosen.append(int(i))
    return chosen
