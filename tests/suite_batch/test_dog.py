"""The batched dog tasks: every world is dm_control's dog episode, bit for bit."""

from types import SimpleNamespace

import mujoco
import numpy as np
import pytest
from episodes import differences, needs_suite

from suite_batch.domains import dog

pytestmark = needs_suite

DOG_TASKS = ("stand", "walk", "trot", "run", "fetch")

#: The data fields the dog tasks read, randomised in `test_observations_and_rewards_...`.
_READ_FIELDS = (
    "qpos",
    "qvel",
    "act",
    "xpos",
    "xmat",
    "sensordata",
    "site_xpos",
    "site_xmat",
    "geom_xpos",
    "cvel",
    "subtree_com",
)
_STATES = 400


def test_the_batch_has_every_dog_task_of_the_suite(suite):
    assert set(DOG_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "dog"}


@pytest.mark.parametrize("task", DOG_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "dog", task) == []


def _random_state(data, model, random: np.random.RandomState) -> None:
    """Writes random values into the fields the dog tasks read: heights, upright cosines
    and paw touches on both sides of the reward bounds, the ball now and then next to the
    target (fetch)."""
    for name in _READ_FIELDS:
        field = getattr(data, name)
        field[...] = random.normal(scale=random.choice([1e-3, 1.0, 10.0]), size=field.shape)
    data.xpos[:, 2] = random.uniform(0, 0.8, model.nbody)
    data.xmat[:, 8] = random.uniform(-1, 1, model.nbody)
    for paw in ("palm_L", "palm_R", "sole_L", "sole_R"):
        data.sensordata[model.sensor(paw).adr[0]] = random.uniform(0, 60)
    has_ball = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ball") >= 0
    if has_ball and random.uniform() < 0.3:
        target = data.geom("target").xpos
        data.geom("ball").xpos[...] = target + random.uniform(-0.2, 0.2, 3)


@pytest.mark.parametrize("task", ["stand", "walk", "fetch"])
def test_observations_and_rewards_are_dm_controls_on_many_states(suite, task):
    # Every body-frame rotation, norm and reward factor against dm_control's own on random
    # states of the fields they read, the reward factors observed too.
    env = suite.load("dog", task, task_kwargs={"random": 0})
    env.reset()
    cpu_task, host = env.task, env.physics
    cpu_task._observe_reward_factors = True
    model, data = host.model.ptr, host.data.ptr
    random = np.random.RandomState(1)
    fields = {name: [] for name in _READ_FIELDS}
    observations, rewards = [], []
    for _ in range(_STATES):
        _random_state(data, model, random)
        for name in _READ_FIELDS:
            fields[name].append(getattr(data, name).copy())
        observations.append(cpu_task.get_observation(host))
        rewards.append(cpu_task.get_reward(host))
    physics = SimpleNamespace(
        num_envs=_STATES,
        data=SimpleNamespace(**{name: np.stack(rows) for name, rows in fields.items()}),
    )
    batch_type = {"stand": dog.BatchStand, "walk": dog.BatchMove, "fetch": dog.BatchFetch}[task]
    batch_task = batch_type(cpu_task, host, physics)
    observation = batch_task.get_observation()
    assert list(observation) == list(observations[0])
    for key in observation:
        expected = np.stack([np.asarray(row[key], float) for row in observations])
        mismatched = np.flatnonzero((observation[key] != expected).reshape(_STATES, -1).any(1))
        assert mismatched.size == 0, f"{key}: states {mismatched[:10]}"
    np.testing.assert_array_equal(batch_task.get_reward(), np.array(rewards))
    env.close()
