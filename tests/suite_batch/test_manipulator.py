"""Manipulator's batched `Bring`: every world is dm_control's episode, bit for bit."""

import numpy as np
import pytest
from episodes import SEEDS, differences, needs_suite

import suite_batch
from suite_batch.domains.manipulator import BatchBring

pytestmark = needs_suite

MANIPULATOR_TASKS = ("bring_ball", "bring_peg", "insert_ball", "insert_peg")


def test_the_batch_has_every_manipulator_task_of_the_suite(suite):
    assert set(MANIPULATOR_TASKS) == {
        task for domain, task in suite.ALL_TASKS if domain == "manipulator"
    }


@pytest.mark.parametrize("task", MANIPULATOR_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "manipulator", task) == []


@pytest.mark.parametrize("task", ["bring_ball", "insert_peg"])
def test_without_the_prop_and_target_the_observation_is_dm_controls(suite, task):
    kwargs = {"fully_observable": False}
    batch = suite_batch.load(
        "manipulator", task, len(SEEDS), task_kwargs=kwargs, random_states=SEEDS, threads=1
    )
    cpus = [
        suite.load("manipulator", task, task_kwargs={"random": seed, **kwargs}) for seed in SEEDS
    ]
    shape = (len(SEEDS), *cpus[0].action_spec().shape)
    steps = [batch.reset()], [[cpu.reset() for cpu in cpus]]
    for action in np.random.RandomState(0).uniform(-1, 1, (5, *shape)):
        steps[0].append(batch.step(action))
        steps[1].append([cpu.step(row) for cpu, row in zip(cpus, action)])
    batch.close()
    for cpu in cpus:
        cpu.close()
    for step, cpu_steps in zip(*steps):
        for world, cpu_step in enumerate(cpu_steps):
            assert (
                list(step.observation)
                == list(cpu_step.observation)
                == [
                    "arm_pos",
                    "arm_vel",
                    "touch",
                ]
            )
            for key, value in cpu_step.observation.items():
                np.testing.assert_array_equal(step.observation[key][world], value, err_msg=key)


@pytest.mark.parametrize("task", MANIPULATOR_TASKS)
def test_the_reward_and_touch_are_dm_controls_with_the_prop_at_the_target_or_in_the_hand(
    suite, task
):
    # Random actions seldom bring the prop near its target or into the hand: put it there
    # (and near there) in each world, as dm_control's own `in_target` and `in_hand` starts
    # do, and compare with dm_control's reward and observation of the same state.
    batch = suite_batch.load("manipulator", task, len(SEEDS), random_states=SEEDS, threads=1)
    cpus = [suite.load("manipulator", task, task_kwargs={"random": seed}) for seed in SEEDS]
    batch.reset()
    starts = [cpu.reset() and cpu.physics.get_state() for cpu in cpus]
    batched = BatchBring(cpus[0].task, cpus[0].physics, batch.physics)
    noise = np.random.RandomState(0)
    rewards, touches = [], []
    for offset in (0.0, 0.004, 0.012, 0.03):
        for in_hand in (False, True):
            expected = []
            for world, (cpu, start) in enumerate(zip(cpus, starts)):
                cpu.physics.set_state(start)
                data = cpu.physics.named.data
                if in_hand:
                    grasp = data.site_xpos["grasp"]
                    pose = [grasp[0], grasp[2], noise.uniform(0, 2 * np.pi)]
                else:
                    target, quaternion = data.xpos[cpu.task._target], data.xquat[cpu.task._target]
                    pose = [target[0], target[2], 2 * np.arctan2(quaternion[2], quaternion[0])]
                data.qpos[cpu.task._object_joints] = pose + offset * noise.standard_normal(3)
                cpu.physics.forward()
                for field in ("qpos", "qvel", "ctrl"):
                    getattr(batch.physics.data, field)[world] = getattr(cpu.physics.data, field)
                expected.append(
                    (cpu.task.get_reward(cpu.physics), cpu.task.get_observation(cpu.physics))
                )
            batch.physics.forward()
            reward, observation = batched.get_reward(), batched.get_observation()
            for world, (cpu_reward, cpu_observation) in enumerate(expected):
                assert reward[world] == cpu_reward
                for key, value in cpu_observation.items():
                    np.testing.assert_array_equal(observation[key][world], value, err_msg=key)
                rewards.append(cpu_reward)
                touches.append(cpu_observation["touch"])
    batch.close()
    for cpu in cpus:
        cpu.close()
    # The states covered a full reward, a partial one and a touching hand.
    assert max(rewards) == 1.0
    assert any(0.01 < r < 1.0 for r in rewards)
    assert np.any(np.array(touches) > 0)
