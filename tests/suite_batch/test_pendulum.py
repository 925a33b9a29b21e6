"""The batched pendulum task: world i is dm_control's
`suite.load("pendulum", "swingup", task_kwargs={"random": seed})`."""

import numpy as np
from episodes import SEEDS, differences, needs_suite

import suite_batch

pytestmark = needs_suite

PENDULUM_TASKS = ("swingup",)


def test_the_batch_has_every_pendulum_task_of_the_suite(suite):
    assert set(PENDULUM_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "pendulum"}


def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite):
    assert differences(suite, "pendulum", "swingup") == []


def test_the_reward_is_one_within_the_angle_bound_of_upright_as_dm_control(suite):
    # Random episodes seldom bring the pole up: angles on both sides of the bound (8 deg).
    angles = np.linspace(-0.3, 0.3, 61)
    batch = suite_batch.load("pendulum", "swingup", len(SEEDS), random_states=SEEDS, threads=1)
    cpu = suite.load("pendulum", "swingup", task_kwargs={"random": SEEDS[0]})
    batch.reset()
    cpu.reset()
    expected, got = [], []
    for angle in angles:
        batch.physics.data.qpos[:] = angle
        batch.physics.forward()
        got.append(list(batch._batch_task.get_reward()))
        cpu.physics.data.qpos[:] = angle
        cpu.physics.forward()
        expected.append([cpu.task.get_reward(cpu.physics)] * len(SEEDS))
    batch.close()
    cpu.close()
    assert {0.0, 1.0} <= set(np.ravel(expected))
    assert got == expected
