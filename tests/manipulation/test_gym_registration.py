"""The manipulation tasks are Gymnasium ids, registered without importing gymnasium early."""

import math
import warnings

import gymnasium
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import composer
import manipulation
from composer.batch.gym import BatchVectorEnv
from composer.gym import GymnasiumEnv, ThreadedVectorEnv
from manipulation.tasks import registry

# 10 s episodes of 0.04 s control steps (manipulation's module docstring).
EPISODE_STEPS = 250

# `mujoco.batch`, which the CPU batch runs on, came with MuJoCo 4.0; the version matrix runs
# these tests on older releases too.
HAS_MUJOCO_BATCH = int(mujoco.__version__.split(".")[0]) >= 4
needs_mujoco_batch = pytest.mark.skipif(
    not HAS_MUJOCO_BATCH, reason=f"mujoco {mujoco.__version__} has no mujoco.batch (from 4.0)"
)


def _output(result) -> str:
    """The printed output of a `fresh_python` run that must have succeeded."""
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_every_task_has_a_composer_v0_id():
    ids = {f"composer/{name}-v0" for name in manipulation.ALL}
    assert len(ids) == 26
    assert ids <= set(gymnasium.registry)


def test_make_builds_the_task_with_the_render_mode():
    env = gymnasium.make(
        "composer/lift_brick_features-v0", render_mode="rgb_array", width=48, height=32
    )
    assert isinstance(env.unwrapped, GymnasiumEnv)
    observation, _ = env.reset(seed=0)
    assert "duplo2x4/position" in observation
    assert env.render().shape == (32, 48, 3)
    env.close()


@needs_mujoco_batch
@pytest.mark.parametrize(
    "backend, vector_type",
    [(None, BatchVectorEnv), ("batch", BatchVectorEnv), ("threads", ThreadedVectorEnv)],
)
def test_make_vec_with_the_vector_entry_point_gives_the_batch_unless_told(backend, vector_type):
    options = {} if backend is None else {"backend": backend}
    envs = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=3,
        vectorization_mode="vector_entry_point",
        **options,
    )
    assert type(envs) is vector_type
    assert envs.num_envs == 3
    observations, _ = envs.reset(seed=0)
    _, rewards, *_ = envs.step(np.zeros((3, 9)))
    assert observations["jaco_arm/joints_pos"].shape == (3, 6, 2)
    assert rewards.shape == (3,)
    envs.close()


@pytest.mark.skipif(HAS_MUJOCO_BATCH, reason=f"mujoco {mujoco.__version__} has mujoco.batch")
def test_below_mujoco_4_make_vec_gives_the_threaded_env_and_refuses_the_batch_by_name():
    name = "composer/reach_site_features-v0"
    envs = gymnasium.make_vec(name, num_envs=2, vectorization_mode="vector_entry_point")
    assert type(envs) is ThreadedVectorEnv
    envs.close()
    with pytest.raises(ImportError, match=r"mujoco\.batch, which MuJoCo 3\.\d+\.\d+ does not"):
        gymnasium.make_vec(
            name, num_envs=2, vectorization_mode="vector_entry_point", backend="batch"
        )


def test_make_vec_passes_thread_count_and_autoreset_mode():
    envs = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
        num_threads=1,
        autoreset_mode="SameStep",
    )
    assert envs.num_threads == 1
    assert envs.metadata["autoreset_mode"] is gymnasium.vector.AutoresetMode.SAME_STEP
    envs.close()


@pytest.mark.parametrize(
    "option", [{"num_threads": 2}, {"max_episode_steps": 5}, {"flatten_observations": True}]
)
def test_make_vec_picks_the_threaded_env_for_an_option_only_it_takes(option):
    envs = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
        **option,
    )
    assert type(envs) is ThreadedVectorEnv
    envs.close()


def test_make_vec_rejects_an_unknown_backend():
    with pytest.raises(
        ValueError, match="backend: expected 'batch', 'threads', 'ray' or None, got 'mpi'"
    ):
        gymnasium.make_vec(
            "composer/reach_site_features-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            backend="mpi",
        )


@pytest.mark.parametrize("option", ["envs_per_actor", "start_timeout", "call_timeout"])
def test_make_vec_rejects_ray_options_for_the_threads_backend(option):
    with pytest.raises(ValueError, match=f"{option}: an option of backend='ray'"):
        gymnasium.make_vec(
            "composer/reach_site_features-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            **{option: 2},
        )


