"""Where the stop-impact model ends: each edge a status or a refusal naming its key,
never a long run or an input error for a physical outcome."""
import pytest

from mechopt import registry
from mechopt.kit.errors import SceneError
from mechopt.kit.result import Status


def test_a_preload_past_the_stroke_is_refused_before_any_work():
    with pytest.raises(SceneError, match=r"params\.preload_mm=100\.0: allowed < stroke_mm=35\.0295"):
        registry.run("stop-impact/rebound-177rpm", {"preload_mm": 100.0})


def test_a_lever_slower_than_its_cycle_is_a_limit_of_the_model_not_a_contact_turns_later():
    result = registry.run("stop-impact/cam-dynamics", {"E_GPa": 1e-3}).result
    assert result.status is Status.LIMIT
    assert "slower than its cycle at 420 rpm" in result.message and "E_GPa" in result.message


def test_a_roller_leaving_its_cam_on_the_way_to_the_bound_is_infeasible_not_bad_input():
    result = registry.run("stop-impact/amplitude-law", {"damping_ratio": 1.0}).result
    assert result.status is Status.INFEASIBLE and result.violated == ("cam_contact",)
    assert "the roller leaves the cam" in result.message
    assert result.values["slope_mm_per_deg"] < 0          # the tangent at the nominal point is kept
