"""The chain's calibration has several roots: `fit_roots` finds them; each found root
is checked here by differences of the rebound law taken apart from the solver's own tangent."""
import dataclasses

import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import SettingError
from mechopt.kit.result import Status
from mechopt.solvers.stop_impact import fit_roots
from mechopt.solvers.stop_impact.law import rebound_amplitude_mm

SLOPE, INTERCEPT = -0.003, 0.208          # Sec. Results: a(3,7) = -0.003 t + 0.208


@pytest.fixture(scope="module")
def narrow():
    """The chain around its taken root: a 1.5 deg box, so the test stays short."""
    task, settings = registry.find("stop-impact/chain-fit-roots").build()
    return task, fit_roots(task, **(settings | {"t_min_deg": 35.0, "t_max_deg": 36.5}))


def test_a_root_found_is_a_tangent_of_the_law_by_independent_differences(narrow):
    task, result = narrow
    assert result.status is Status.SOLVED and result.values["roots"] == 1
    t, H = result.values["root_t_deg_1"], result.values["root_stroke_mm_1"]
    lever = dataclasses.replace(task, stroke_mm=H, t_deg=t)
    a = lambda dt: rebound_amplitude_mm(lever, 420.0, t + np.asarray(dt))
    h = 0.05
    coarse, fine = ((a([d]) - a([-d]))[0] / (2 * d) for d in (2 * h, h))
    slope = (4 * fine - coarse) / 3                      # Richardson on central differences
    assert slope == pytest.approx(SLOPE, rel=1e-5)
    assert float(a(0.0)) == pytest.approx(INTERCEPT + SLOPE * t, rel=1e-9)


def test_the_taken_calibration_is_the_root_the_rule_picks(narrow):
    task, result = narrow
    assert result.values["t0_deg"] == pytest.approx(INTERCEPT / (2 * -SLOPE), rel=1e-12)
    amplitude_law = registry.find("stop-impact/amplitude-law").params()
    assert result.values["root_t_deg_1"] == pytest.approx(amplitude_law["t_deg"], rel=1e-6)
    assert result.values["root_stroke_mm_1"] == pytest.approx(amplitude_law["stroke_mm"], rel=1e-5)
    # the spread over one root is no spread: the damping's is
    assert result.values["rebound_roots_min_mm_370"] == result.values["rebound_roots_max_mm_370"]
    assert result.values["rebound_damping_min_mm_370"] < result.values["rebound_mm_370"] \
        < result.values["rebound_damping_max_mm_370"]


def test_a_box_without_a_root_is_infeasible_not_an_answer_on_its_edge(narrow):
    task, _ = narrow
    result = fit_roots(task, t_min_deg=36.0, t_max_deg=37.0, t_step_deg=0.5)
    assert result.status is Status.INFEASIBLE and result.values["roots"] == 0


def test_an_empty_box_is_refused_naming_its_settings(narrow):
    task, _ = narrow
    with pytest.raises(SettingError, match=r"t_min_deg=40 must be below t_max_deg=30"):
        fit_roots(task, t_min_deg=40.0, t_max_deg=30.0)
