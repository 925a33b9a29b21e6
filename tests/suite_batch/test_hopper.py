"""Hopper's batched `Hopper`: every world is dm_control's episode, bit for bit."""

import types

import numpy as np
import pytest
from episodes import differences, needs_suite

from suite_batch import tasks

pytestmark = needs_suite

HOPPER_TASKS = ("stand", "hop")
#: The MjData fields the task reads.
FIELDS = ("qpos", "qvel", "xipos", "sensordata", "ctrl")


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


def test_the_batch_has_every_hopper_task_of_the_suite(suite):
    assert set(HOPPER_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "hopper"}


@pytest.mark.parametrize("task", HOPPER_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "hopper", task) == []


@pytest.mark.parametrize("task", HOPPER_TASKS)
def test_rewards_and_observations_are_dm_controls_on_many_states(suite, task):
    # Heights in and out of the standing band, speeds about the ramp, touch forces of
    # several magnitudes, controls in and out of range.
    env = suite.load("hopper", task, task_kwargs={"random": 0})
    rng = np.random.default_rng(0)
    data = env.physics.data
    rows = {name: rng.uniform(-1, 4, (512, *getattr(data, name).shape)) for name in FIELDS}
    sensors = rows["sensordata"].shape
    rows["sensordata"] = rng.uniform(0, 1, sensors) * rng.choice([1e-3, 1.0, 100.0], sensors)
    rows["ctrl"] = rng.uniform(-1.5, 1.5, rows["ctrl"].shape)
    assert_batch_is_cpu(env, rows)
    env.close()


def test_the_small_control_reward_is_dm_controls_on_an_array(suite):
    # The task passes the controls as an array, which dm_control's tolerance squares
    # differently from one number in the last bit for a few values: those are checked.
    from dm_control.utils import rewards as dm_rewards

    env = suite.load("hopper", "stand", task_kwargs={"random": 0})

    def small_control(control):
        return dm_rewards.tolerance(control, margin=1, value_at_margin=0, sigmoid="quadratic")

    candidates = np.random.default_rng(0).uniform(-1, 1, 20_000)
    controls = [c for c in candidates if small_control(c) != small_control(np.array([c]))[0]]
    assert controls
    data = env.physics.data
    rows = {name: np.zeros((len(controls), *getattr(data, name).shape)) for name in FIELDS}
    torso, foot = (env.physics.model.name2id(name, "body") for name in ("torso", "foot"))
    rows["xipos"][:, torso, 2] = 1.0  # standing, so that the reward is the control's
    rows["xipos"][:, foot, 2] = 0.0
    rows["ctrl"][:] = np.array(controls)[:, None]
    assert_batch_is_cpu(env, rows)
    env.close()
