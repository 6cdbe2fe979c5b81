"""press.flywheel: the least flywheel alone by a safeguarded secant on the periodic solution,
against the NLP (press.design) on the same question, and its refusals and bounds."""
import dataclasses

import numpy as np
import pytest

from mechopt import registry
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.models.press_design import single_stroke_margin_J
from mechopt.solvers import press as pd

TASK, _ = registry.find("press/flywheel-design-newton").build()


def test_the_secant_finds_the_nlps_least_flywheel_in_a_handful_of_periodic_solves():
    secant = pd.flywheel(TASK)
    nlp = pd.design(TASK)
    assert secant.status is Status.SOLVED and nlp.status is Status.SOLVED
    assert secant.values["flywheel_inertia_kgm2"] == pytest.approx(nlp.values["flywheel_inertia_kgm2"], rel=2e-6)
    assert secant.values["speed_fluctuation"] == pytest.approx(0.01, rel=1e-9)
    assert secant.values["periodic_solves"] <= 8
    assert secant.values["single_stroke_margin_J"] > 0


def test_bounds_and_single_stroke_decide_when_they_bind():
    """A 50 % limit any flywheel keeps: the single stroke sets the flywheel (as the NLP finds it);
    without it the lower bound does; a 0.1 % limit within 6 kg m2 is infeasible."""
    loose = dataclasses.replace(TASK, max_speed_fluctuation=0.5)
    run = pd.flywheel(loose)
    assert run.status is Status.SOLVED and run.diagnostics["active"] == "single_stroke"
    # the least such flywheel: the energy balance of the cut (closed form) at the orbit's entry speed holds
    # at J and fails 0.1 % below it (the NLP cannot check this one: so small a flywheel puts the belt mode
    # past what it affords, and it designs on the rigid-belt limit instead)
    J = run.values["flywheel_inertia_kgm2"]
    for factor, sign in ((1.0, 1), (0.999, -1)):
        orbit = pd.steady_state(loose.drive({"flywheel_inertia_kgm2": factor * J}), samples=200)
        entry = float(np.interp(loose.cut_window_rad()[0], orbit.arrays["phi_rad"], orbit.arrays["omega_rad_s"]))
        assert sign * single_stroke_margin_J(loose, factor * J, entry, loose.single_stroke_speed_drop) >= -1e-9
    free = pd.flywheel(dataclasses.replace(loose, single_stroke_speed_drop=None))
    assert free.values["flywheel_inertia_kgm2"] == pytest.approx(TASK.flywheel_inertia_min_kgm2, rel=1e-12)
    tight = dataclasses.replace(TASK, max_speed_fluctuation=0.001, flywheel_inertia_max_kgm2=6.0)
    assert pd.flywheel(tight).status is Status.INFEASIBLE


def test_the_design_questions_it_does_not_take_are_refused():
    with pytest.raises(ModelError, match=r"press\.design takes the others"):
        pd.flywheel(dataclasses.replace(TASK, variables=("flywheel_inertia_kgm2", "gear_ratio")))
    with pytest.raises(ModelError, match=r"max_speed_fluctuation missing"):
        pd.flywheel(dataclasses.replace(TASK, max_speed_fluctuation=None))
