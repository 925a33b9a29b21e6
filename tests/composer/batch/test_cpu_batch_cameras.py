"""Camera observables on the CPU batch (`device="cpu"`), rendered with OpenGL: every world's
images are its CPU environment's, bit for bit.

World i of a batch built with `random_states=SEEDS` equals `composer.Environment` of the
same task seeded `SEEDS[i]` (the rule `test_cpu_batch.py` checks for features); here every
observation, camera images included, is compared exactly, across an episode start.
"""

import threading

import mujoco
import numpy as np
import pytest

import composer
from composer import batch
from composer.observation import observable
from manipulation import batch as manipulation_batch
from manipulation.tasks import registry
from manipulation.tasks import task_constants as tc

pytest.importorskip("mujoco.batch", reason="the CPU batch needs MuJoCo >= 4 (mujoco.batch)")

SEEDS = (11, 12, 13)
# Three control steps to an episode: the six steps compared cross an episode start.
SHORT_EPISODE = 3 * tc.CONTROL_TIMESTEP
STEPS = 6


def _assert_worlds_equal(batch_step, cpu_steps, where: str) -> None:
    for world, cpu in enumerate(cpu_steps):
        assert int(batch_step.step_type[world]) == int(cpu.step_type), f"world {world} {where}"
        assert set(batch_step.observation) == set(cpu.observation)
        for key, value in cpu.observation.items():
            got = batch_step.observation[key][world]
            message = f"observation {key!r} of world {world} {where}"
            assert (got.dtype, got.shape) == (value.dtype, value.shape), message
            np.testing.assert_array_equal(got, value, err_msg=message)


def _run_alike(batch_env, cpu_envs, steps: int = STEPS) -> list:
    """Resets and steps the batch and its CPU environments with the same random actions,
    asserting every world equal each time; returns the episodes started and the last
    batch time step."""
    spec = cpu_envs[0].action_spec()
    rng = np.random.RandomState(0)
    batch_step, cpu_steps = batch_env.reset(), [env.reset() for env in cpu_envs]
    _assert_worlds_equal(batch_step, cpu_steps, "at the reset")
    starts = 0
    for step in range(1, steps + 1):
        action = rng.uniform(spec.minimum, spec.maximum, (len(cpu_envs), *spec.shape))
        batch_step = batch_env.step(action)
        cpu_steps = [env.step(world_action) for env, world_action in zip(cpu_envs, action)]
        _assert_worlds_equal(batch_step, cpu_steps, f"at step {step}")
        starts += int(np.sum(batch_step.first()))
    return starts, batch_step


def _cpu_envs(make_task, time_limit: float) -> list:
    return [
        composer.Environment(make_task(), time_limit=time_limit, random_state=seed)
        for seed in SEEDS
    ]


def _gl_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name.startswith("gl_cameras_")]


@pytest.mark.parametrize("name", manipulation_batch.BATCHED_VISION)
def test_every_observation_of_every_vision_task_equals_the_cpu_envs_bit_for_bit(name):
    env = manipulation_batch.load(
        name, len(SEEDS), random_states=SEEDS, device="cpu", time_limit=SHORT_EPISODE
    )
    try:
        starts, last = _run_alike(env, _cpu_envs(lambda: registry.build_task(name), SHORT_EPISODE))
    finally:
        env.close()
    assert starts, "no episode started in the compared steps"
    images = last.observation["front_close"]
    assert images.dtype == np.uint8 and images.shape == (len(SEEDS), 1, 84, 84, 3)
    assert not np.array_equal(images[0], images[1]), "two worlds saw the same image"


