"""Where a model leaves what its source or its own derivation supports: the sentences of a
Result's `warnings`. The answer stands; the warning says how far to trust it.

Each range is data: given by the scene (eq. (1)'s fitted travel, the speeds a lever's law was
studied at) or following from the model's own derivation (the paper's lambda << 1 kinematics,
a single-mode lever). A range the scene does not state is not checked.
"""
import numpy as np

from mechopt.models.loom import Cyclogram
from mechopt.models.press import PressDrive, cutting_force_N
from mechopt.models.stop_impact import LeverStop

# The paper's X(phi) drops the O(lambda^3) terms of the crank-slider; past this error of the tool's
# acceleration (relative to its exact peak: about lambda = 0.29) the inertia loads it gives are off.
PAPER_KINEMATICS_TOLERANCE = 0.01


def paper_kinematics_error(rod_ratio: float, samples: int = 2881) -> float:
    """Largest error of the paper's X''(phi) / r = cos phi + lambda cos 2 phi against the exact
    crank-slider's, over a turn, relative to the exact peak [-] (0.00017 at lambda = 0.071)."""
    phi = np.linspace(0.0, 2 * np.pi, samples)
    s, c = np.sin(phi), np.cos(phi)
    root = np.sqrt(1 - rod_ratio**2 * s**2)
    exact = c + rod_ratio * (c**2 - s**2) / root + rod_ratio**3 * s**2 * c**2 / root**3
    paper = c + rod_ratio * np.cos(2 * phi)
    return float(np.max(np.abs(paper - exact)) / np.max(np.abs(exact)))


def press_warnings(task: PressDrive) -> list[str]:
    out = []
    top = task.force_fit_max_mm
    if task.cutting and top is not None and task.blank_thickness_mm > top:
        forces = [cutting_force_N(x, task.force_c1_N_mm, task.force_c2_N_mm2, task.force_c3_N_mm3,
                                  task.force_c4_N_mm4) for x in (task.blank_thickness_mm, top)]
        out.append(f"eq. (1) extrapolated beyond X = {top:g} mm, its fitted range: at X = blank_thickness_mm = "
                   f"{task.blank_thickness_mm:g} mm it gives {forces[0] / 1000:.3g} kN, "
                   f"{forces[0] / forces[1]:.2g}x its value at {top:g} mm")
    if task.kinematics == "paper":
        error = paper_kinematics_error(task.rod_ratio)
        if error > PAPER_KINEMATICS_TOLERANCE:
            out.append(f"kinematics = 'paper' (lambda << 1) at rod_ratio = {task.rod_ratio:g}: its tool acceleration "
                       f"is off by {error:.1%} of the exact crank-slider's peak; use kinematics = 'exact'")
    return out


def lever_warnings(lever: LeverStop, speeds_rpm) -> list[str]:
    """A single-mass lever model needs its first mode faster than the cycle it is struck in."""
    slow = [n for n in speeds_rpm if n is not None and lever.f_free_Hz < n / 60]
    if not slow:
        return []
    return [f"the lever's first mode ({lever.f_free_Hz:.3g} Hz) is slower than the cycle at {max(slow):g} rpm "
            f"({max(slow) / 60:.3g} Hz): it does not settle between strikes, which the single-mass rebound assumes"]


def cyclogram_warnings(task: Cyclogram, values: dict) -> list[str]:
    out = []
    speed = values.get("max_speed_rpm", task.speed_rpm)
    if task.lever is not None and speed is not None:
        lever = task.lever_model
        out += lever_warnings(lever, [speed])
        top = task.lever_law_max_rpm
        if top is not None and speed > top:
            out.append(f"the lever's rebound law is applied at {speed:.4g} rpm, above lever_law_max_rpm = {top:g} rpm, "
                       f"the highest speed its source studied: an extrapolation")
    return out


def out_of_range(task, values: dict) -> tuple[str, ...]:
    """Every warning for a task (the model's inputs) and its result's `values`."""
    if isinstance(task, PressDrive):
        return tuple(press_warnings(task))
    if isinstance(task, LeverStop):
        return tuple(lever_warnings(task, [*task.speeds_rpm, task.speed_nominal_rpm]))
    if isinstance(task, Cyclogram):
        return tuple(cyclogram_warnings(task, values))
    return ()
