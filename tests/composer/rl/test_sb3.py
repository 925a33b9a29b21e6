"""composer.rl.sb3: SB3's VecEnv contract over the threaded (and Ray) vector envs.

Expected values come from outside the adapter: plain Gymnasium runs of the same
environments with the same seeds and actions, SB3's own `DummyVecEnv` over the same
factories, and counts that follow from the episode length. Skipped without
Stable-Baselines3 (the extra `[sb3]`).
"""

import functools

import gymnasium
import numpy as np
import pytest

pytest.importorskip(
    "stable_baselines3",
    reason="Stable-Baselines3 is not installed (pip install torch==2.13.0, the CPU build, "
    "then pip install -e '.[sb3]')",
)

from gymnasium.vector import AutoresetMode  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.env_checker import check_env  # noqa: E402
from stable_baselines3.common.evaluation import evaluate_policy  # noqa: E402
from stable_baselines3.common.monitor import Monitor  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor, VecNormalize  # noqa: E402
from vec_env_checks import assert_observations_equal  # noqa: E402

import composer  # noqa: E402
import manipulation  # noqa: E402, F401  (registers the composer/<name>-v0 ids)
import mjcf  # noqa: E402
from composer.gym import GymnasiumEnv, ThreadedVectorEnv  # noqa: E402
from composer.observation import observable  # noqa: E402
from composer.rl.sb3 import Sb3VecEnv, make_vec_env  # noqa: E402
from manipulation.tasks import registry  # noqa: E402

# Control steps of 0.04 s: a 0.2 s time limit ends every episode after 5 steps.
_EPISODE_STEPS = 5
# reach_site_features' features: target (3), arm joints' sin/cos (12), torques (6),
# velocities (6), finger positions (3) and velocities (3), pinch site position (3) and
# rotation matrix (9).
_REACH_FEATURES = 45


def _reach(seed=None, flatten=False, render_mode=None):
    """reach_site_features with 5-step episodes, as a Gymnasium env."""
    env = composer.Environment(
        registry.build_task("reach_site_features"),
        time_limit=_EPISODE_STEPS * 0.04,
        random_state=seed,
    )
    return GymnasiumEnv(
        env, flatten_observations=flatten, render_mode=render_mode, width=64, height=48
    )


class _Bead(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="bead")
        body = self._model.worldbody.add("body", name="bead")
        self.joint = body.add("joint", name="slide", type="slide", axis=[1, 0, 0])
        body.add("geom", type="sphere", size=[0.05], mass=0.1)
        self._model.actuator.add("motor", joint=self.joint, ctrlrange=[-1, 1])

    @property
    def mjcf_model(self):
        return self._model


class _EndsAfterThreeSteps(composer.Task):
    """A bead pushed along a rail from a random start; the task ends the episode (discount
    0) after 3 control steps; the reward is the bead's position."""

    def __init__(self):
        self._bead = _Bead()
        self._steps = 0
        position = observable.MJCFFeature("qpos", self._bead.joint)
        position.enabled = True
        self._observables = {"position": position}

    @property
    def root_entity(self):
        return self._bead

    @property
    def task_observables(self):
        return self._observables

    def initialize_episode(self, physics, random_state):
        physics.bind(self._bead.joint).qpos = random_state.uniform(-1, 1)
        self._steps = 0

    def after_step(self, physics, random_state):
        self._steps += 1

    def should_terminate_episode(self, physics):
        return self._steps >= 3

    def get_discount(self, physics):
        return 0.0 if self._steps >= 3 else 1.0

    def get_reward(self, physics):
        return float(physics.bind(self._bead.joint).qpos[0])


def _ending(seed=None):
    return GymnasiumEnv(composer.Environment(_EndsAfterThreeSteps(), random_state=seed))


def _actions(space, count, seed=0):
    space = gymnasium.spaces.Box(space.low, space.high, dtype=np.float64)
    space.seed(seed)
    return [space.sample() for _ in range(count)]


def _rows(observation, i):
    if isinstance(observation, dict):
        return {key: value[i] for key, value in observation.items()}
    return observation[i]


@pytest.fixture
def closing():
    """Returns `keep(venv)`, which closes it after the test (its worker threads too)."""
    kept = []
    yield lambda venv: kept.append(venv) or venv
    for venv in kept:
        venv.close()


