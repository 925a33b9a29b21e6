"""GymnasiumEnv runs a dm_env environment through Gymnasium's Env API."""

import warnings

import dm_env
import gymnasium
import numpy as np
import pytest
from dm_env import specs
from gym_scene import SliderTask, slider_environment
from gymnasium.utils.env_checker import check_env

import composer
import manipulation
from composer.gym import GymnasiumEnv


def test_action_space_has_the_action_specs_bounds():
    env = GymnasiumEnv(slider_environment())
    assert env.action_space == gymnasium.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float64)


def test_observation_space_is_a_dict_of_the_observables():
    env = GymnasiumEnv(slider_environment())
    assert list(env.observation_space.keys()) == ["position", "velocity"]
    assert env.observation_space["position"].shape == (1, 1)
    observation, info = env.reset(seed=0)
    assert observation in env.observation_space
    assert info == {}


def test_manipulation_observation_space_flattens_to_one_box_in_spec_order():
    dm = manipulation.load("lift_brick_features", seed=0)
    env = GymnasiumEnv(dm, flatten_observations=True)
    # 6x2 + 6 + 6 joint values, 3 + 3 hand, 3 + 9 pinch site, 3 + 3 + 4 + 3 brick.
    assert env.observation_space.shape == (55,)
    flat, _ = env.reset(seed=3)
    nested, _ = GymnasiumEnv(
        manipulation.load("lift_brick_features"), flatten_observations=False
    ).reset(seed=3)
    np.testing.assert_array_equal(flat[:12], nested["jaco_arm/joints_pos"].ravel())
    np.testing.assert_array_equal(flat[-3:], nested["duplo2x4/position"].ravel())


def test_vision_task_flattens_features_and_keeps_the_camera_image():
    env = GymnasiumEnv(manipulation.load("lift_brick_vision", seed=0), flatten_observations=True)
    assert list(env.observation_space.keys()) == ["features", "front_close"]
    assert env.observation_space["front_close"].shape == (1, 84, 84, 3)
    assert env.observation_space["front_close"].dtype == np.uint8


def test_reset_with_the_same_seed_gives_identical_observations():
    env = GymnasiumEnv(manipulation.load("lift_brick_features"))
    first, _ = env.reset(seed=7)
    env.step(env.action_space.high)
    env.reset(seed=8)
    again, _ = env.reset(seed=7)
    other, _ = env.reset(seed=8)
    for name in first:
        np.testing.assert_array_equal(first[name], again[name])
    assert not np.array_equal(first["duplo2x4/position"], other["duplo2x4/position"])


def test_reset_without_a_seed_continues_the_random_sequence():
    env = GymnasiumEnv(manipulation.load("lift_brick_features"))
    first, _ = env.reset(seed=7)
    second, _ = env.reset()
    assert not np.array_equal(first["duplo2x4/position"], second["duplo2x4/position"])


class VectorRewardTask(SliderTask):
    """Returns its reward as an array of shape (1,), which composer.Environment passes on."""

    def get_reward(self, physics):
        return np.array([0.5])


class UnitRewardTask(SliderTask):
    """Declares rewards in [0, 1], but returns 1.5."""

    def get_reward_spec(self):
        return specs.BoundedArray((), np.float64, minimum=0.0, maximum=1.0, name="reward")

    def get_reward(self, physics):
        return 1.5


class TwoRewardsTask(SliderTask):
    def get_reward_spec(self):
        return specs.Array((2,), np.float64, name="reward")


def test_a_reward_of_shape_one_is_refused_naming_the_reward_and_its_spec():
    env = GymnasiumEnv(composer.Environment(VectorRewardTask()))
    env.reset(seed=0)
    with pytest.raises(ValueError) as raised:
        env.step(np.zeros(1))
    assert str(raised.value) == (
        "reward: expected one number, as Environment.reward_spec() says "
        "(Array(shape=(), dtype=dtype('float64'), name='reward')), got array([0.5]) of shape "
        "(1,); make the task's get_reward return a float"
    )


