"""Quadruped's batched tasks: world i is dm_control's quadruped episode seeded alike, and
the escape task, whose episodes redraw the height field, is refused."""

import numpy as np
import pytest
from episodes import differences, needs_suite

import suite_batch
from suite_batch import tasks
from suite_batch.environment import SuiteBatchEnvironment

pytestmark = needs_suite

BATCHED = ("walk", "run", "fetch")
#: Escape's starts write a new terrain into `hfield_data`, one array for every world.
REFUSED = ("escape",)


def test_every_quadruped_task_of_the_suite_is_batched_or_refused(suite):
    assert {task for domain, task in suite.ALL_TASKS if domain == "quadruped"} == {
        *BATCHED,
        *REFUSED,
    }


@pytest.mark.parametrize("task", BATCHED)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "quadruped", task) == []


def test_escape_is_not_batched(suite):
    with pytest.raises(NotImplementedError, match="escape"):
        suite_batch.load("quadruped", "escape", 2)


def test_the_environment_refuses_escape_for_its_height_field(suite):
    env = suite.load("quadruped", "escape")
    generators = [np.random.RandomState(seed) for seed in (1, 2)]
    try:
        with pytest.raises(NotImplementedError, match="'hfield_data'"):
            SuiteBatchEnvironment(env, tasks.SuiteBatchTask, generators)
    finally:
        env.close()
