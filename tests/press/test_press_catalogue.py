"""press.catalogue: a motor row and a belt ratio from a catalogue, by enumeration
with the continuous design NLP inside; the cheapest feasible row and its margin."""
import dataclasses

import numpy as np
import pytest

from mechopt import load
from mechopt.kit.errors import ModelError
from mechopt.kit.result import Status
from mechopt.solvers.press import catalogue, design

SCENE = load("press/motor-catalogue")
TASK = SCENE.build()[0]


@pytest.fixture(scope="module")
def stricter():
    """A reserve of 6 (the 0.37 kW motor's margin at its design is 5.1): that row must fail."""
    return catalogue(dataclasses.replace(TASK, motor_safety_factor=6.0))


def test_the_cheapest_feasible_row_is_chosen_and_every_cheaper_one_is_shown_infeasible(stricter):
    assert stricter.status is Status.SOLVED, stricter.message
    chosen = int(stricter.values["motor_row"])
    assert chosen > 0 and TASK.motors[chosen][0] in stricter.message
    assert "cheaper rows: IEC 71 0.37 kW" in stricter.message
    # the margin is what the chosen motor's breakdown torque leaves over the peak shaft torque
    assert stricter.values["motor_torque_margin"] >= 6.0 * (1 - 1e-6)
    # the cheaper row at every ratio the search designed it with: not SOLVED, or off the speed band
    table = stricter.arrays
    cheaper = table["row"] < chosen
    assert cheaper.any() and not np.any(table["code"][cheaper] == 0)


def test_the_chosen_design_is_the_design_of_that_row_and_ratio(stricter):
    """The enumeration adds nothing to the continuous NLP: the same row and ratio designed directly
    give the same least flywheel."""
    k, ratio = int(stricter.values["motor_row"]), stricter.values["gear_ratio"]
    direct = design(dataclasses.replace(TASK, motor_safety_factor=6.0).candidate(TASK.motors[k], ratio))
    assert direct.status is Status.SOLVED
    assert direct.values["flywheel_inertia_kgm2"] == pytest.approx(stricter.values["flywheel_inertia_kgm2"], rel=1e-9)


@pytest.mark.parametrize("change, key", [
    ({"motors": (("bad row", 1.0, -2.0, 0.01),)}, "motors"),
    ({"motors": ()}, "motors"),
    ({"ratios": (0.0,)}, "ratios"),
    ({"variables": ("flywheel_inertia_kgm2", "gear_ratio")}, "variables"),
    ({"max_speed_deviation": 0.0}, "max_speed_deviation"),
])
def test_a_bad_catalogue_is_refused_naming_its_key(change, key):
    with pytest.raises(ModelError) as refused:
        dataclasses.replace(TASK, **change)
    assert refused.value.key == key