def test_make_vec_rejects_num_threads_for_the_ray_backend():
    with pytest.raises(ValueError, match="num_threads: an option of backend='threads'"):
        gymnasium.make_vec(
            "composer/reach_site_features-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            backend="ray",
            num_threads=2,
        )


def test_importing_the_packages_does_not_import_gymnasium(fresh_python):
    result = fresh_python(
        """
        import sys
        import composer, mjcf, manipulation
        print("gymnasium" in sys.modules)
        """
    )
    assert _output(result) == "False"


@pytest.mark.parametrize(
    "imports",
    [
        "import manipulation, gymnasium",
        "import gymnasium, manipulation",
        "import gymnasium",
        # composer.gym imports gymnasium, whose import then registers the tasks.
        "import manipulation; import composer.gym; import gymnasium",
    ],
)
def test_module_syntax_id_works_whatever_was_imported_first(imports, fresh_python):
    result = fresh_python(
        f"""
        {imports}
        env = gymnasium.make("manipulation:composer/lift_brick_features-v0")
        print(type(env.unwrapped).__name__)
        """
    )
    assert _output(result) == "GymnasiumEnv"


def test_plain_id_works_once_manipulation_is_imported_before_gymnasium(fresh_python):
    result = fresh_python(
        """
        import manipulation
        import gymnasium
        print(gymnasium.spec("composer/reach_site_vision-v0").kwargs)
        """
    )
    assert _output(result) == "{'environment_name': 'reach_site_vision'}"


@needs_mujoco_batch
def test_the_batch_and_threaded_env_match_gymnasiums_sync_vector_env_step_for_step():
    # Sub-environment (or world) i is seeded with 4 + i in each.
    name = "composer/lift_brick_features-v0"
    vector_envs = [
        gymnasium.make_vec(name, num_envs=2, vectorization_mode="sync"),
        gymnasium.make_vec(name, num_envs=2, vectorization_mode="vector_entry_point"),
        gymnasium.make_vec(
            name, num_envs=2, vectorization_mode="vector_entry_point", backend="threads"
        ),
    ]
    assert [type(envs) for envs in vector_envs[1:]] == [BatchVectorEnv, ThreadedVectorEnv]
    actions = np.random.RandomState(0).uniform(-0.5, 0.5, size=(3, 2, 9))
    results = []
    for envs in vector_envs:
        observations, _ = envs.reset(seed=4)
        trace = [observations["duplo2x4/position"].copy()]
        for action in actions:
            observations, rewards, *_ = envs.step(action)
            trace += [observations["jaco_arm/joints_pos"].copy(), rewards]
        results.append(trace)
        envs.close()
    for sync, *ours in zip(*results):
        for values in ours:
            np.testing.assert_array_equal(values, sync)


def test_make_with_human_render_mode_opens_no_window_before_the_first_reset():
    # No display here: the window (tested under Xvfb in test_gym_human_render.py) opens at
    # the first reset.
    env = gymnasium.make("composer/reach_site_features-v0", render_mode="human")
    assert env.render_mode == "human"
    env.close()


def _steps_until_the_end(env, action) -> tuple[int, bool, bool, dict]:
    """Steps `env` from a reset until its episode ends: (steps, terminated, truncated, info)."""
    env.reset(seed=0)
    steps = 0
    while True:
        _, _, terminated, truncated, info = env.step(action)
        steps += 1
        if terminated or truncated:
            return steps, terminated, truncated, info


@pytest.mark.parametrize("name", ["reach_site_features", "lift_brick_features"])
def test_max_episode_steps_is_the_step_at_which_episodes_truncate(name):
    spec = gymnasium.spec(f"composer/{name}-v0")
    assert spec.max_episode_steps == EPISODE_STEPS
    env = gymnasium.make(spec.id)
    steps, terminated, truncated, _ = _steps_until_the_end(env, np.zeros(9))
    assert (steps, terminated, truncated) == (EPISODE_STEPS, False, True)
    # The environment itself ends the episode at the same step: Gymnasium's TimeLimit
    # neither cuts it short nor adds a second end.
    steps, terminated, truncated, _ = _steps_until_the_end(env.unwrapped, np.zeros(9))
    assert (steps, terminated, truncated) == (EPISODE_STEPS, False, True)


def test_every_ids_max_episode_steps_is_its_tasks_time_limit_in_control_steps():
    for name in manipulation.ALL:
        task = registry.build_task(name)
        # manipulation.load gives every task 10 s episodes.
        steps = round(10.0 / task.control_timestep)
        assert gymnasium.spec(f"composer/{name}-v0").max_episode_steps == steps == EPISODE_STEPS


