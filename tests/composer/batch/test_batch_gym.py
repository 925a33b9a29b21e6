"""The batched tasks through gymnasium.make_vec(..., backend='warp') as a VectorEnv."""

import gymnasium
import numpy as np
import pytest

import manipulation  # noqa: F401  (registers the composer/ ids with Gymnasium)
from manipulation import batch as manipulation_batch

pytestmark = pytest.mark.warp

NUM_ENVS = 2


@pytest.mark.parametrize("name", manipulation_batch.BATCHED)
def test_make_vec_with_backend_warp_steps_every_world(name):
    env = gymnasium.make_vec(
        f"composer/{name}-v0",
        num_envs=NUM_ENVS,
        vectorization_mode="vector_entry_point",
        backend="warp",
        device="warp-cpu",
    )
    assert isinstance(env, gymnasium.vector.VectorEnv)
    observations, _ = env.reset(seed=3)
    assert observations in env.observation_space
    actions = env.action_space.sample()
    observations, rewards, terminated, truncated, infos = env.step(actions)
    assert observations in env.observation_space
    assert rewards.shape == terminated.shape == truncated.shape == (NUM_ENVS,)
    assert not terminated.any() and not truncated.any()
    np.testing.assert_array_equal(infos["discount"], np.ones(NUM_ENVS))


def test_reset_with_the_same_seed_gives_the_same_first_observations():
    env = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
        backend="warp",
    )
    first, _ = env.reset(seed=11)
    first = {key: value.copy() for key, value in first.items()}
    env.step(env.action_space.sample())
    again, _ = env.reset(seed=11)
    for key, value in first.items():
        np.testing.assert_array_equal(again[key], value, err_msg=key)
    assert not np.array_equal(first["target_position"][0], first["target_position"][1])


def test_time_limit_truncates_every_world_and_the_next_step_resets_it():
    env = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
        backend="warp",
        time_limit=0.08,
    )
    env.reset(seed=0)
    zeros = np.zeros(env.action_space.shape)
    _, _, terminated, truncated, _ = env.step(zeros)
    assert not truncated.any()
    _, _, terminated, truncated, _ = env.step(zeros)
    assert truncated.all() and not terminated.any()
    _, rewards, terminated, truncated, _ = env.step(zeros)
    assert not truncated.any() and not terminated.any()
    np.testing.assert_array_equal(rewards, 0.0)


def test_warp_backend_refuses_a_thread_option():
    with pytest.raises(ValueError, match="num_threads: not an option of backend='warp'"):
        gymnasium.make_vec(
            "composer/reach_site_features-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            backend="warp",
            num_threads=2,
        )