def test_step_returns_what_sb3_expects_for_dict_observations(closing):
    venv = closing(make_vec_env(_reach, 3, seed=0, monitor=False))
    observations = venv.reset()
    space = _reach().observation_space
    assert observations.keys() == space.keys()
    for key, subspace in space.items():
        assert observations[key].shape == (3, *subspace.shape)
        assert observations[key].dtype == np.float64
    actions = np.stack(_actions(venv.action_space, 3))
    observations, rewards, dones, infos = venv.step(actions)
    assert observations["target_position"].shape == (3, 1, 3)
    assert rewards.shape == (3,) and rewards.dtype == np.float32
    assert dones.shape == (3,) and dones.dtype == np.bool_
    assert isinstance(infos, list) and len(infos) == 3
    assert [info["TimeLimit.truncated"] for info in infos] == [False] * 3


def test_flattened_observations_are_one_float_box(closing):
    venv = closing(make_vec_env(functools.partial(_reach, flatten=True), 2, monitor=False))
    assert venv.observation_space.shape == (_REACH_FEATURES,)
    assert venv.reset().shape == (2, _REACH_FEATURES)


def test_matches_sb3_dummy_vec_env_step_for_step(closing):
    # SB3's own DummyVecEnv is the reference for the VecEnv contract: same factories,
    # seeds and actions, through a time-limit end (env 0) and task ends (env 1).
    for factory in (_reach, _ending):
        reference = DummyVecEnv([factory] * 2)
        venv = closing(make_vec_env(factory, 2, seed=3, monitor=False))
        reference.seed(3)
        assert_observations_equal(venv.reset(), reference.reset())
        for action in _actions(venv.action_space, 12):
            actions = np.stack([action, -action])
            got = venv.step(actions)
            expected = reference.step(actions)
            assert_observations_equal(got[0], expected[0])
            np.testing.assert_array_equal(got[1], expected[1])
            np.testing.assert_array_equal(got[2], expected[2])
            for info, expected_info in zip(got[3], expected[3]):
                assert info.keys() == expected_info.keys()
                assert info["TimeLimit.truncated"] == expected_info["TimeLimit.truncated"]
                if "terminal_observation" in expected_info:
                    assert_observations_equal(
                        info["terminal_observation"], expected_info["terminal_observation"]
                    )
        reference.close()


def test_terminal_observation_is_the_episodes_last_and_the_next_episode_starts():
    actions = _actions(_reach().action_space, _EPISODE_STEPS)
    plain = _reach()
    plain.reset(seed=5)
    for action in actions:
        last, *_ = plain.step(action)
    first_of_next, _ = plain.reset()
    venv = make_vec_env(_reach, 1, seed=5, monitor=False)
    venv.reset()
    for action in actions:
        observations, _, dones, infos = venv.step(action[None])
    venv.close()
    assert dones.tolist() == [True]
    assert_observations_equal(infos[0]["terminal_observation"], last)
    assert_observations_equal(_rows(observations, 0), first_of_next)


def test_time_limit_end_is_truncated_and_a_task_end_is_not(closing):
    ends = {}
    for name, factory, length in (("time limit", _reach, 5), ("task", _ending, 3)):
        venv = closing(make_vec_env(factory, 1, seed=0, monitor=False))
        venv.reset()
        flags = []
        for action in _actions(venv.action_space, length):
            _, _, dones, infos = venv.step(action[None])
            flags.append((bool(dones[0]), infos[0]["TimeLimit.truncated"]))
        ends[name] = flags
    assert ends["time limit"] == [(False, False)] * 4 + [(True, True)]
    assert ends["task"] == [(False, False)] * 2 + [(True, False)]


def test_vec_monitor_episode_return_is_the_sum_of_the_rewards():
    actions = _actions(_reach().action_space, _EPISODE_STEPS)
    plain = _reach()
    plain.reset(seed=1)
    expected_return = sum(plain.step(action)[1] for action in actions)
    venv = make_vec_env(_reach, 1, seed=1)
    assert isinstance(venv, VecMonitor)
    venv.reset()
    for action in actions:
        _, _, _, infos = venv.step(action[None])
    venv.close()
    assert infos[0]["episode"]["l"] == _EPISODE_STEPS
    assert infos[0]["episode"]["r"] == pytest.approx(expected_return, rel=1e-6)


