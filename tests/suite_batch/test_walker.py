"""Walker's batched `PlanarWalker`: every world is dm_control's episode, bit for bit."""

import sys
import types

import numpy as np
import pytest
from episodes import differences, needs_suite

from suite_batch import tasks

pytestmark = needs_suite

WALKER_TASKS = ("stand", "walk", "run")
#: The MjData fields the task reads.
FIELDS = ("xpos", "xmat", "qvel", "sensordata")


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
        for key, value in env.task.get_observation(env.physics).items():
            assert np.array_equal(observations[key][world], value), (world, key)


def test_the_batch_has_every_walker_task_of_the_suite(suite):
    assert set(WALKER_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "walker"}


@pytest.mark.parametrize("task", WALKER_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "walker", task) == []


@pytest.mark.parametrize("task", WALKER_TASKS)
def test_rewards_and_observations_are_dm_controls_on_many_states(suite, task):
    # Heights in and below the standing band, speeds below, on and above the ramp.
    env = suite.load("walker", task, task_kwargs={"random": 0})
    rng = np.random.default_rng(0)
    data = env.physics.data
    assert_batch_is_cpu(
        env, {name: rng.uniform(-2, 10, (512, *getattr(data, name).shape)) for name in FIELDS}
    )
    env.close()


def test_the_standing_reward_of_a_height_is_dm_controls_on_one_number(suite):
    # The task passes the torso's height as one number, which dm_control's tolerance squares
    # differently from an array in the last bit for a few heights: those are checked.
    from dm_control.utils import rewards as dm_rewards

    env = suite.load("walker", "stand", task_kwargs={"random": 0})
    height = sys.modules[type(env.task).__module__]._STAND_HEIGHT
    bounds, margin = (height, float("inf")), height / 2
    candidates = np.random.default_rng(0).uniform(0, height, 20_000)
    heights = [
        h
        for h in candidates
        if dm_rewards.tolerance(h, bounds, margin)
        != dm_rewards.tolerance(np.array([h]), bounds, margin)[0]
    ]
    assert heights
    data = env.physics.data
    rows = {name: np.zeros((len(heights), *getattr(data, name).shape)) for name in FIELDS}
    torso = env.physics.model.name2id("torso", "body")
    rows["xpos"][:, torso, 2] = heights
    assert_batch_is_cpu(env, rows)
    env.close()
