"""Ball-in-Cup's batched `BallInCup`: every world is dm_control's episode, bit for bit."""

import types

import numpy as np
from episodes import differences, needs_suite

from suite_batch import tasks

pytestmark = needs_suite

BALL_IN_CUP_TASKS = ("catch",)


def test_the_batch_has_every_ball_in_cup_task_of_the_suite(suite):
    assert set(BALL_IN_CUP_TASKS) == {
        task for domain, task in suite.ALL_TASKS if domain == "ball_in_cup"
    }


def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite):
    assert differences(suite, "ball_in_cup", "catch") == []


def test_the_reward_is_dm_controls_with_the_ball_in_and_about_the_cup(suite):
    # Random episodes rarely catch the ball: stand-in views put it in, at and beyond the
    # edges of the target box, read by the array code and by the CPU task row by row.
    env = suite.load("ball_in_cup", "catch", task_kwargs={"random": 0})
    data, num_envs = env.physics.data, 2000
    rng = np.random.default_rng(0)
    rows = {
        name: rng.uniform(-1, 1, (num_envs, *getattr(data, name).shape))
        for name in ("qpos", "qvel", "site_xpos", "xpos")
    }
    target = env.physics.model.name2id("target", "site")
    ball = env.physics.model.name2id("ball", "body")
    rows["xpos"][:, ball] = rows["site_xpos"][:, target] + rng.uniform(-0.04, 0.04, (num_envs, 3))
    stand_in = types.SimpleNamespace(num_envs=num_envs, data=types.SimpleNamespace(**rows))
    batch_task = tasks.for_task(env.task)(env.task, env.physics, stand_in)
    rewards, observations = batch_task.get_reward(), batch_task.get_observation()
    expected = []
    for world in range(num_envs):
        for name, value in rows.items():
            getattr(data, name)[...] = value[world]
        expected.append(env.task.get_reward(env.physics))
        for key, value in env.task.get_observation(env.physics).items():
            assert np.array_equal(observations[key][world], value), key
    assert 0.0 < np.mean(expected) < 1.0  # both in and out of the cup
    assert np.array_equal(rewards, expected)
    env.close()
