"""The suite's front door: names, tags, `load` and its errors, timing and action spec."""

import numpy as np
import pytest
from manipulation_specs import (
    EASY_NAMES,
    EXPECTED_SPECS,
    FEATURES_NAMES,
    VISION_NAMES,
)

import composer
import manipulation


def test_all_lists_dm_controls_25_environments_and_the_randomised_lift():
    assert len(manipulation.ALL) == 26
    assert "lift_brick_randomised_features" in manipulation.ALL
    assert set(manipulation.ALL) == set(EXPECTED_SPECS)


def test_tags_are_features_vision_and_easy():
    assert set(manipulation.TAGS) == {"features", "vision", "easy"}


@pytest.mark.parametrize(
    "tag, expected",
    [("features", FEATURES_NAMES), ("vision", VISION_NAMES), ("easy", EASY_NAMES)],
)
def test_get_environments_by_tag_returns_exactly_the_tagged_names(tag, expected):
    assert set(manipulation.get_environments_by_tag(tag)) == set(expected)


def test_get_environments_by_tag_rejects_an_unknown_tag():
    with pytest.raises(ValueError, match="unknown tag 'hard'"):
        manipulation.get_environments_by_tag("hard")


def test_load_rejects_an_unknown_name_and_suggests_close_ones():
    with pytest.raises(ValueError, match="reach_sight_features") as error:
        manipulation.load("reach_sight_features")
    assert "reach_site_features" in str(error.value)


def test_load_returns_a_composer_environment_with_the_suite_timing():
    env = manipulation.load("reach_site_features", seed=0)
    assert isinstance(env, composer.Environment)
    assert env.control_timestep() == pytest.approx(0.04)
    assert env.physics.timestep() == pytest.approx(0.002)


def test_action_is_six_arm_velocities_then_three_finger_velocities():
    spec = manipulation.load("lift_brick_features", seed=0).action_spec()
    assert spec.shape == (9,)
    np.testing.assert_allclose(spec.maximum, [0.6283] * 3 + [0.8378] * 3 + [5.0] * 3)
    np.testing.assert_allclose(spec.minimum, -spec.maximum)
    names = spec.name.split("\t")
    assert names[0] == "jaco_arm/joint_1_velocity"
    assert names[-1] == "jaco_arm/jaco_hand/finger_3_velocity"
