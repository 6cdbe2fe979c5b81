"""The synthesised law on the lever's box (solvers/stop_impact/lever_box.py): the linear model's
and the chain's worst rebound over the box's grid, and beside the robust law the nominal law's and
the cycloid's worst on the same box."""
import dataclasses
import math

import numpy as np

from mechopt.kit.result import Status
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.lever_box import LeverBox
from mechopt.solvers.stop_impact.synthesis_search import dense_worst, least_phase
from mechopt.solvers.stop_impact.window_lp import band_speeds, linear_lever, predicted_rebounds_mm

__all__ = ["beside", "box_values", "box_worst_point"]


def box_worst_point(task, law, t_deg, band, box, step, lever):
    """(the linear model's largest rebound [mm], its point (frequency factor, zeta, rpm)) of `law`
    at `t_deg` over the box's grid of levers and its band (the margin added), every `step` rpm."""
    keys = box.grid_keys(task)
    levers = {key: LeverBox.lever(task, key) for key in keys}
    return dense_worst(levers, keys, law, t_deg, band_speeds(box.band(band), step), lever)


def box_values(task, law, t_deg, band, box, step, lever, values, suffix):
    """The chain's worst rebound of `law` at `t_deg` over the box: at every lever of its grid, the
    chain (CVODES rise, eq. (2)) at the speed where the linear model's rebound is largest (the two
    agree within the synthesis' agreement_rel: the status criterion). Sets
    `rebound_worst_box<suffix>_mm` and `box_roller_left<suffix>` (levers of the grid on which the
    roller leaves its cam there: no rebound, a failure of its own, counted, not in the worst);
    returns the diagnostics naming where they are."""
    dense = band_speeds(box.band(band), step)
    worst, where, left = -math.inf, None, []
    for key in box.grid_keys(task):
        each = LeverBox.lever(task, key)
        pred = [p[0] for p in predicted_rebounds_mm(each, law, t_deg, dense, lever=lever)]
        n = float(dense[int(np.argmax(pred))])
        chain = float(rebound_amplitude_mm(dataclasses.replace(each, law=law), n, t_deg, lost=math.nan))
        if math.isnan(chain):
            left.append(list(key) + [n])
        elif chain > worst:
            worst, where = chain, key + (n,)
    values |= {f"rebound_worst_box{suffix}_mm": worst, f"box_roller_left{suffix}": float(len(left))}
    return {f"rebound_worst_box{suffix}_at": where and {"frequency_factor": where[0], "zeta": where[1],
                                                        "speed_rpm": where[2]},
            f"box_roller_left{suffix}_at": left,
            "box": {"frequency_factor": list(box.frequency), "zeta": list(box.zeta or box._zetas(task)),
                    "band_rpm": list(box.band(band)), "grid": box.grid}}


def beside(task, band, lo, hi, tol, common, box, values, diagnostics):
    """The nominal law (synthesised without the box) and the cycloid at its least angle, each with
    its worst rebound over the same box (`rebound_worst_box_nominal_mm`, `..._cycloidal_mm`)."""
    lever = linear_lever(common["coefficients"], common["continuity"])
    nominal = {k: v for k, v in common.items() if k not in ("box", "rounds")}
    design, t_nom, _ = least_phase(task, band, lo, hi, tol, nominal)
    if design.status is Status.SOLVED:
        values["t_min_nominal_deg"] = t_nom
        diagnostics |= box_values(task, design.law, t_nom, band, box, common["dense_step_rpm"], lever, values,
                                   "_nominal")
    if "t_min_cycloidal_deg" in values:
        diagnostics |= box_values(task, "cycloidal", values["t_min_cycloidal_deg"], band, box,
                                   common["dense_step_rpm"], lever, values, "_cycloidal")
