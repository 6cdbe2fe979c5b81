"""Units read from names by a grammar (mechopt.units): the suffix in full, `_per_` as a quotient,
powers, derivatives, elasticities, a trailing case number; every key of every scene reads cleanly."""
import pytest

from mechopt import registry
from mechopt.scene import solver_options, task_fields
from mechopt.units import SYMBOLS, label, parse, unit_of


@pytest.mark.parametrize("name, unit", [
    ("sens_sigma_H_deg_per_MPa", "deg/MPa"), ("sens_amplitude_limit_deg_per_mm", "deg/mm"),
    ("velocity_analogue_error_mm_per_rad", "mm/rad"), ("acceleration_analogue_error_mm_per_rad2", "mm/rad²"),
    ("J_x_mm4", "mm⁴"), ("c1_N_per_mm1", "N/mm"), ("c2_N_per_mm2", "N/mm²"), ("c4_N_per_mm4", "N/mm⁴"),
    ("force_c3_N_mm3", "N/mm³"), ("c_stop_N_per_mm", "N/mm"), ("amplitude_slope_mm_per_deg", "mm/deg"),
    ("d_flywheel_inertia_kgm2_d_max_speed_fluctuation", "kg m²"),
    ("d_motor_rms_torque_N_m_d_nominal_speed_rad_s", "N m/(rad/s)"),
    ("d_cut_work_J", "J/(parameter)"),                         # a sensitivity table's column: per row's parameter
    ("speed_fluctuation_elasticity_flywheel_inertia_kgm2", ""), ("elasticity_cut_work_J", ""),
    ("belt_damping_Nms_rad", "N m s/rad"), ("belt_stiffness_Nm_rad", "N m/rad"), ("gravity_m_s2", "m/s²"),
    ("alpha_rad_s2", "rad/s²"), ("M_N_m", "N m"), ("max_driving_torque_N_m", "N m"), ("N_N", "N"),
    ("rebound_mm_280", "mm"), ("approach_velocity_m_s_420", "m/s"), ("impulse_Ns_280", "N s"),
    ("p_10.1_deg", "deg"), ("t_s", "s"), ("cycle_time_ms", "ms"), ("flywheel_inertia_kgm2", "kg m²"),
    ("speed_fluctuation", ""), ("max_iter", ""), ("impulse_over_momentum_280", ""), ("E_GPa", "GPa"),
])
def test_the_suffix_is_read_in_full(name, unit):
    assert unit_of(name) == unit


def test_labels_keep_the_words_and_the_case_number():
    assert label("rebound_mm_280") == "rebound 280 [mm]"
    assert label("sens_sigma_H_deg_per_MPa") == "sens sigma H [deg/MPa]"
    assert label("d_flywheel_inertia_kgm2_d_max_speed_fluctuation") == \
        "d flywheel inertia / d max speed fluctuation [kg m²]"
    assert label("speed_fluctuation_elasticity_rod_mass_kg") == "speed fluctuation elasticity rod mass"


def unread(name: str) -> list[str]:
    """Unit symbols or `per` left among a name's words (its first word may be a symbol: `N_N`)."""
    words = parse(name)[0].replace(" / d ", " ").split()
    unit = [w in SYMBOLS or w.rstrip("1234") in SYMBOLS for w in words] + [False]
    return [w for i, w in enumerate(words) if i and (unit[i] or (w == "per" and unit[i + 1]))]


def test_the_check_bites_on_the_old_reading():
    assert unread("sens_sigma_H_deg_per_MPa") == []
    assert unread("elasticity_cut_work_J") == []                    # an elasticity drops its unit words
    assert unread("force_x_mm_deg_per_stroke") == ["mm", "deg"]     # a unit not at the end is named
    assert unread("energy_per_stroke_J") == [] and unread("slope_per_mm_x") == ["per", "mm"]


@pytest.mark.parametrize("scene", registry.all_scenes(), ids=lambda s: s.id)
def test_every_key_of_every_scene_reads_its_unit_cleanly(scene):
    keys = {*task_fields(scene.task_class), *solver_options(scene.solver), *scene.spec.params, *scene.spec.expect}
    assert not {k: unread(k) for k in keys if unread(k)}