def _lift_with_more_cameras():
    """lift_brick_vision with depth, segmentation and optioned RGB cameras on
    'front_close', one of them at another size."""
    task = registry.build_task("lift_brick_vision")
    camera = task.root_entity.mjcf_model.find("camera", "front_close")
    no_sites = mujoco.MjvOption()
    no_sites.sitegroup[:] = 0
    no_sites.flags[mujoco.mjtVisFlag.mjVIS_CONTACTPOINT] = True
    extra = {
        "depth": observable.MJCFCamera(camera, height=48, width=64, depth=True),
        "segmentation": observable.MJCFCamera(camera, height=48, width=64, segmentation=True),
        "no_shadows_small": observable.MJCFCamera(
            camera,
            height=24,
            width=32,
            scene_option=no_sites,
            render_flag_overrides={"shadow": False, "wireframe": True},
        ),
    }
    for key, value in extra.items():
        value.enabled = True
        task.task_observables[f"front_close_{key}"] = value
    return task


def test_depth_segmentation_scene_options_and_other_sizes_equal_the_cpu_renders():
    env = batch.BatchEnvironment(
        _lift_with_more_cameras(),
        len(SEEDS),
        device="cpu",
        random_states=SEEDS,
        time_limit=SHORT_EPISODE,
        task_factory=_lift_with_more_cameras,
    )
    try:
        cpu_envs = _cpu_envs(_lift_with_more_cameras, SHORT_EPISODE)
        starts, last = _run_alike(env, cpu_envs, steps=4)
    finally:
        env.close()
    assert starts
    observation = last.observation
    assert observation["front_close_depth"].dtype == np.float32
    assert observation["front_close_depth"].shape == (len(SEEDS), 1, 48, 64, 1)
    assert observation["front_close_segmentation"].shape == (len(SEEDS), 1, 48, 64, 2)
    assert observation["front_close_no_shadows_small"].shape == (len(SEEDS), 1, 24, 32, 3)
    assert len(np.unique(observation["front_close_segmentation"][0, 0, ..., 0])) > 3


def test_worlds_with_their_own_geom_colours_render_them_as_their_cpu_envs():
    name = "reach_site_vision"
    env = manipulation_batch.load(
        name, len(SEEDS), random_states=SEEDS, device="cpu", batched_model_fields=["geom_rgba"]
    )
    cpu_envs = _cpu_envs(lambda: registry.build_task(name), tc.TIME_LIMIT)
    try:
        env.reset()
        for env_ in cpu_envs:
            env_.reset()
        physics = env.physics
        rgba = np.repeat(physics.mj_model.geom_rgba[None], len(SEEDS), axis=0)
        for world, cpu in enumerate(cpu_envs):
            rgba[world, :, world] = 1.0  # world 0 reddens everything, 1 greens, 2 blues
            cpu.physics.model.geom_rgba[...] = rgba[world]
        physics.set_model_rows("geom_rgba", rgba, np.arange(len(SEEDS)))
        action = np.zeros((len(SEEDS), *cpu_envs[0].action_spec().shape))
        batch_step = env.step(action)
        cpu_steps = [cpu.step(world_action) for cpu, world_action in zip(cpu_envs, action)]
    finally:
        env.close()
    _assert_worlds_equal(batch_step, cpu_steps, "after their colours changed")
    means = batch_step.observation["front_close"][:, 0].reshape(len(SEEDS), -1, 3).mean(axis=1)
    assert [int(np.argmax(row)) for row in means] == [0, 1, 2]


def test_closing_the_env_releases_the_opengl_workers():
    env = manipulation_batch.load("reach_site_vision", 3, seed=0, device="cpu", threads=2)
    cameras = env.cameras
    assert cameras.threads == 1  # one render thread, whatever the physics' threads
    assert len(_gl_threads()) == 1
    env.reset()
    env.close()
    assert cameras.threads == 0
    assert _gl_threads() == []
    with pytest.raises(RuntimeError, match=r"the cameras were closed"):
        cameras.render()
    env.close()  # a second close does nothing


def test_an_opengl_that_cannot_start_names_the_camera_observable_and_mujoco_gl(monkeypatch):
    def no_context(*args, **kwargs):
        raise RuntimeError("no EGL device")

    monkeypatch.setattr(mujoco, "Renderer", no_context)
    with pytest.raises(RuntimeError, match=r"camera observable 'front_close'.*MUJOCO_GL"):
        manipulation_batch.load("reach_site_vision", 2, seed=0, device="cpu")
    assert _gl_threads() == []