def test_a_reward_outside_the_bounds_of_its_spec_is_refused():
    env = GymnasiumEnv(composer.Environment(UnitRewardTask()))
    env.reset(seed=0)
    with pytest.raises(ValueError) as raised:
        env.step(np.zeros(1))
    assert str(raised.value) == (
        "reward: expected one number in [0, 1], as Environment.reward_spec() says "
        "(BoundedArray(shape=(), dtype=dtype('float64'), name='reward', minimum=0.0, "
        "maximum=1.0)), got 1.5"
    )


def test_a_reward_spec_of_more_than_one_number_is_refused_at_construction():
    with pytest.raises(ValueError) as raised:
        GymnasiumEnv(composer.Environment(TwoRewardsTask()))
    assert str(raised.value) == (
        "Environment.reward_spec(): expected the spec of one number (Gymnasium's step "
        "returns one float reward), got Array(shape=(2,), dtype=dtype('float64'), "
        "name='reward')"
    )


def test_a_reward_within_its_bounded_spec_is_returned_as_a_float():
    class HalfRewardTask(UnitRewardTask):
        def get_reward(self, physics):
            return np.float32(0.5)

    env = GymnasiumEnv(composer.Environment(HalfRewardTask()))
    env.reset(seed=0)
    reward = env.step(np.zeros(1))[1]
    assert type(reward) is float and reward == 0.5


@pytest.mark.parametrize("flatten", [False, True])
def test_observation_space_follows_an_observable_disabled_after_wrapping(flatten):
    env = GymnasiumEnv(slider_environment(), flatten_observations=flatten)
    env.reset(seed=0)
    env.dm_env.task.task_observables["velocity"].enabled = False
    observation, _ = env.reset(seed=0)
    if flatten:
        assert observation.shape == env.observation_space.shape == (1,)
    else:
        assert list(observation) == list(env.observation_space.spaces) == ["position"]
    assert env.observation_space.contains(observation)
    assert env.observation_space.contains(env.step(np.zeros(1))[0])


def test_observation_space_follows_a_buffer_size_changed_after_wrapping():
    env = GymnasiumEnv(slider_environment())
    env.dm_env.task.task_observables["position"].buffer_size = 3
    assert env.observation_space["position"].shape == (1, 1)
    observation, _ = env.reset(seed=0)
    assert observation["position"].shape == env.observation_space["position"].shape == (3, 1)
    assert env.observation_space.contains(observation)


def test_observation_space_changes_at_reset_not_in_the_middle_of_an_episode():
    env = GymnasiumEnv(slider_environment())
    env.reset(seed=0)
    space = env.observation_space
    env.dm_env.task.task_observables["velocity"].enabled = False
    observation = env.step(np.zeros(1))[0]
    assert env.observation_space is space
    assert space.contains(observation)


def test_observation_space_is_kept_when_reset_changes_no_observable():
    env = GymnasiumEnv(slider_environment())
    space = env.observation_space
    env.reset(seed=0)
    env.reset(seed=1)
    assert env.observation_space is space


def test_env_checker_passes_after_an_observable_is_disabled():
    env = GymnasiumEnv(slider_environment(time_limit=0.2), flatten_observations=True)
    env.dm_env.task.task_observables["velocity"].enabled = False
    env.reset(seed=0)
    with warnings.catch_warnings():
        # An observation outside its space is a warning too: make it an error. The advice
        # about the unbounded Box is not one.
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", message=".*value is -?infinity")
        check_env(env, skip_render_check=True)


def _empty_like(space):
    if isinstance(space, gymnasium.spaces.Dict):
        return {key: _empty_like(part) for key, part in space.spaces.items()}
    return np.full(space.shape, np.nan, space.dtype)


@pytest.mark.parametrize("flatten", [False, True])
def test_observations_written_to_given_arrays_are_those_a_twin_env_returns(flatten):
    ours = GymnasiumEnv(manipulation.load("lift_brick_features"), flatten_observations=flatten)
    twin = GymnasiumEnv(manipulation.load("lift_brick_features"), flatten_observations=flatten)
    out = _empty_like(ours.observation_space)
    ours.write_observations_to(out)
    steps = [lambda env: env.reset(seed=4)[0]]
    steps += [
        lambda env, a=a: env.step(a)[0] for a in (twin.action_space.low, twin.action_space.high)
    ]
    for step in steps:
        mine, theirs = step(ours), step(twin)
        assert mine is out
        if flatten:
            np.testing.assert_array_equal(mine, theirs)
        else:
            for name in theirs:
                np.testing.assert_array_equal(mine[name], theirs[name], err_msg=name)


