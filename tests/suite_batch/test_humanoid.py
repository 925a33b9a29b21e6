"""Humanoid's batched `Humanoid`: every world is dm_control's episode, bit for bit."""

import sys
import types

import numpy as np
import pytest
from episodes import differences, needs_suite

from suite_batch import tasks

pytestmark = needs_suite

HUMANOID_TASKS = ("stand", "walk", "run", "run_pure_state")
#: The MjData fields the task reads.
FIELDS = ("qpos", "qvel", "ctrl", "xpos", "xmat", "sensordata")


def assert_batch_is_cpu(env, rows: dict[str, np.ndarray]) -> None:
    """Asserts that the array code of `env`'s task, reading `rows` (field -> (worlds, ...))
    from stand-in views, gives the CPU task's reward and observation on each row."""
    num_envs = len(next(iter(rows.values())))
    stand_in = types.SimpleNamespace(num_envs=num_envs, data=types.SimpleNamespace(**rows))
    batch_task = tasks.for_task(env.task)(env.task, env.physics, stand_in)
    rewards, observations = batch_task.get_reward(), batch_task.get_observation()
    for world in range(num_envs):
        for name, value in rows.items():
            getattr(env.physics.data, name)[...] = value[world]
        assert rewards[world] == env.task.get_reward(env.physics), world
        observation = env.task.get_observation(env.physics)
        assert list(observations) == list(observation)
        for key, value in observation.items():
            assert np.array_equal(observations[key][world], value), (world, key)


def random_rows(env, num_envs: int) -> dict[str, np.ndarray]:
    """Every field the task reads, random: head heights in and below the standing band,
    uprightness from upside down to up, controls up to and past the limits, horizontal
    centre-of-mass speeds from still to past the run speed, limbs near and far."""
    rng = np.random.default_rng(0)
    data = env.physics.data
    rows = {name: rng.uniform(-1, 1, (num_envs, *getattr(data, name).shape)) for name in FIELDS}
    rows["xpos"] = rng.uniform(-0.5, 2, rows["xpos"].shape)
    rows["xpos"] *= rng.choice([0.1, 1.0, 30.0], (num_envs, 1, 1))
    rows["ctrl"] *= 1.2
    rows["sensordata"] *= rng.choice([0.3, 3.0, 15.0], (num_envs, 1))
    return rows


def test_the_batch_has_every_humanoid_task_of_the_suite(suite):
    assert set(HUMANOID_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "humanoid"}


@pytest.mark.parametrize("task", HUMANOID_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "humanoid", task) == []


@pytest.mark.parametrize("task", HUMANOID_TASKS)
def test_rewards_and_observations_are_dm_controls_on_many_states(suite, task):
    # The extremities are vectors times the torso's matrix (np.dot, BLAS) on the CPU: a sum
    # of products differs from it in the last bit on most of these rows.
    env = suite.load("humanoid", task, task_kwargs={"random": 0})
    assert_batch_is_cpu(env, random_rows(env, 512))
    env.close()


def test_the_standing_reward_of_a_head_height_is_dm_controls_on_one_number(suite):
    # The task passes the head's height as one number, which dm_control's tolerance squares
    # differently from an array in the last bit for a few heights: those are checked.
    from dm_control.utils import rewards as dm_rewards

    env = suite.load("humanoid", "stand", task_kwargs={"random": 0})
    height = sys.modules[type(env.task).__module__]._STAND_HEIGHT
    bounds, margin = (height, float("inf")), height / 4
    candidates = np.random.default_rng(0).uniform(0, height, 20_000)
    heights = [
        h
        for h in candidates
        if dm_rewards.tolerance(h, bounds, margin)
        != dm_rewards.tolerance(np.array([h]), bounds, margin)[0]
    ]
    assert heights
    rows = random_rows(env, len(heights))
    # Upright and still, so that the height decides the reward.
    rows["xmat"][:] = np.eye(3).ravel()
    rows["sensordata"][:] = 0
    head = env.physics.model.name2id("head", "body")
    rows["xpos"][:, head, 2] = heights
    assert_batch_is_cpu(env, rows)
    env.close()
