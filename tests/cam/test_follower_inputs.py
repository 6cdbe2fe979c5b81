"""Bad input to the cam wing: a clear error naming the key and what is allowed, from Python and
from a scene file alike; segments whose angles miss a turn refused with their sum."""
import math

import pytest
from cam_closed_forms import CycloidRDRD

from mechopt import registry
from mechopt.kit.errors import MechoptError, ModelError
from mechopt.kit.result import Status
from mechopt.models.cam_followers import CamFollower
from mechopt.scene import load
from mechopt.solvers.cam import least_base_radius, size_cam


def make(**kw):
    return CamFollower(**({"base_radius_mm": 40.0, "roller_radius_mm": 10.0, "motion": CycloidRDRD()} | kw))


@pytest.mark.parametrize("kw, key, words", [
    ({"roller_radius_mm": 0.0}, "roller_radius_mm", "needs roller_radius_mm > 0"),
    ({"roller_radius_mm": -1.0}, "roller_radius_mm", "roller_radius_mm=-1.0: allowed 0 ... 100,000"),
    ({"offset_mm": 60.0}, "offset_mm", "allowed |offset| < base + roller radius = 50 mm"),
    ({"follower": "oscillating"}, "pivot_distance_mm", "an oscillating follower needs it > 0"),
    ({"follower": "oscillating", "pivot_distance_mm": 300.0, "arm_mm": 80.0}, "pivot_distance_mm",
     "cannot reach the prime circle"),
    ({"face": "flat", "follower": "oscillating", "pivot_distance_mm": 50.0, "arm_mm": 80.0, "face_offset_mm": 20.0},
     "face_offset_mm", "the face cannot touch the base circle"),
    ({"closure": "groove", "face": "flat"}, "closure", "takes a roller follower"),
    ({"sense": "clockwise"}, "sense", "allowed ccw, cw"),
    ({"base_radius_min_mm": 50.0, "base_radius_max_mm": 20.0}, "base_radius_min_mm", "allowed 0 < min < max"),
    ({"motion": None}, "segments", "give the cam's `segments`"),
    ({"motion": object()}, "motion", "expected an object with at(theta_rad)"),
])
def test_an_impossible_follower_is_refused_by_name(kw, key, words):
    with pytest.raises(ModelError) as caught:
        make(**kw)
    assert caught.value.key == key and words in str(caught.value)


def test_an_arm_swung_past_the_line_to_the_cam_is_refused_naming_the_arm():
    task = make(follower="oscillating", pivot_distance_mm=100.0, arm_mm=20.0, roller_radius_mm=10.0,
                base_radius_mm=75.0, motion=CycloidRDRD(h=60.0))
    with pytest.raises(ModelError, match=r"the arm swings to .* deg .* past it") as caught:
        size_cam(task)
    assert caught.value.key == "arm_mm"


def test_least_base_radius_without_bounds_is_refused():
    with pytest.raises(ModelError, match="needs base_radius_min_mm and base_radius_max_mm"):
        least_base_radius(make())


def test_a_follower_driven_at_90_degrees_is_named_not_a_nan():
    # an oscillating flat face whose contact passes the foot of the pivot's perpendicular: the
    # normal runs through the pivot, no force turns the follower (and this cam is cusped too)
    task = make(face="flat", follower="oscillating", pivot_distance_mm=50.0, arm_mm=30.0, base_radius_mm=10.0,
                face_offset_mm=10.0, motion=CycloidRDRD(h=40.0), mass_kg=1.0, spring_rate_N_per_mm=1.0,
                speed_rpm=10.0)
    r = size_cam(task, samples=720)
    assert r.status is Status.INFEASIBLE and "pressure_angle" in r.violated
    assert "the follower locks there" in r.message and "max_contact_force_N" not in r.values
    assert all(math.isfinite(v) for v in r.values.values())


SCENE = registry.find("cam/translating-roller").path


def test_segments_that_miss_a_turn_are_refused_naming_the_file_and_the_sum(tmp_path):
    text = SCENE.read_text("utf-8").replace("angle_deg = 120.0\nlift_mm = -30.0", "angle_deg = 110.0\nlift_mm = -30.0")
    mine = tmp_path / "short.toml"
    mine.write_text(text, "utf-8")
    with pytest.raises(MechoptError) as caught:
        load(mine)
    assert str(mine) in str(caught.value) and "350 deg" in str(caught.value) and "360" in str(caught.value)


def test_a_bad_value_set_on_the_command_line_names_its_range():
    with pytest.raises(MechoptError, match=r"roller_radius_mm=-5: allowed 0 \.\.\. 100,000"):
        registry.run("cam/translating-roller", {"roller_radius_mm": -5})


def test_an_acceleration_jump_between_segments_reaches_the_cams_warnings_and_refuse_makes_it_an_error():
    harmonic = {"segments[segment=return].law": "harmonic"}
    r = registry.run("cam/translating-roller", harmonic)
    assert any("acceleration jump of -33.75 mm/rad^2 at cam angle 180 deg" in w and "infinite jerk" in w
               for w in r.result.warnings)
    with pytest.raises(MechoptError, match="joins='refuse'"):
        registry.run("cam/translating-roller", harmonic | {"joins": "refuse"})
