"""composer.rl.sb3_batch: SB3's VecEnv contract over a batch of worlds.

The reference is `composer.rl.sb3.Sb3VecEnv` over the threaded vector env of the same id,
seeds and actions (itself checked against SB3's `DummyVecEnv` in test_sb3.py): every
observation, reward, done, `TimeLimit.truncated` and terminal observation must be equal.
Skipped without Stable-Baselines3 (the extra `[sb3]`).
"""

import numpy as np
import pytest

pytest.importorskip(
    "stable_baselines3",
    reason="Stable-Baselines3 is not installed (pip install torch==2.13.0, the CPU build, "
    "then pip install -e '.[sb3]')",
)
pytest.importorskip("mujoco.batch", reason="the CPU batch needs MuJoCo >= 4 (mujoco.batch)")

from stable_baselines3 import PPO  # noqa: E402
from vec_env_checks import assert_observations_equal  # noqa: E402

import manipulation  # noqa: E402, F401  (registers the composer/<name>-v0 ids)
from composer.rl.sb3 import make_vec_env  # noqa: E402
from composer.rl.sb3_batch import Sb3BatchVecEnv  # noqa: E402

REACH = "composer/reach_site_features-v0"
EPISODE_STEPS = 5  # of 0.04 s: a time limit of 0.2 s
REACH_FEATURES = 45  # reach_site_features' flattened features (as in test_sb3.py)


def _batch(num_envs, **kwargs):
    return make_vec_env(
        REACH, num_envs, seed=3, backend="batch", time_limit=EPISODE_STEPS * 0.04, **kwargs
    )


def _threaded(num_envs, **kwargs):
    return make_vec_env(
        REACH, num_envs, seed=3, backend="threads", max_episode_steps=EPISODE_STEPS, **kwargs
    )


@pytest.mark.parametrize("flatten", [False, True])
def test_matches_the_threaded_sb3_vec_env_step_for_step(flatten):
    batch, threaded = (
        make(2, monitor=False, flatten_observations=flatten) for make in (_batch, _threaded)
    )
    assert isinstance(batch, Sb3BatchVecEnv)
    assert batch.observation_space == threaded.observation_space
    if flatten:
        assert batch.observation_space.shape == (REACH_FEATURES,)
    try:
        assert_observations_equal(batch.reset(), threaded.reset())
        rng = np.random.RandomState(0)
        ends = 0
        for _ in range(2 * EPISODE_STEPS + 2):
            actions = rng.uniform(-1, 1, (2, *batch.action_space.shape))
            got, expected = batch.step(actions), threaded.step(actions)
            assert_observations_equal(got[0], expected[0])
            np.testing.assert_array_equal(got[1], expected[1])
            assert got[1].dtype == np.float32
            np.testing.assert_array_equal(got[2], expected[2])
            for info, expected_info in zip(got[3], expected[3]):
                assert info["TimeLimit.truncated"] == expected_info["TimeLimit.truncated"]
                assert ("terminal_observation" in info) == ("terminal_observation" in expected_info)
                if "terminal_observation" in info:
                    ends += 1
                    assert_observations_equal(
                        info["terminal_observation"], expected_info["terminal_observation"]
                    )
        assert ends == 4  # both worlds, at steps 5 and 10
    finally:
        batch.close(), threaded.close()


def test_ppo_learns_on_the_batch_and_logs_every_finished_episode():
    venv = _batch(4, flatten_observations=True)
    try:
        model = PPO("MlpPolicy", venv, n_steps=16, batch_size=64, n_epochs=1, device="cpu")
        model.learn(total_timesteps=128)
        assert model.num_timesteps == 128
        # 32 steps per world: 6 whole 5-step episodes each.
        assert len(model.ep_info_buffer) == 24
        assert {episode["l"] for episode in model.ep_info_buffer} == {EPISODE_STEPS}
    finally:
        venv.close()


def test_a_batch_refuses_what_has_no_world_objects():
    venv = _batch(2, monitor=False)
    try:
        assert venv.env_is_wrapped(object) == [False, False]
        assert venv.get_attr("num_envs") == [2, 2]
        with pytest.raises(AttributeError):
            venv.get_attr("no_such_attribute")
        with pytest.raises(NotImplementedError, match="env_method\\('reset'\\): the worlds"):
            venv.env_method("reset")
    finally:
        venv.close()


def test_backend_batch_needs_a_registered_id():
    with pytest.raises(TypeError, match="env: backend 'batch' needs the registered id"):
        make_vec_env(lambda: None, 2, backend="batch")
