"""Humanoid_CMU's batched `HumanoidCMU`: every world is dm_control's episode, bit for bit."""

import pytest
from episodes import differences, needs_suite
from test_humanoid import assert_batch_is_cpu, random_rows

pytestmark = needs_suite

HUMANOID_CMU_TASKS = ("stand", "walk", "run")


def test_the_batch_has_every_humanoid_cmu_task_of_the_suite(suite):
    assert set(HUMANOID_CMU_TASKS) == {
        task for domain, task in suite.ALL_TASKS if domain == "humanoid_CMU"
    }


@pytest.mark.parametrize("task", HUMANOID_CMU_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "humanoid_CMU", task) == []


@pytest.mark.parametrize("task", HUMANOID_CMU_TASKS)
def test_rewards_and_observations_are_dm_controls_on_many_states(suite, task):
    # The thorax's frame and its y axis's uprightness, the CMU model's 56 controls.
    env = suite.load("humanoid_CMU", task, task_kwargs={"random": 0})
    assert_batch_is_cpu(env, random_rows(env, 512))
    env.close()