def test_make_vec_takes_a_shorter_max_episode_steps():
    envs = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
        max_episode_steps=3,
    )
    envs.reset(seed=0)
    truncations = [envs.step(np.zeros((2, 9)))[3].tolist() for _ in range(3)]
    assert truncations == [[False, False], [False, False], [True, True]]
    envs.close()


def test_make_vec_refuses_a_max_episode_steps_beyond_the_time_limit():
    with pytest.raises(
        ValueError, match="max_episode_steps: expected an int from 1 to 250 .* got 300"
    ):
        gymnasium.make_vec(
            "composer/reach_site_features-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            max_episode_steps=300,
        )


def test_registered_ids_observations_have_no_buffer_axis():
    env = gymnasium.make("composer/reach_site_features-v0")
    observation, _ = env.reset(seed=0)
    space = env.observation_space
    # A 3-D target position; two values (sine and cosine) for each of the six arm joints.
    assert space["target_position"].shape == observation["target_position"].shape == (3,)
    assert space["jaco_arm/joints_pos"].shape == (6, 2)
    assert observation["jaco_arm/joints_pos"].shape == (6, 2)
    assert space["jaco_arm/jaco_hand/pinch_site_rmat"].shape == (9,)
    assert observation in space
    env.close()


def test_a_vision_ids_camera_image_has_no_buffer_axis():
    env = gymnasium.make("composer/reach_site_vision-v0")
    observation, _ = env.reset(seed=0)
    assert env.observation_space["front_close"].shape == (84, 84, 3)
    assert observation["front_close"].shape == (84, 84, 3)
    env.close()


def test_check_env_passes_headless_on_the_unwrapped_registered_env(monkeypatch):
    # Headless: GLFW, which the 'human' render mode needs, finds no display.
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    env = gymnasium.make("composer/reach_site_features-v0")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # Advice, not failures: unbounded observations, actions not in [-1, 1].
        warnings.filterwarnings("ignore", message=".*observation space m.*infinity")
        warnings.filterwarnings("ignore", message=".*symmetric and normalized space")
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_rescale_action_maps_minus_one_and_one_to_the_actuators_ranges():
    env = gymnasium.wrappers.RescaleAction(
        gymnasium.make("composer/reach_site_features-v0"), -1.0, 1.0
    )
    assert env.action_space == gymnasium.spaces.Box(-1.0, 1.0, (9,), np.float64)
    # Joint velocity limits (rad/s) of the arm's six joints, then the three fingers'.
    limits = np.array([0.6283] * 3 + [0.8378] * 3 + [5.0] * 3)
    env.reset(seed=0)
    controls = env.unwrapped.dm_env.physics.data.ctrl
    for sign in (-1.0, 1.0):
        env.step(np.full(9, sign))
        np.testing.assert_allclose(controls, sign * limits, rtol=1e-12)
    env.close()


def _pinch_to_target(env) -> float:
    """The distance from the pinch site to the reach target, from the physics."""
    task, physics = env.dm_env.task, env.dm_env.physics
    pinch = physics.bind(task.hand.tool_center_point).xpos
    return math.dist(pinch, physics.bind(task.target).xpos)


def test_reach_episode_with_the_hand_at_the_target_ends_with_is_success():
    env = gymnasium.make("composer/reach_site_features-v0")
    env.reset(seed=0)
    gym_env = env.unwrapped
    task, physics = gym_env.dm_env.task, gym_env.dm_env.physics
    target = physics.bind(task.target)
    infos = []
    truncated = False
    while not truncated:
        # The target follows the hand: the hand is at the target after every step.
        target.pos = physics.bind(task.hand.tool_center_point).xpos
        physics.forward()
        _, _, terminated, truncated, info = env.step(np.zeros(9))
        infos.append(info)
    assert _pinch_to_target(gym_env) < 0.05  # within the 5 cm reach radius
    assert infos[-1]["is_success"] is True
    assert all("is_success" not in info for info in infos[:-1])
    env.close()


def test_short_random_reach_episode_ends_without_success():
    task = registry.build_task("reach_site_features")
    env = GymnasiumEnv(composer.Environment(task, time_limit=0.4, random_state=3))
    env.action_space.seed(3)
    env.reset(seed=3)
    infos = [env.step(env.action_space.sample())[-1] for _ in range(10)]
    assert _pinch_to_target(env) > 0.05  # outside the 5 cm reach radius
    assert infos[-1]["is_success"] is False  # 0.4 s: the tenth step is the last
    assert all("is_success" not in info for info in infos[:-1])