@pytest.mark.parametrize("flatten", [False, True])
def test_the_composer_env_writes_its_observations_into_the_given_arrays_itself(flatten):
    env = GymnasiumEnv(slider_environment(), flatten_observations=flatten)
    out = _empty_like(env.observation_space)
    env.write_observations_to(out)
    env.reset(seed=0)
    # A dict observation is copied once, by the composer env straight into `out`; a
    # flattened one is concatenated into it by the adapter.
    timestep = env.dm_env.step(np.ones(1))
    assert (timestep.observation is out) is not flatten
    env.write_observations_to(None)
    assert env.dm_env.step(np.ones(1)).observation is not out


def test_write_observations_to_refuses_an_array_of_another_shape_naming_its_key():
    env = GymnasiumEnv(slider_environment())
    out = {"position": np.zeros((1, 1)), "velocity": np.zeros(1)}
    with pytest.raises(
        ValueError, match=r"out\['velocity'\]: expected a writeable float64 array of shape \(1, 1\)"
    ):
        env.write_observations_to(out)


def test_a_reset_that_changes_the_observation_space_refuses_the_given_arrays():
    env = GymnasiumEnv(slider_environment())
    env.write_observations_to({"position": np.zeros((1, 1)), "velocity": np.zeros((1, 1))})
    env.reset(seed=0)
    env.dm_env.task.task_observables["velocity"].enabled = False
    with pytest.raises(ValueError, match=r"out: expected a dict with the keys \['position'\]"):
        env.reset(seed=0)


def test_step_after_the_episode_ended_asks_for_reset():
    env = GymnasiumEnv(slider_environment(end_after_steps=1))
    with pytest.raises(RuntimeError, match="call reset"):
        env.step(np.zeros(1))
    env.reset(seed=0)
    env.step(np.zeros(1))
    with pytest.raises(RuntimeError, match="call reset"):
        env.step(np.zeros(1))


def test_rgb_render_has_the_requested_size():
    env = GymnasiumEnv(slider_environment(), render_mode="rgb_array", width=64, height=48)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (48, 64, 3)
    assert frame.dtype == np.uint8


def test_depth_render_is_float_metres_from_the_named_camera():
    env = GymnasiumEnv(
        slider_environment(), render_mode="depth_array", camera="side", width=32, height=24
    )
    env.reset(seed=0)
    physics = env.dm_env.physics
    physics.data.qpos[:] = 0.0
    physics.forward()
    depth = env.render()
    assert depth.shape == (24, 32)
    assert depth.dtype == np.float32
    # The camera is 1 m from the block's centre, whose near face is 5 cm closer.
    assert depth[12, 16] == pytest.approx(0.95, abs=0.01)


def test_named_camera_sees_a_different_view_than_the_free_camera():
    free = GymnasiumEnv(slider_environment(), render_mode="rgb_array", width=32, height=24)
    side = GymnasiumEnv(
        slider_environment(), render_mode="rgb_array", camera="side", width=32, height=24
    )
    free.reset(seed=0)
    side.reset(seed=0)
    assert not np.array_equal(free.render(), side.render())


def test_without_render_mode_render_returns_none():
    env = GymnasiumEnv(slider_environment())
    env.reset(seed=0)
    assert env.render() is None


def test_metadata_lists_human_and_the_off_screen_render_modes():
    # The window itself is tested under Xvfb in test_gym_human_render.py.
    assert GymnasiumEnv.metadata["render_modes"] == ["human", "rgb_array", "depth_array"]


def test_unknown_render_mode_is_rejected_naming_it():
    with pytest.raises(ValueError, match="render_mode: expected .* got 'rgb'"):
        GymnasiumEnv(slider_environment(), render_mode="rgb")


