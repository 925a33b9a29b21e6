"""Swimmer's batched `Swimmer`: every world is dm_control's episode, bit for bit, for both
of the suite's generated models (6 and 15 links)."""

import types

import mujoco
import numpy as np
import pytest
from episodes import differences, needs_suite

from suite_batch import tasks

pytestmark = needs_suite

SWIMMER_TASKS = ("swimmer6", "swimmer15")
#: The MjData fields the task reads.
FIELDS = ("qpos", "sensordata", "xmat", "geom_xpos")


def test_the_batch_has_every_swimmer_task_of_the_suite(suite):
    assert set(SWIMMER_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "swimmer"}


@pytest.mark.parametrize("task", SWIMMER_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "swimmer", task) == []


@pytest.mark.parametrize("task", SWIMMER_TASKS)
def test_rewards_and_observations_are_dm_controls_on_many_states(suite, task):
    # Random head orientations and positions (the nose from inside the target to metres
    # off), read by the array code from stand-in views and by the CPU task row by row:
    # the target seen from the nose (a vector times a matrix) must match in every bit.
    env = suite.load("swimmer", task, task_kwargs={"random": 0})
    data, num_envs = env.physics.data, 1000
    rng = np.random.default_rng(0)
    rows = {name: rng.uniform(-1, 1, (num_envs, *getattr(data, name).shape)) for name in FIELDS}
    quaternions = rng.normal(size=(*rows["xmat"].shape[:2], 4))
    quaternions /= np.linalg.norm(quaternions, axis=-1, keepdims=True)
    for index in np.ndindex(*quaternions.shape[:2]):
        mujoco.mju_quat2Mat(rows["xmat"][index], quaternions[index])
    rows["geom_xpos"] *= rng.choice([0.03, 0.3, 3.0], (num_envs, 1, 1))
    stand_in = types.SimpleNamespace(num_envs=num_envs, data=types.SimpleNamespace(**rows))
    batch_task = tasks.for_task(env.task)(env.task, env.physics, stand_in)
    rewards, observations = batch_task.get_reward(), batch_task.get_observation()
    assert np.any(rewards == 1.0) and len(np.unique(rewards)) > 100
    for world in range(num_envs):
        for name in FIELDS:
            getattr(data, name)[...] = rows[name][world]
        assert rewards[world] == env.task.get_reward(env.physics)
        for key, value in env.task.get_observation(env.physics).items():
            assert np.array_equal(observations[key][world], value), key
    env.close()
