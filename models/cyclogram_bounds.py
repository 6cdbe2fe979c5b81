"""Each operation's least phase angle under every limit: its [phi], its least duration at the speed
(min_ms), and the loom's laws an operation may name (contact stress, rebound amplitude:
models/loom_limits.py)."""
from functools import cached_property

import numpy as np

from mechopt.kit.errors import ModelError
from mechopt.models.loom_limits import amplitude_bound_deg, stress_bound_deg, stress_MPa


def time_floor_deg(min_ms, speed_rpm):
    """Angle the main shaft turns in `min_ms` at `speed_rpm` [deg]: 360 n / 60 deg/s times T."""
    return 0.006 * speed_rpm * min_ms



class Bounds:
    """The lower bounds of a Cyclogram's operations (a part of it: the dataclass's fields are the task's)."""

    def min_angles_deg(self) -> np.ndarray:
        """[phi] of every arc, in `arcs` order [deg] (a copy)."""
        return self._min_angles.copy()

    @cached_property
    def _min_angles(self) -> np.ndarray:
        phi = (self._columnar.min_deg.copy() if self._columnar is not None else   # a plain table's column
               np.fromiter((d["min_deg"] for d in self._arc_data), dtype=float, count=len(self._arc_data)))
        timed = self.time_arcs()
        if timed and self.speed_rpm is None:
            x, y = self.arcs[timed[0]]
            raise ModelError(f"operations[{x}->{y}].min_ms needs speed_rpm (a time becomes an angle at a speed)",
                             key="speed_rpm")
        if timed:
            phi[timed] = np.maximum(phi[timed], self.time_coeffs_deg_per_rpm()[timed] * self.speed_rpm)
        return phi

    def time_arcs(self) -> list[int]:
        """Indices (in `arcs` order) of the operations with a minimum duration `min_ms`."""
        return list(self._time_arcs)

    @cached_property
    def _time_arcs(self) -> tuple[int, ...]:
        return () if self._columnar is not None else tuple(k for k, d in enumerate(self._arc_data)
                                                          if d["min_ms"] is not None)

    def time_coeffs_deg_per_rpm(self) -> np.ndarray:
        """Per arc, the angle its `min_ms` asks for per rpm of main-shaft speed [deg/rpm] (0: none)."""
        out = np.zeros(len(self.arcs))
        for k in self.time_arcs():
            out[k] = time_floor_deg(self.arc_data(k)["min_ms"], 1.0)
        return out

    @property
    def stress_reference_rpm(self) -> float | None:
        """The speed the stress references hold at: stress_speed_rpm, else speed_rpm."""
        return self.speed_rpm if self.stress_speed_rpm is None else self.stress_speed_rpm

    def stress_at_MPa(self, k: int, t_deg, speed_rpm):
        """sigma_max of arc k's cam pair over t at speed n [MPa]: sigma_ref (t_ref / t) (n / n_ref)."""
        model = self.stress_models[self.arc_data(k)["stress"]]
        return stress_MPa(float(model["sigma_ref_MPa"]), float(model["t_ref_deg"]), t_deg) * speed_rpm \
            / self.stress_reference_rpm

    def stress_coeff_deg_per_rpm(self, k: int) -> float:
        """sigma_max(t, n) <= [sigma_H] as t >= coeff n: sigma_ref t_ref / ([sigma_H] n_ref)
        [deg/rpm], n_ref the speed the references hold at (`stress_reference_rpm`)."""
        if self.stress_reference_rpm is None:
            raise ModelError("stress_speed_rpm: the stress references need the speed they hold at",
                             key="stress_speed_rpm")
        model = self.stress_models[self.arc_data(k)["stress"]]
        return stress_bound_deg(float(model["sigma_ref_MPa"]), float(model["t_ref_deg"]),
                                self.sigma_H_limit_MPa) / self.stress_reference_rpm

    def stress_arcs(self) -> list[int]:
        """Indices (in `arcs` order) of the operations with a contact-stress model."""
        return list(self._model_arcs[0])

    def amplitude_arcs(self) -> list[int]:
        """Indices (in `arcs` order) of the operations with an amplitude model."""
        return list(self._model_arcs[1])

    @cached_property
    def _model_arcs(self):
        data = () if self._columnar is not None else self._arc_data      # a plain table names no law
        return ([k for k, d in enumerate(data) if d["stress"] is not None],
                [k for k, d in enumerate(data) if d["amplitude"] is not None])


    def stress_reference(self, k: int) -> tuple[float, float]:
        """(sigma_ref_MPa, t_ref_deg) of arc k's cam pair at the task's speed: the reference
        stress scaled by speed_rpm / stress_speed_rpm when both are given (sigma ~ n / t)."""
        model = self.stress_models[self.arc_data(k)["stress"]]
        scale = 1.0 if self.stress_speed_rpm is None or self.speed_rpm is None else self.speed_rpm / self.stress_speed_rpm
        return float(model["sigma_ref_MPa"]) * scale, float(model["t_ref_deg"])

    def lower_bounds_deg(self, stress_form: str = "exact") -> tuple[np.ndarray, list[str]]:
        """Each arc's smallest phase angle [deg] under every limit, and which limit sets it
        ("min_angle", "min_time", "contact_stress" or "amplitude")."""
        lb = self.min_angles_deg()
        why = ["min_angle"] * lb.size
        for k in self.time_arcs():
            if lb[k] > self.arc_data(k)["min_deg"]:
                why[k] = self.arc_data(k)["motion_limit"] or "min_time"
        for k in self.stress_arcs():
            bound = stress_bound_deg(*self.stress_reference(k), self.sigma_H_limit_MPa, stress_form)
            if bound > lb[k]:
                lb[k], why[k] = bound, "contact_stress"
        for k in self.amplitude_arcs() if self.has_linear_amplitude else ():
            bound = amplitude_bound_deg(self.amplitude_slope_mm_per_deg, self.amplitude_intercept_mm,
                                        self.amplitude_limit_mm)
            if bound > lb[k]:
                lb[k], why[k] = bound, "amplitude"
        return lb, why

