"""Every environment of the suite has the suite's observations and runs an episode of random
actions to its time limit."""

import math

import dm_env
import numpy as np
import pytest
from manipulation_specs import EXPECTED_SPECS, FEATURES_NAMES, VISION_NAMES

import composer
import manipulation
from manipulation.tasks import registry

# Vision episodes are cut to a few control steps: with software rendering (the headless
# test machines have no GPU) one 84x84 frame takes tens of milliseconds, and the physics
# they step is exactly that of the features variant, which runs to the full 10 s.
_VISION_TIME_LIMIT = 0.12


def _check_observation(observation, spec):
    assert set(observation) == set(spec)
    for key, value in observation.items():
        spec[key].validate(value)


def _run_episode(env, seed=0):
    """Runs random actions until the episode ends; returns (timesteps after reset, rewards)."""
    action_spec = env.action_spec()
    observation_spec = env.observation_spec()
    rng = np.random.RandomState(seed)
    timestep = env.reset()
    _check_observation(timestep.observation, observation_spec)
    steps, rewards = 0, []
    while not timestep.last():
        timestep = env.step(rng.uniform(action_spec.minimum, action_spec.maximum))
        _check_observation(timestep.observation, observation_spec)
        steps += 1
        rewards.append(timestep.reward)
    return steps, rewards


def _spec_summary(env):
    return {key: (tuple(spec.shape), spec.dtype) for key, spec in env.observation_spec().items()}


@pytest.mark.parametrize("name", FEATURES_NAMES)
def test_features_environment_runs_a_full_random_episode_with_rewards_in_unit_interval(name):
    env = manipulation.load(name, seed=0)
    assert _spec_summary(env) == EXPECTED_SPECS[name]
    steps, rewards = _run_episode(env)
    assert steps == 250
    assert all(math.isfinite(r) and 0.0 <= r <= 1.0 for r in rewards)


@pytest.mark.parametrize("name", VISION_NAMES)
def test_vision_environment_runs_a_short_random_episode_with_rewards_in_unit_interval(name):
    env = composer.Environment(
        registry.build_task(name), time_limit=_VISION_TIME_LIMIT, random_state=0
    )
    assert _spec_summary(env) == EXPECTED_SPECS[name]
    steps, rewards = _run_episode(env)
    assert steps == 3
    assert all(math.isfinite(r) and 0.0 <= r <= 1.0 for r in rewards)


def test_vision_observation_is_a_non_blank_rgb_image():
    env = composer.Environment(registry.build_task("lift_brick_vision"), random_state=0)
    image = env.reset().observation["front_close"][0]
    # The table, the arm and the sky differ in colour: the image is not one flat colour.
    assert image.reshape(-1, 3).std(axis=0).max() > 10


def test_episode_ends_with_a_last_step_of_discount_one():
    env = composer.Environment(registry.build_task("reach_site_features"), time_limit=0.08)
    env.reset()
    first = env.step(np.zeros(9))
    last = env.step(np.zeros(9))
    assert first.step_type == dm_env.StepType.MID
    assert last.step_type == dm_env.StepType.LAST
    assert last.discount == 1.0
