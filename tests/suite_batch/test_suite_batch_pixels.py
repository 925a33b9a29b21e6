"""The batched suite's pixels: every world's frame is dm_control's `pixels.Wrapper` frame of
the env seeded alike, bit for bit, across resets."""

import numpy as np
import pytest
from episodes import SEEDS, needs_suite, short_time_limit

import suite_batch
from suite_batch import pixels

pytestmark = needs_suite

# What pixel-based agents (DrQ-v2, DreamerV3) render.
RENDER = {"height": 84, "width": 84, "camera_id": 0}
STEPS = 30  # 25-step episodes: one reset inside


def _pair(suite, domain, task, **wrapper_kwargs):
    from dm_control.suite.wrappers import pixels as dm_pixels

    limit = {"time_limit": short_time_limit(suite, domain, task)}
    batch = pixels.Wrapper(
        suite_batch.load(domain, task, len(SEEDS), task_kwargs=limit, random_states=SEEDS),
        render_kwargs=RENDER,
        **wrapper_kwargs,
    )
    cpus = [
        dm_pixels.Wrapper(
            suite.load(domain, task, task_kwargs={"random": seed, **limit}),
            render_kwargs=RENDER,
            **wrapper_kwargs,
        )
        for seed in SEEDS
    ]
    return batch, cpus


# reacher: its target, drawn per episode, moves in each world's frame.
@pytest.mark.parametrize(
    "domain, task", [("cartpole", "swingup"), ("walker", "walk"), ("reacher", "easy")]
)
def test_every_frame_is_dm_controls_pixels_wrapper_frame(suite, domain, task):
    batch, cpus = _pair(suite, domain, task)
    assert batch.observation_spec() == cpus[0].observation_spec()
    spec = batch.action_spec()
    actions = np.random.RandomState(0).uniform(
        spec.minimum, spec.maximum, (STEPS, len(SEEDS), *spec.shape)
    )
    step, cpu_steps = batch.reset(), [cpu.reset() for cpu in cpus]
    differing, first_frames = [], step.observation["pixels"].copy()
    for t in range(STEPS + 1):
        assert list(step.observation) == ["pixels"]
        frames = step.observation["pixels"]
        assert frames.shape == (len(SEEDS), 84, 84, 3) and frames.dtype == np.uint8
        differing += [
            (t, world)
            for world, cpu_step in enumerate(cpu_steps)
            if not np.array_equal(frames[world], cpu_step.observation["pixels"])
        ]
        if t == STEPS:
            break
        step = batch.step(actions[t])
        cpu_steps = [cpu.step(action) for cpu, action in zip(cpus, actions[t])]
    assert differing == []
    # The frames show each world's own state, and it moved.
    assert not np.array_equal(first_frames[0], first_frames[1])
    assert not np.array_equal(first_frames[0], frames[0])
    batch.close()


def test_pixels_only_false_keeps_the_state_observations(suite):
    batch, cpus = _pair(suite, "cartpole", "swingup", pixels_only=False)
    step, cpu_step = batch.reset(), cpus[0].reset()
    assert list(step.observation) == ["position", "velocity", "pixels"]
    for key, value in cpu_step.observation.items():
        np.testing.assert_array_equal(step.observation[key][0], value)
    batch.close()


def test_a_key_the_observations_have_is_refused(suite):
    env = suite_batch.load("cartpole", "swingup", 2)
    with pytest.raises(ValueError, match=r"observation_key: 'position' is already an observation"):
        pixels.Wrapper(env, pixels_only=False, observation_key="position")
    env.close()


def test_a_world_renders_its_own_model_rows(suite):
    # A colour given to one world only (a row of its own), as a per-world model field the
    # frames read from the model rather than from the data.
    from dm_control.suite.wrappers import pixels as dm_pixels

    batch = pixels.Wrapper(
        suite_batch.load("reacher", "easy", 2, random_states=(3, 11)), render_kwargs=RENDER
    )
    cpu = dm_pixels.Wrapper(
        suite.load("reacher", "easy", task_kwargs={"random": 11}), render_kwargs=RENDER
    )
    batch.reset()
    cpu.reset()
    rgba = batch.env.physics.batch.expand("geom_rgba")
    rgba[1, :, :3] = [1.0, 0.0, 0.0]
    cpu.physics.model.geom_rgba[:, :3] = [1.0, 0.0, 0.0]
    frames = batch.render()
    expected = cpu.physics.render(**RENDER)
    np.testing.assert_array_equal(frames[1], expected)
    assert not np.array_equal(frames[0][..., 1:], np.zeros_like(frames[0][..., 1:]))
    batch.close()
