"""The loads a designer sizes the press's parts with, over one revolution of the periodic steady
motion (paper 001, Figs. 9-10): connecting-rod force, crank torque, main-bearing load, belt and motor
torque, each with its peak and where it occurs (crank angle, tool travel).

The loads themselves are outputs of the model (`models.press_laws.linkage_forces`, evaluated along the
orbit by `Dynamics.outputs`); this module only finds their peaks.

The "resulting force" Q of Figs. 9-10: the paper plots "the loading Q (N) against the tool travel and
the crank angle during the cut" and calls it the resulting cutting force, without an equation. We
read it as the force the rod exerts on the tool along the stroke, Q = F + m_tool (X'' - g) (the
tool's equation of motion). The other readings are the technological force F alone (Fig. 8) and the
force along the rod (Q / cos beta, with the rod's own mass); `Q_reading_spread` is the spread of
their peaks during the cut relative to ours.
"""
from dataclasses import replace

import numpy as np

from mechopt.kit.result import Result
from mechopt.kit.settings import Annotated, Interval, Tolerance
from mechopt.models.press import PressDrive
from mechopt.solvers.press.periodic import steady_state
from mechopt.solvers.press.problem import Samples

# array name -> value stem; peaks are of the magnitude (a rod in tension or a torque braking counts too)
LOADS = {"rod_force_N": "rod_force_N", "rod_force_pin_N": "rod_force_pin_N", "crank_torque_Nm": "crank_torque_Nm",
         "main_bearing_load_N": "main_bearing_load_N", "belt_torque_Nm": "belt_torque_Nm",
         "motor_shaft_torque_Nm": "motor_torque_Nm", "motor_torque_Nm": "motor_torque_at_crank_Nm",
         "guide_force_N": "guide_force_N"}


def loads(task: PressDrive, *, tol: Tolerance = 1e-10, samples: Samples = 60,
          max_iter: Annotated[int, Interval(ge=1, le=100)] = 30) -> Result:
    """The periodic steady motion (`steady_state`, same settings) with the peak of each load:
    `peak_<load>` [its unit], `peak_<load>_at_deg` (crank angle from top dead centre) and
    `peak_<load>_at_mm` (tool travel X). The motor torque is at the motor shaft
    (`peak_motor_torque_Nm`, to compare with its breakdown torque) and reduced to the crank
    (`peak_motor_torque_at_crank_Nm`). A result that is not SOLVED or INACCURATE is returned as it is."""
    result = steady_state(task, tol=tol, samples=samples, max_iter=max_iter)
    a = result.arrays
    if not len(a.get("t_s", ())):
        return result
    arrays = dict(a)
    arrays["motor_shaft_torque_Nm"] = a["motor_torque_Nm"] / task.gear_ratio
    values = dict(result.values)
    for name, stem in LOADS.items():
        if name.startswith("motor") and not task.motor:
            continue
        peak, at = _peak(a["phi_rad"], arrays[name], a["cutting"])
        base = stem.rsplit("_", 1)[0]            # peak_rod_force_N, peak_rod_force_at_deg, ..._at_mm
        values[f"peak_{stem}"] = peak
        values[f"peak_{base}_at_deg"] = float(np.degrees(at))
        values[f"peak_{base}_at_mm"] = float(task.travel(at) * 1000)
    values["peak_belt_torque_Nm"] = result.values["peak_belt_torque_Nm"]
    cut = a["cutting"] > 0
    if cut.any():
        readings = [float(np.max(np.abs(a[k][cut]))) for k in ("force_N", "Q_N", "rod_force_N")]
        values["peak_Q_cut_N"] = readings[1]
        values["Q_reading_spread"] = (max(readings) - min(readings)) / readings[1]
    return replace(result, values=values, arrays=arrays)          # the steady motion's status, timing, words


def _peak(phi, y, mode):
    """(largest |y|, crank angle [rad]): the largest sample, refined by the parabola through it and
    its neighbours when all three lie in one piece (a smooth peak; a peak at the jump is a sample)."""
    i = int(np.argmax(np.abs(y)))
    best, at = float(abs(y[i])), float(phi[i])
    if 0 < i < len(y) - 1 and mode[i - 1] == mode[i] == mode[i + 1] and phi[i - 1] < phi[i] < phi[i + 1]:
        c = np.polyfit(phi[i - 1:i + 2] - phi[i], y[i - 1:i + 2], 2)
        if c[0] != 0:
            vertex = -c[1] / (2 * c[0])
            if phi[i - 1] - phi[i] < vertex < phi[i + 1] - phi[i] and abs(np.polyval(c, vertex)) > best:
                best, at = float(abs(np.polyval(c, vertex))), float(phi[i] + vertex)
    return best, at
