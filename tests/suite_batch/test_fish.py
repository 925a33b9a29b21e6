"""Fish's batched `Upright` and `Swim`: every world is dm_control's episode, bit for bit."""

import types

import mujoco
import numpy as np
import pytest
from episodes import differences, needs_suite

from suite_batch import tasks

pytestmark = needs_suite

FISH_TASKS = ("upright", "swim")
#: The MjData fields the tasks read.
FIELDS = ("qpos", "qvel", "xmat", "geom_xpos", "geom_xmat")


def _rotations(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    """Row-major rotation matrices (*shape, 9) of uniformly random orientations."""
    quaternions = rng.normal(size=(*shape, 4))
    quaternions /= np.linalg.norm(quaternions, axis=-1, keepdims=True)
    matrices = np.empty((*shape, 9))
    for index in np.ndindex(*shape):
        mujoco.mju_quat2Mat(matrices[index], quaternions[index])
    return matrices


def test_the_batch_has_every_fish_task_of_the_suite(suite):
    assert set(FISH_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "fish"}


@pytest.mark.parametrize("task", FISH_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "fish", task) == []


@pytest.mark.parametrize("task", FISH_TASKS)
def test_rewards_and_observations_are_dm_controls_on_many_states(suite, task):
    # Random orientations and positions (the target from beside the mouth to far off),
    # read by the array code from stand-in views and by the CPU task row by row: the
    # target seen from the mouth (a vector times a matrix) must match in every bit.
    env = suite.load("fish", task, task_kwargs={"random": 0})
    data, num_envs = env.physics.data, 1000
    rng = np.random.default_rng(0)
    rows = {name: rng.uniform(-1, 1, (num_envs, *getattr(data, name).shape)) for name in FIELDS}
    rows["xmat"] = _rotations(rng, rows["xmat"].shape[:2])
    rows["geom_xmat"] = _rotations(rng, rows["geom_xmat"].shape[:2])
    rows["geom_xpos"] *= rng.choice([1e-3, 0.1, 1.0], (num_envs, 1, 1))
    stand_in = types.SimpleNamespace(num_envs=num_envs, data=types.SimpleNamespace(**rows))
    batch_task = tasks.for_task(env.task)(env.task, env.physics, stand_in)
    rewards, observations = batch_task.get_reward(), batch_task.get_observation()
    assert len(np.unique(rewards)) > 100
    for world in range(num_envs):
        for name in FIELDS:
            getattr(data, name)[...] = rows[name][world]
        assert rewards[world] == env.task.get_reward(env.physics)
        for key, value in env.task.get_observation(env.physics).items():
            assert np.array_equal(observations[key][world], value), key
    env.close()
