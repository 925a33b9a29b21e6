"""The batched tasks through gymnasium.make_vec(..., backend='batch') as a VectorEnv."""

import gymnasium
import numpy as np
import pytest

import manipulation  # noqa: F401  (registers the composer/ ids with Gymnasium)
from manipulation import batch as manipulation_batch

pytestmark = pytest.mark.warp

NUM_ENVS = 2


@pytest.mark.parametrize("name", manipulation_batch.BATCHED)
def test_make_vec_with_backend_batch_steps_every_world_on_warp(name):
    env = gymnasium.make_vec(
        f"composer/{name}-v0",
        num_envs=NUM_ENVS,
        vectorization_mode="vector_entry_point",
        backend="batch",
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
        backend="batch",
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
        backend="batch",
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


def test_batch_backend_refuses_a_thread_option():
    with pytest.raises(ValueError, match="num_threads: not an option of backend='batch'"):
        gymnasium.make_vec(
            "composer/reach_site_features-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            backend="batch",
            num_threads=2,
        )


def test_the_old_backend_and_class_names_still_work():
    from composer.batch.gym import BatchVectorEnv, WarpVectorEnv

    assert WarpVectorEnv is BatchVectorEnv
    env = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
        backend="warp",
    )
    assert type(env) is BatchVectorEnv
    env.close()


@pytest.mark.parametrize("seed", [[1], [1, None], "1", [1.0, 2.0]])
def test_reset_refuses_a_seed_that_is_not_one_int_per_world(seed):
    env = gymnasium.make_vec(
        "composer/reach_site_features-v0", num_envs=2, vectorization_mode="vector_entry_point"
    )
    with pytest.raises(ValueError, match=r"seed: expected None, an int or 2 ints \(one per world"):
        env.reset(seed=seed)
    env.close()