class _Succeeds(gymnasium.Wrapper):
    """Puts `is_success` in the info of an episode's last step (as tasks that know it do)."""

    def step(self, action):
        observation, reward, terminated, truncated, info = super().step(action)
        if terminated or truncated:
            info = {**info, "is_success": True}
        return observation, reward, terminated, truncated, info


def test_episode_end_infos_reach_sb3_as_the_environment_gave_them(closing):
    def factory():
        return gymnasium.wrappers.RecordEpisodeStatistics(_Succeeds(_reach()))

    venv = closing(make_vec_env(factory, 2, seed=0, monitor=False))
    venv.reset()
    for action in _actions(venv.action_space, _EPISODE_STEPS):
        _, _, dones, infos = venv.step(np.stack([action, action]))
        if not dones.all():
            assert all("is_success" not in info for info in infos)
    assert [bool(info["is_success"]) for info in infos] == [True, True]
    assert [int(info["episode"]["l"]) for info in infos] == [_EPISODE_STEPS] * 2
    assert [info["discount"] for info in infos] == [1.0, 1.0]


def test_seed_then_reset_seeds_sub_env_i_with_seed_plus_i(closing):
    venv = closing(make_vec_env(_reach, 2, monitor=False))
    assert venv.seed(7) == [7, 8]
    observations = venv.reset()
    for i, seed in enumerate((7, 8)):
        assert_observations_equal(_rows(observations, i), _reach().reset(seed=seed)[0])


def test_attributes_and_methods_reach_only_the_chosen_sub_envs(closing):
    venv = closing(make_vec_env(_reach, 3, monitor=False))
    venv.set_attr("note", "middle", indices=[1])
    assert venv.get_attr("note", indices=[1]) == ["middle"]
    with pytest.raises(AttributeError, match="note"):
        venv.get_attr("note", indices=[0])
    ((observation, info),) = venv.env_method("reset", seed=11, indices=2)
    assert_observations_equal(observation, _reach().reset(seed=11)[0])
    assert venv.get_attr("render_mode") == [None, None, None]


def test_env_is_wrapped_looks_through_each_sub_envs_wrappers(closing):
    venv = closing(make_vec_env(lambda: Monitor(_reach()), 2, monitor=False))
    assert venv.env_is_wrapped(Monitor) == [True, True]
    assert venv.env_is_wrapped(gymnasium.wrappers.TimeLimit, indices=[0]) == [False]


def test_render_tiles_the_sub_envs_frames(closing):
    venv = closing(make_vec_env(functools.partial(_reach, render_mode="rgb_array"), 2))
    venv.reset()
    # SB3 tiles 2 frames of 48x64 in 2 rows of 1.
    assert venv.render().shape == (96, 64, 3)


def test_sb3_check_env_accepts_a_registered_composer_env():
    env = gymnasium.make("composer/reach_site_features-v0")
    check_env(env, warn=False)
    env.close()


def test_vec_normalize_on_top_normalizes_each_observation_key(closing):
    venv = VecNormalize(closing(make_vec_env(_reach, 2, seed=0)), norm_reward=False)
    venv.reset()
    for action in _actions(venv.action_space, 20):
        observations, *_ = venv.step(np.stack([action, action]))
    assert observations.keys() == _reach().observation_space.keys()
    # Clipped at VecNormalize's default of 10 standard deviations.
    assert all(np.abs(value).max() <= 10 for value in observations.values())
    assert venv.obs_rms["target_position"].count > 20


def test_ppo_learns_256_steps_and_logs_every_finished_episode(closing):
    venv = closing(make_vec_env(_reach, 2, seed=0))
    model = PPO(
        "MultiInputPolicy",
        VecNormalize(venv),
        n_steps=64,
        batch_size=64,
        n_epochs=1,
        seed=0,
        device="cpu",
    )
    model.learn(total_timesteps=256)
    assert model.num_timesteps == 256
    # 128 steps per sub-environment: 25 whole 5-step episodes each.
    assert len(model.ep_info_buffer) == 50
    assert {episode["l"] for episode in model.ep_info_buffer} == {_EPISODE_STEPS}


