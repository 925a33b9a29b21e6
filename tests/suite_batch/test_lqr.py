"""LQR batched: each world's model is drawn from its own seed, as `suite.load`'s."""

import numpy as np
import pytest
from episodes import differences, needs_suite

import suite_batch

pytestmark = needs_suite

TASKS = ("lqr_2_1", "lqr_6_2")


def test_the_batch_has_every_lqr_task_of_the_suite(suite):
    assert set(TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "lqr"}


@pytest.mark.parametrize("task", TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "lqr", task) == []


def test_each_world_has_the_stiffnesses_of_its_own_seed(suite):
    seeds = (3, 11)
    batch = suite_batch.load("lqr", "lqr_6_2", len(seeds), random_states=seeds)
    batch.reset()
    for world, seed in enumerate(seeds):
        cpu = suite.load("lqr", "lqr_6_2", task_kwargs={"random": seed})
        expected = cpu.physics.model.jnt_stiffness
        assert np.array_equal(batch.physics.model.jnt_stiffness[world], expected)
    stiffness = batch.physics.model.jnt_stiffness
    assert not np.array_equal(stiffness[0], stiffness[1])
    batch.close()


def test_a_state_near_zero_ends_the_episode_as_dm_controls(suite):
    batch = suite_batch.load("lqr", "lqr_2_1", 2, random_states=(3, 11))
    batch.reset()
    cpu = suite.load("lqr", "lqr_2_1", task_kwargs={"random": 3})
    cpu.reset()
    found = []
    for scale in (1e-8, 1e-3):  # a state norm below the tolerance (1e-6), then above
        cpu.physics.data.qpos[:] = scale
        cpu.physics.data.qvel[:] = 0.0
        batch.physics.data.qpos[0] = scale
        batch.physics.data.qvel[0] = 0.0
        got = batch._batch_task.get_termination()[0]
        found.append((cpu.task.get_termination(cpu.physics), None if np.isnan(got) else got))
    assert found == [(0.0, 0.0), (None, None)]
    batch.close()
