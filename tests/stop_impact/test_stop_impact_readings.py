"""Readings of paper 004's stop impact: how C leaves the plate (the scene
key `launch`), the paper's own reading (a rebound proportional to n / t), and no stop-impact
check that passes by construction."""
import math

import pytest

from mechopt import registry
from mechopt.kit.errors import ModelError
from mechopt.models.stop_impact import LeverStop
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm

LEVER = dict(E_GPa=210.0, J_x_mm4=13020.8, a_mm=80.0, b_mm=120.0, a_stop_mm=80.0, b_stop_mm=56.2286, mass_kg=0.81792,
             stroke_mm=20.0, velocity_factor=0.34, t_deg=34.667, restitution=5 / 9, damping_ratio=0.05,
             effects=("initial_velocity", "impact_pulse", "damping"))


def test_each_launch_reading_starts_eq_2_as_it_says():
    pulse, newton = (LeverStop(**LEVER, launch=launch) for launch in ("pulse_plus_v0", "restitution"))
    v0 = pulse.approach_velocity_m_s(280.0)
    with_pulse, restituted = pulse.impact(280.0), newton.impact(280.0)
    assert with_pulse.v0_m_s == pytest.approx(v0, rel=1e-15)      # q0' = v0, and the pulse reverses m v0 on top
    assert with_pulse.force_N * with_pulse.tau_s == pytest.approx((1 + 5 / 9) * LEVER["mass_kg"] * v0, rel=1e-12)
    assert restituted.v0_m_s == pytest.approx(5 / 9 * v0, rel=1e-15)   # Newton: C leaves at k v0, no pulse
    assert restituted.force_N == 0.0


def test_restitution_rebound_is_the_damped_free_swing_from_k_v0():
    """q = k v0 e^{-n t} sin(k1 t) / k1 peaks at tan(k1 t) = k1 / n: written out by hand."""
    task = LeverStop(**LEVER, launch="restitution")
    w, zeta = task.omega_stop_rad_s, LEVER["damping_ratio"]
    n, k1 = zeta * w, w * math.sqrt(1 - zeta**2)
    peak_t = math.atan2(k1, n) / k1
    by_hand = 5 / 9 * task.approach_velocity_m_s(280.0) * math.exp(-n * peak_t) * math.sin(k1 * peak_t) / k1
    assert float(rebound_amplitude_mm(task, 280.0, LEVER["t_deg"])) == pytest.approx(by_hand * 1e3, rel=1e-12)


@pytest.mark.parametrize("launch", ["pulse_plus_v0", "restitution"])
def test_without_preload_either_launch_gives_a_rebound_proportional_to_n_over_t(launch):
    task = LeverStop(**LEVER, launch=launch)
    a = rebound_amplitude_mm(task, [280.0, 420.0, 420.0], [30.0, 30.0, 45.0])
    assert a[0] / a[1] == pytest.approx(280 / 420, rel=1e-12)
    assert a[2] / a[1] == pytest.approx(30 / 45, rel=1e-12)


def test_an_unknown_launch_or_one_without_its_effects_is_refused_by_name():
    with pytest.raises(ModelError, match=r"launch='bounce': allowed pulse_plus_v0, restitution"):
        LeverStop(**LEVER, launch="bounce")
    with pytest.raises(ModelError, match=r"launch='restitution' needs the effect 'initial_velocity'"):
        LeverStop(**(LEVER | {"effects": ("impact_pulse", "damping")}), launch="restitution")


def test_the_scenes_declare_their_launch_and_the_177_rpm_figure_tells_the_two_apart():
    """The paper's reading under its text's launch misses 0.022 mm by 12 %; Newton's restitution meets it."""
    pulse = registry.run("stop-impact/rebound-177rpm-paper-reading")
    newton = registry.run("stop-impact/rebound-177rpm-restitution-paper-reading")
    assert pulse.task.launch == "pulse_plus_v0" and newton.task.launch == "restitution"
    assert pulse.result.values["rebound_mm_177"] == pytest.approx(0.019262, rel=1e-4)
    assert newton.result.values["rebound_mm_177"] == pytest.approx(0.021715, rel=1e-4)
    measured = {c.name: c for c in pulse.checks}["rebound_experiment_mm_177"]     # a second row of one value (of = ...)
    assert measured.got == pulse.result.values["rebound_mm_177"] and measured.verdict == "reproduced"


def test_the_papers_reading_makes_its_law_the_tangent_of_a_hyperbola():
    """a = K n / t: slope -a0 / t0 and intercept 2 a0 (an independent formula for the solver's tangent)."""
    v = registry.run("stop-impact/law-paper-reading").result.values
    a0, t0 = v["amplitude_nominal_mm"], registry.find("stop-impact/law-paper-reading").params()["t_deg"]
    assert v["slope_mm_per_deg"] == pytest.approx(-a0 / t0, rel=1e-9)
    assert v["intercept_mm"] == pytest.approx(2 * a0, rel=1e-9)


STOP_SCENES = [s for s in registry.all_scenes() if s.id.startswith("stop-impact/")]


@pytest.mark.parametrize("scene", STOP_SCENES, ids=lambda s: s.id)
def test_no_derived_stop_impact_check_holds_whatever_the_lever(scene, solved_once):
    """A derived number that no input moves cannot fail (S / (m v0) = 1 + k was one):
    with the lever 2 % stiffer every derived numeric check's value must move."""
    derived = [name for name, e in scene.spec.expect.items()     # (a count moves by whole steps only: left out)
               if e.kind == "derived" and isinstance(e.value, float) and e.max is None and e.min is None]
    if not derived:
        pytest.skip("no derived numeric check")
    before = registry.run(scene).result.values
    key = "E_GPa" if "E_GPa" in scene.params() else "base_radius_mm"     # the lift cam's shape: its cam, not the lever
    after = registry.run(scene, {key: scene.params()[key] * 1.02}).result.values
    still = [name for name in derived if after[name] == pytest.approx(before[name], rel=1e-9)]
    assert not still, f"{scene.id}: {still} do not depend on {key}"
