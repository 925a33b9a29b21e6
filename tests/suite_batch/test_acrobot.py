"""The batched acrobot tasks: world i is dm_control's
`suite.load("acrobot", task, task_kwargs={"random": seed})`."""

import numpy as np
import pytest
from episodes import SEEDS, differences, needs_suite

import suite_batch

pytestmark = needs_suite

ACROBOT_TASKS = ("swingup", "swingup_sparse")


def test_the_batch_has_every_acrobot_task_of_the_suite(suite):
    assert set(ACROBOT_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "acrobot"}


@pytest.mark.parametrize("task", ACROBOT_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "acrobot", task) == []


@pytest.mark.parametrize("task", ACROBOT_TASKS)
def test_the_reward_near_the_upright_target_is_dm_controls(suite, task):
    # Random episodes seldom bring the tip to the target: (shoulder, elbow) angles around
    # upright, inside and outside the target.
    angles = np.random.RandomState(0).normal(0, 0.15, (40, len(SEEDS), 2))
    batch = suite_batch.load("acrobot", task, len(SEEDS), random_states=SEEDS, threads=1)
    cpu = suite.load("acrobot", task, task_kwargs={"random": SEEDS[0]})
    batch.reset()
    cpu.reset()
    expected, got = [], []
    for worlds in angles:
        batch.physics.data.qpos[...] = worlds
        batch.physics.forward()
        got += list(batch._batch_task.get_reward())
        for qpos in worlds:
            cpu.physics.data.qpos[:] = qpos
            cpu.physics.forward()
            expected.append(cpu.task.get_reward(cpu.physics))
    batch.close()
    cpu.close()
    assert 1.0 in expected and min(expected) < 1.0
    assert got == expected
