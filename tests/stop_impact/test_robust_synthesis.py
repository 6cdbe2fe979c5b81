"""The lift law synthesised on a box of the lever's uncertain inputs (natural frequencies, damping,
a speed margin), checked by the chain on a finer grid of the box built here, not by the synthesis'
own box (solvers/stop_impact/lever_box.py)."""
import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Status
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm
from mechopt.solvers.stop_impact.synthesis import law_of, synthesise_law

BOX = dict(box_frequency_low=0.9, box_frequency_high=1.1, box_zeta_low=0.03, box_zeta_high=0.08, box_speed_margin=0.05)
# coarse: what the tests show holds at any setting (the scenes run 24 coefficients, 5 speeds, 0.05 deg)
COARSE = dict(objective="least_phase", coefficients=8, sample_speeds=2, phase_from_deg=26.0, phase_to_deg=45.0,
              phase_tol_deg=0.1, max_acceleration_mm_per_rad2=570.0, compare=False)
ROBUST_SCENE = "stop-impact/law-synthesis-robust"
AGREEMENT = 2e-3            # the synthesis' agreement_rel: the chain against its linear model, of the limit


@pytest.fixture(scope="module")
def lever():
    return registry.find(ROBUST_SCENE).build()[0]


@pytest.fixture(scope="module")
def robust(lever):
    return synthesise_law(lever, robust=True, **COARSE, **BOX)


@pytest.fixture(scope="module")
def nominal(lever):
    return synthesise_law(lever, **COARSE, **BOX)


def box_lever(lever, factor, zeta, law):
    """The lever with both natural frequencies times `factor` (E times its square) and damping `zeta`."""
    return dataclasses.replace(lever, E_GPa=lever.E_GPa * factor**2, damping_ratio=zeta, law=law)


def chain_worst_mm(lever, law, t_deg, factors, zetas, speeds):
    """The chain's largest rebound over the grid factors x zetas x speeds, and where."""
    worst = (-1.0, None)
    for f in factors:
        for z in zetas:
            a = rebound_amplitude_mm(box_lever(lever, f, z, law), speeds, t_deg)
            j = int(np.argmax(a))
            worst = max(worst, (float(a[j]), (f, z, float(speeds[j]))), key=lambda w: w[0])
    return worst


def test_a_box_lever_has_both_frequencies_scaled_by_its_factor(lever):
    other = box_lever(lever, 0.9, 0.03, lever.law)
    assert other.f_free_Hz / lever.f_free_Hz == pytest.approx(0.9, rel=1e-12)
    assert other.f_stop_Hz / lever.f_stop_Hz == pytest.approx(0.9, rel=1e-12)


def test_the_robust_law_keeps_the_limit_on_a_finer_grid_of_the_box(lever, robust):
    assert robust.status is Status.SOLVED, robust.message
    t = robust.values["t_min_robust_deg"]
    worst, where = chain_worst_mm(lever, law_of(robust), t, np.linspace(0.9, 1.1, 4), np.linspace(0.03, 0.08, 4),
                                  np.arange(280.0, 441.0 + 1e-9, 2.5))
    assert worst <= lever.amplitude_limit_mm * (1 + AGREEMENT), where
    # the synthesis' own worst over its coarser grid is no larger than this finer grid's
    assert robust.values["rebound_worst_box_mm"] <= worst + AGREEMENT * lever.amplitude_limit_mm


def test_the_nominal_law_breaks_the_limit_somewhere_in_the_box(lever, nominal, robust):
    assert nominal.status is Status.SOLVED, nominal.message
    at = nominal.diagnostics["rebound_worst_box_at"]
    a = float(rebound_amplitude_mm(box_lever(lever, at["frequency_factor"], at["zeta"], law_of(nominal)),
                                   at["speed_rpm"], nominal.values["t_min_synthesized_deg"]))
    assert a > lever.amplitude_limit_mm * 1.05
    assert a == pytest.approx(nominal.values["rebound_worst_box_mm"], rel=1e-9)
    # robustness costs phase angle: the robust law needs more
    assert robust.values["t_min_robust_deg"] > nominal.values["t_min_synthesized_deg"]


def test_a_box_of_one_point_gives_the_nominal_law(lever, nominal):
    z = lever.damping_ratio
    one = synthesise_law(lever, robust=True, **COARSE, box_zeta_low=z, box_zeta_high=z)
    assert one.status is Status.SOLVED
    assert one.values["t_min_synthesized_deg"] == nominal.values["t_min_synthesized_deg"]
    assert law_of(one).coefficients == law_of(nominal).coefficients


@pytest.mark.parametrize("bad, key", [(dict(box_frequency_low=0.0), "box_frequency_low"),
                                      (dict(box_frequency_low=-0.5), "box_frequency_low"),
                                      (dict(box_zeta_low=0.08, box_zeta_high=0.03), "box_zeta_low"),
                                      (dict(box_frequency_low=1.1, box_frequency_high=0.9), "box_frequency_low")])
def test_bad_box_input_is_a_clear_error_naming_the_key(lever, bad, key):
    with pytest.raises(SettingError, match=key) as caught:
        synthesise_law(lever, robust=True, **COARSE, **(BOX | bad))
    assert caught.value.key == key


def test_the_synthesis_is_bit_identical_with_two_cpu_burners_beside_it(lever, nominal):
    """Counts, never seconds: the same law, angle and values on a loaded machine."""
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        loaded = synthesise_law(lever, **COARSE, **BOX)
    finally:
        for p in burners:
            p.kill()
            p.wait()
    assert law_of(loaded).coefficients == law_of(nominal).coefficients
    assert loaded.values == nominal.values


def test_the_box_settings_are_declared_once_for_both_solvers_and_checked_by_the_scene_loader(lever):
    """The synthesis and the co-design show the same six box settings (lever_box.BOX_SETTINGS) to the
    scene loader; a scene's bad box setting is refused before any solve, naming the key; a Python
    caller gives the box or its settings, not both."""
    from mechopt.scene import solver_options
    from mechopt.solvers.loom.codesign import codesign_machine_speed
    from mechopt.solvers.stop_impact.lever_box import BOX_SETTINGS, LeverBox
    for solver in (synthesise_law, codesign_machine_speed):
        options = solver_options(solver)
        assert "box" not in options
        assert [options[p.name] for p in BOX_SETTINGS] == list(BOX_SETTINGS)
    with pytest.raises(SettingError, match="box_zeta_low") as caught:
        registry.run("stop-impact/law-synthesis", {"box_zeta_low": 2.0})
    assert caught.value.key.endswith("box_zeta_low")
    with pytest.raises(SettingError, match="box_grid"):
        synthesise_law(lever, box=LeverBox(), box_grid=4, **COARSE)
