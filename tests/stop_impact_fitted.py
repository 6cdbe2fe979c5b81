"""The earlier fitted reading of the lift lever (before the cam chain): v0 = velocity_factor *
stroke * Omega / t and a separately fitted J_A. The scenes now take the chain; the tests keep this
reading to pin eq. (2)'s methods and to show, beside the chain, what fitting did. Its numbers:
velocity_factor fitted to 0.07 mm at 280 rpm, J_A to 4.137 N at 280 rpm, t_deg to the slope
-0.003 mm/deg (the scenes' mass and plate overhang, fitted to 297 / 768 Hz, are shared)."""
from mechopt.models.stop_impact import LeverStop

LEVER = {"E_GPa": 210.0, "J_x_mm4": 13020.8, "a_mm": 80.0, "b_mm": 120.0, "a_stop_mm": 80.0, "b_stop_mm": 56.2286,
         "mass_kg": 0.81792, "stroke_mm": 20.0, "velocity_factor": 0.379503, "t_deg": 35.0, "restitution": 5 / 9}
J_A_FITTED_KGM2 = 1.90100e-4
FREE = ("initial_velocity", "impact_pulse", "damping")

FITTED_SCENES = {    # what the earlier scenes of these ids held
    "stop-impact/impact-force": {"effects": ("initial_velocity", "impact_pulse"), "speeds_rpm": (280.0, 420.0)},
    "stop-impact/rebound-280-420": {"effects": FREE, "damping_ratio": 0.05, "speeds_rpm": (280.0, 320.0, 370.0, 420.0)},
    "stop-impact/rebound-177rpm": {"effects": (*FREE, "preload"), "damping_ratio": 0.05, "preload_mm": 0.25,
                                   "speeds_rpm": (177.0,)},
    "stop-impact/amplitude-law": {"effects": FREE, "damping_ratio": 0.05, "speed_nominal_rpm": 420.0,
                                  "amplitude_limit_mm": 0.1},
    "stop-impact/rebound-map": {"effects": FREE, "damping_ratio": 0.05, "speed_nominal_rpm": 280.0,
                                "amplitude_limit_mm": 0.1},
}


def fitted_task(scene_id, **change):
    """The fitted reading's LeverStop for what scene `scene_id` held, with `change` applied."""
    return LeverStop(**(LEVER | {"inertia_A_kgm2": J_A_FITTED_KGM2} | FITTED_SCENES[scene_id] | change))