def test_render_fps_is_the_control_rate():
    assert GymnasiumEnv(slider_environment()).metadata["render_fps"] == pytest.approx(50.0)


class _Unseedable(dm_env.Environment):
    def reset(self):
        return dm_env.restart({"x": np.zeros(1)})

    def step(self, action):
        return dm_env.transition(0.0, {"x": np.zeros(1)})

    def observation_spec(self):
        return {"x": dm_env.specs.Array((1,), np.float64)}

    def action_spec(self):
        return dm_env.specs.BoundedArray((1,), np.float64, -1, 1)


def test_plain_dm_env_without_random_state_runs_but_cannot_be_seeded():
    env = GymnasiumEnv(_Unseedable())
    observation, _ = env.reset()
    assert observation["x"].shape == (1,)
    with pytest.raises(ValueError, match="has no `random_state`"):
        env.reset(seed=1)


@pytest.mark.parametrize("name", manipulation.ALL)
def test_every_manipulation_task_passes_gymnasiums_env_checker(name):
    env = GymnasiumEnv(manipulation.load(name, seed=0))
    with warnings.catch_warnings():
        # Advice about unbounded observations and non-normalised actions, not errors.
        warnings.simplefilter("ignore", UserWarning)
        check_env(env, skip_render_check=True)


def test_flattening_a_task_without_observations_gives_empty_dict_observations():
    class Unobserved(SliderTask):
        @property
        def task_observables(self):
            return {}

    env = GymnasiumEnv(composer.Environment(Unobserved()), flatten_observations=True)
    observation, _ = env.reset(seed=0)
    assert observation == {}
    assert env.observation_space == gymnasium.spaces.Dict({})
    assert env.step(np.zeros(env.action_space.shape))[0] == {}


class _SliderToTheRight(SliderTask):
    """Success: the block right of the origin."""

    def get_success(self, physics):
        return physics.data.qpos[0] > 0.0


def test_is_success_comes_with_the_last_step_of_a_terminated_episode_only():
    env = GymnasiumEnv(composer.Environment(_SliderToTheRight(end_after_steps=3)))
    env.reset(seed=0)
    env.dm_env.physics.data.qpos[0] = 0.5
    infos = [env.step(np.zeros(1))[-1] for _ in range(3)]
    assert [("is_success" in info) for info in infos] == [False, False, True]
    assert infos[-1]["is_success"] is True


def test_is_success_comes_with_the_last_step_of_a_truncated_episode():
    env = GymnasiumEnv(composer.Environment(_SliderToTheRight(), time_limit=0.04))
    env.reset(seed=0)
    env.dm_env.physics.data.qpos[0] = -0.5
    first = env.step(np.zeros(1))
    last = env.step(np.zeros(1))
    assert "is_success" not in first[-1]
    assert last[3] and last[-1]["is_success"] is False


def test_a_task_that_does_not_define_success_gives_no_is_success():
    env = GymnasiumEnv(slider_environment(time_limit=0.04))
    env.reset(seed=0)
    infos = [env.step(np.zeros(1))[-1] for _ in range(2)]
    assert infos == [{"discount": 1.0}, {"discount": 1.0}]


def test_a_success_that_is_not_a_bool_is_refused_naming_get_success():
    class Scored(SliderTask):
        def get_success(self, physics):
            return 0.7

    env = GymnasiumEnv(composer.Environment(Scored(end_after_steps=1)))
    env.reset(seed=0)
    with pytest.raises(
        ValueError, match=r"Scored.get_success: expected True, False or None, got 0.7"
    ):
        env.step(np.zeros(1))


@pytest.mark.parametrize("strip, shape", [(False, (1, 1)), (True, (1,))])
def test_a_wrapped_environment_keeps_its_own_observation_buffer_axis(strip, shape):
    dm = composer.Environment(SliderTask(), strip_singleton_obs_buffer_dim=strip)
    env = GymnasiumEnv(dm)
    observation, _ = env.reset(seed=0)
    assert env.observation_space["position"].shape == shape
    assert observation["position"].shape == shape