def test_evaluate_policy_gives_the_returns_sb3_gives_on_its_own_vec_env(closing):
    venv = closing(make_vec_env(_reach, 2, seed=0))
    model = PPO("MultiInputPolicy", venv, n_steps=32, batch_size=32, seed=0, device="cpu")
    returns, lengths = evaluate_policy(model, venv, n_eval_episodes=4, return_episode_rewards=True)
    reference = VecMonitor(DummyVecEnv([_reach] * 2))
    reference.seed(0)
    expected_returns, expected_lengths = evaluate_policy(
        model, reference, n_eval_episodes=4, return_episode_rewards=True
    )
    reference.close()
    assert lengths == expected_lengths == [_EPISODE_STEPS] * 4
    np.testing.assert_allclose(returns, expected_returns, rtol=1e-6)


def test_refuses_a_vector_env_that_autoresets_on_the_next_step():
    envs = ThreadedVectorEnv([_reach], autoreset_mode=AutoresetMode.NEXT_STEP)
    with pytest.raises(ValueError, match=r"vector_env: expected autoreset_mode SAME_STEP"):
        Sb3VecEnv(envs)
    envs.close()


def test_refuses_a_vector_env_of_another_kind():
    envs = gymnasium.vector.SyncVectorEnv([_reach], autoreset_mode=AutoresetMode.SAME_STEP)
    with pytest.raises(TypeError, match=r"vector_env: expected a composer.gym"):
        Sb3VecEnv(envs)
    envs.close()


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (
            dict(num_envs=2, backend="processes"),
            r"backend: expected one of \('threads', 'ray', 'batch'\)",
        ),
        (dict(num_envs=0), r"num_envs: expected an integer >= 1, got 0"),
        (dict(num_envs=2, autoreset_mode="NextStep"), r"autoreset_mode: make_vec_env always"),
    ],
)
def test_make_vec_env_names_the_bad_argument(arguments, message):
    with pytest.raises(ValueError, match=message):
        make_vec_env(_reach, **arguments)


def test_make_vec_env_builds_a_registered_id_through_its_vector_entry_point(closing):
    venv = closing(
        make_vec_env("composer/reach_site_features-v0", 2, seed=0, flatten_observations=True)
    )
    assert isinstance(venv.unwrapped.vector_env, ThreadedVectorEnv)
    assert venv.reset().shape == (2, _REACH_FEATURES)


def test_make_vec_env_refuses_an_id_without_a_vector_entry_point():
    with pytest.raises(ValueError, match=r"env: 'Pendulum-v1' has no vector entry point"):
        make_vec_env("Pendulum-v1", 2)


def test_make_vec_env_refuses_an_id_whose_vector_env_is_not_composers():
    with pytest.raises(TypeError, match=r"env: the vector entry point of 'CartPole-v1' \(gym"):
        make_vec_env("CartPole-v1", 2)


@pytest.mark.ray
def test_over_ray_actors_matches_sb3_dummy_vec_env(closing):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install -e '.[ray]')")
    ray.init(address="local", num_cpus=2, include_dashboard=False)
    # The actors import manipulation through the id (pickled: the function, not the env).
    factory = functools.partial(
        gymnasium.make,
        "manipulation:composer/reach_site_features-v0",
        max_episode_steps=_EPISODE_STEPS,
        flatten_observations=True,
    )
    try:
        venv = closing(make_vec_env(factory, 2, seed=4, backend="ray", envs_per_actor=1))
        reference = DummyVecEnv([factory] * 2)
        reference.seed(4)
        np.testing.assert_array_equal(venv.reset(), reference.reset())
        ends = []
        for step, action in enumerate(_actions(venv.action_space, 7), start=1):
            actions = np.stack([action, -action])
            observations, rewards, dones, infos = venv.step(actions)
            ends += [step] * int(dones.sum())
            expected = reference.step(actions)
            np.testing.assert_array_equal(observations, expected[0])
            np.testing.assert_array_equal(rewards, expected[1])
            np.testing.assert_array_equal(dones, expected[2])
            for info, expected_info in zip(infos, expected[3]):
                assert info["TimeLimit.truncated"] == expected_info["TimeLimit.truncated"]
                if "terminal_observation" in expected_info:
                    np.testing.assert_array_equal(
                        info["terminal_observation"], expected_info["terminal_observation"]
                    )
        assert ends == [_EPISODE_STEPS, _EPISODE_STEPS]
        reference.close()
        venv.close()
    finally:
        ray.shutdown()
