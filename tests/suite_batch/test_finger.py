"""The batched finger tasks: world i is dm_control's
`suite.load("finger", task, task_kwargs={"random": seed})`."""

import mujoco
import numpy as np
import pytest
from episodes import SEEDS, differences, needs_suite

import suite_batch

pytestmark = needs_suite

FINGER_TASKS = ("spin", "turn_easy", "turn_hard")


def test_the_batch_has_every_finger_task_of_the_suite(suite):
    assert set(FINGER_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "finger"}


@pytest.mark.parametrize("task", FINGER_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "finger", task) == []


def _rewards_at_hinge_states(suite, task, angles, velocities):
    """The CPU envs' and the batch's rewards, and the worlds whose observations differ,
    with the spinner's hinge set to each (angle, velocity) in every world after its first
    reset (the CPU envs seeded as the batch's worlds, so each world keeps its target)."""
    batch = suite_batch.load("finger", task, len(SEEDS), random_states=SEEDS, threads=1)
    cpus = [suite.load("finger", task, task_kwargs={"random": seed}) for seed in SEEDS]
    batch.reset()
    for cpu in cpus:
        cpu.reset()
    model = cpus[0].physics.model.ptr
    hinge = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "hinge")
    qpos, qvel = int(model.jnt_qposadr[hinge]), int(model.jnt_dofadr[hinge])
    expected, got, differing = [], [], []
    for angle, velocity in zip(angles, velocities):
        batch.physics.data.qpos[:, qpos] = angle
        batch.physics.data.qvel[:, qvel] = velocity
        batch.physics.forward()
        got += list(batch._batch_task.get_reward())
        observation = batch._batch_task.get_observation()
        for world, cpu in enumerate(cpus):
            cpu.physics.data.qpos[qpos] = angle
            cpu.physics.data.qvel[qvel] = velocity
            cpu.physics.forward()
            expected.append(cpu.task.get_reward(cpu.physics))
            for key, value in cpu.task.get_observation(cpu.physics).items():
                if not np.array_equal(observation[key][world], value):
                    differing.append((angle, world, key))
    batch.close()
    for cpu in cpus:
        cpu.close()
    return expected, got, differing


def test_spin_rewards_a_fast_negative_spin_as_dm_control(suite):
    velocities = np.random.RandomState(0).uniform(-30, 0, 40)
    expected, got, differing = _rewards_at_hinge_states(
        suite, "spin", np.zeros_like(velocities), velocities
    )
    assert {0.0, 1.0} <= set(expected)
    assert got == expected
    assert differing == []


@pytest.mark.parametrize("task", ("turn_easy", "turn_hard"))
def test_turn_rewards_the_tip_inside_each_worlds_target_as_dm_control(suite, task):
    angles = np.linspace(-np.pi, np.pi, 120)
    expected, got, differing = _rewards_at_hinge_states(suite, task, angles, np.zeros(120))
    assert {0.0, 1.0} <= set(expected)
    assert got == expected
    assert differing == []
