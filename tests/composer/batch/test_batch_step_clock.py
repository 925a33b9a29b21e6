"""The step's parts timed by a StepClock, and the device-to-host copies a step makes."""

import time

import numpy as np
import pytest

from composer.batch import step_clock
from manipulation import batch as manipulation_batch

pytestmark = pytest.mark.warp
pytest.importorskip("warp", reason="needs MuJoCo Warp: pip install -e '.[warp]'")

NAME = "reach_site_features"
NUM_ENVS = 4
STEPS = 12


def _zeros(env):
    return np.zeros((env.num_envs, *env.action_spec().shape), np.float32)


def test_the_parts_of_each_step_add_up_to_its_wall_time():
    # Episodes of 0.2 s (5 steps): the timed steps start episodes too.
    env = manipulation_batch.load(NAME, NUM_ENVS, device="warp-cpu", seed=0, time_limit=0.2)
    action = _zeros(env)
    env.reset()
    env.step(action)
    # On Warp's CPU device nothing is captured: a wrapper times the physics from outside.
    physics_seconds = []
    step_physics = env.physics.step

    def timed_physics(n_sub_steps):
        begin = time.perf_counter()
        step_physics(n_sub_steps)
        physics_seconds.append(time.perf_counter() - begin)

    env.physics.step = timed_physics
    clock = step_clock.StepClock(env.synchronize)
    env.step_clock = clock
    begin = time.perf_counter()
    for _ in range(STEPS):
        env.step(action)
    wall = time.perf_counter() - begin
    env.step_clock = None
    env.step(action)  # untimed: the clock no longer counts
    env.close()
    parts = sum(clock.seconds.values())
    assert clock.steps == STEPS
    assert set(clock.seconds) == set(step_clock.PARTS)
    # Outside the parts: only entering and leaving `step` (microseconds of a step of ms).
    assert 0.9 * wall <= parts <= wall
    # The physics part is the physics: the wrapper's time, give or take a synchronisation.
    assert len(physics_seconds) == STEPS + 1
    assert sum(physics_seconds[:STEPS]) <= clock.seconds["physics"]
    assert clock.seconds["physics"] <= sum(physics_seconds[:STEPS]) + 0.05 * wall


def test_a_step_clock_must_be_a_step_clock():
    env = manipulation_batch.load(NAME, 1, device="warp-cpu", seed=0)
    with pytest.raises(ValueError, match="step_clock: expected a StepClock or None"):
        env.step_clock = "fast"
    env.close()


# Lift's reward is a kernel after a contact watch; reach's is array code.
@pytest.mark.parametrize("name", [NAME, "lift_brick_features"])
def test_steps_copy_to_the_host_only_the_refills_counter_read(name):
    torch = pytest.importorskip("torch", reason="torch is optional: pip install torch==2.13.0")
    # Task code on torch tensors on Warp's CPU device: the code path CUDA runs, where every
    # copy to the host would synchronise. Episodes of 0.2 s (5 steps) start within the run.
    env = manipulation_batch.load(
        name,
        NUM_ENVS,
        device="warp-cpu",
        seed=0,
        time_limit=0.2,
        array_type="torch",
        check_action_values=False,
        refill_interval=8,
    )
    action = torch.zeros(tuple(_zeros(env).shape))
    env.reset()
    counts = []
    with step_clock.HostCopies() as copies:
        for _ in range(3 * 8):
            before = copies.count
            env.step(action)
            counts.append(copies.count - before)
    env.close()
    # One read of the episode counters every 8 steps (refill_interval), nothing else.
    assert sum(counts) == 3
    steps_with_a_copy = np.flatnonzero(counts)
    assert np.all(np.diff(steps_with_a_copy) == 8)
    assert max(counts) == 1
