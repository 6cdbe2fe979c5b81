"""Event times of a network cyclogram (paper 004, problem (1)): on the graph (the LP's dual, longest
paths; the default) or as a linear program in cvxpy (method "lp").

    minimise p(N) - p(1)   subject to   p(y) - p(x) >= [phi(x, y)]                 every operation
                                        p(y) - p(x) >= sigma-bound(x, y; [sigma_H])  cam pairs
                                        slope (p(7) - p(3)) + intercept <= a_lim    amplitude law
                                        p(y) - p(x) <= w,  p(a) = p(b)             windows, syncs
                                        p(1) = 0                                     anchor

or, for a machine with a limiting operation (x*, y*), maximise p(y*) - p(x*) with p(N) - p(1) <=
cycle. Constraints are built from the incidence matrix (one vectorised row block per kind); every
limit is a cvxpy Parameter, so a what-if re-solve reuses the compiled problem (DPP). The anchor
p(1) = 0 removes the shift invariance that otherwise slows HiGHS a hundredfold.

Sensitivities are reported in user terms with one sign convention: d(objective)/d(limit), the
change of the objective (span_deg, or limiting_op_deg on a machine) per unit *increase* of the
limit. Raising [sigma_H] or the amplitude limit loosens a bound: the span falls (<= 0); raising a
critical [phi] lengthens it (+1 deg/deg).
"""
import functools
from typing import Literal

from mechopt.kit.result import Result
from mechopt.kit.settings import Tolerance, check_settings
from mechopt.models.cyclogram import Cyclogram
from mechopt.solvers.cyclogram.certify import certify, one_sided_sensitivity
from mechopt.solvers.cyclogram.graph_method import plan_graph
from mechopt.solvers.cyclogram.lp_method import plan_lp


def plan_cyclogram(task: Cyclogram, *, method: Literal["graph", "lp"] = "graph",
                   backend: Literal["HIGHS", "CLARABEL"] = "HIGHS",
                   stress_form: Literal["exact", "linear"] = "exact", warm_start: bool = False,
                   tol_deg: Tolerance = 1e-6, check: bool = False) -> Result:
    """Event times minimising the span p(N) - p(1) of a cyclogram (paper 004, problem (1)), or
    maximising the machine's limiting operation inside its cycle.

    Parameters
    ----------
    task : the network and its limits (models/cyclogram.py).
    method : "graph" (longest paths on the difference constraints, solvers/cyclogram/graph.py: the
        LP's dual solved exactly) or "lp" (the cvxpy model of the design card).
    backend : LP solver behind cvxpy (method "lp", and the check).
    stress_form : "exact" sigma_max(t) <= [sigma_H] as t >= K/[sigma_H]; "linear" its tangent at t_ref.
    warm_start : pass cvxpy's warm start to the back end (with HiGHS it can slow re-solves).
    tol_deg : tolerance [deg] for float = 0 (critical), binding constraints and the cross-check.
    check : also solve by the other method and compare: status, span (or limiting_op_deg) to
        tol_deg and, where the critical chain is unique, every sens_*; a mismatch makes the result
        INACCURATE. The value check_rel is the objectives' difference per degree above 1 (the
        cyclogram scenes expect it below 1e-9: the LP as certificate in `mechopt validate`).

    Returns
    -------
    Result with values span_deg, longest_path_deg (the longest path first -> last on the graph),
    p_<event>_deg, t_<x>_<y>_deg, amplitude_<x>_<y>_mm, sigma_<x>_<y>_MPa, span_<group>_deg,
    limiting_op_deg (machines) and sens_* sensitivities (see SENSITIVITY_CONVENTION);
    diagnostics: float_deg, critical_ops, critical_chain, binding (with duals), sens_min_deg.
    An infeasible problem names its conflicting chain (a positive cycle of the difference
    constraints) in `message` and `violated`, its events and excess [deg] in `diagnostics`.

    Method "graph" also gives ranging_deg: per operation [how far its bound may fall, rise]
    [deg] before its dual changes (None: without end).

    The back end's answer is checked against the exact certificate, whatever it says: a positive
    cycle (above 1e-12 of the largest angle: round-off) makes the result INFEASIBLE, an optimum
    differing from the longest path by more than tol_deg * max(1, |longest path|) INACCURATE.

    Examples
    --------
    >>> from mechopt import registry
    >>> r = plan_cyclogram(registry.find("loom/group1").build()[0])
    >>> r.status.value, r.diagnostics["critical_chain"][:3]                             # doctest: +SKIP
    ('SOLVED', ['1', '3', '7'])
    """
    check_settings(plan_cyclogram, method=method, backend=backend, stress_form=stress_form)
    solve = plan_graph if method == "graph" else functools.partial(plan_lp, backend=backend, warm_start=warm_start)
    result = solve(task, stress_form=stress_form, tol_deg=tol_deg)
    if not check:
        return result
    other = (plan_lp(task, stress_form=stress_form, tol_deg=tol_deg, backend=backend, warm_start=warm_start)
             if method == "graph" else plan_graph(task, stress_form=stress_form, tol_deg=tol_deg))
    graph = functools.partial(plan_graph, stress_form=stress_form, tol_deg=tol_deg)
    return certify(result, other, tol_deg, one_sided=lambda key: one_sided_sensitivity(task, key, graph, result))
