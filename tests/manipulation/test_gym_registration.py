"""The manipulation tasks are Gymnasium ids, registered without importing gymnasium early."""

import subprocess
import sys
import textwrap

import gymnasium
import numpy as np
import pytest

import manipulation
from composer.gym import GymnasiumEnv, ThreadedVectorEnv


def _run(code: str) -> str:
    result = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        check=False,
        env={"MUJOCO_GL": "egl", "PATH": ""},
    )
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_every_task_has_a_composer_v0_id():
    ids = {f"composer/{name}-v0" for name in manipulation.ALL}
    assert len(ids) == 25
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


def test_make_vec_with_the_vector_entry_point_gives_the_threaded_vector_env():
    envs = gymnasium.make_vec(
        "composer/reach_site_features-v0", num_envs=3, vectorization_mode="vector_entry_point"
    )
    assert isinstance(envs, ThreadedVectorEnv)
    assert envs.num_envs == 3
    observations, _ = envs.reset(seed=0)
    _, rewards, *_ = envs.step(np.zeros((3, 9)))
    assert observations["jaco_arm/joints_pos"].shape == (3, 1, 6, 2)
    assert rewards.shape == (3,)
    envs.close()


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


def test_make_vec_rejects_an_unknown_backend():
    with pytest.raises(ValueError, match="backend: expected 'threads', 'ray' or 'warp', got 'mpi'"):
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


def test_importing_the_packages_does_not_import_gymnasium():
    assert (
        _run(
            """
            import sys
            import composer, mjcf, manipulation
            print("gymnasium" in sys.modules)
            """
        )
        == "False"
    )


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
def test_module_syntax_id_works_whatever_was_imported_first(imports):
    out = _run(
        f"""
        {imports}
        env = gymnasium.make("manipulation:composer/lift_brick_features-v0")
        print(type(env.unwrapped).__name__)
        """
    )
    assert out == "GymnasiumEnv"


def test_plain_id_works_once_manipulation_is_imported_before_gymnasium():
    out = _run(
        """
        import manipulation
        import gymnasium
        print(gymnasium.spec("composer/reach_site_vision-v0").kwargs)
        """
    )
    assert out == "{'environment_name': 'reach_site_vision'}"


def test_threaded_vector_env_matches_gymnasiums_sync_vector_env_step_for_step():
    kinds = ("vector_entry_point", "sync")
    vector_envs = [
        gymnasium.make_vec("composer/lift_brick_features-v0", num_envs=2, vectorization_mode=m)
        for m in kinds
    ]
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
    for ours, sync in zip(*results):
        np.testing.assert_array_equal(ours, sync)


def test_make_with_human_render_mode_opens_no_window_before_the_first_reset():
    # No display here: the window (tested under Xvfb in test_gym_human_render.py) opens at
    # the first reset.
    env = gymnasium.make("composer/reach_site_features-v0", render_mode="human")
    assert env.render_mode == "human"
    env.close()
