"""Stacker's batched `Stack`: every world is dm_control's episode, bit for bit."""

import numpy as np
import pytest
from episodes import SEEDS, differences, needs_suite

import suite_batch
from suite_batch.domains.stacker import BatchStack

pytestmark = needs_suite

STACKER_TASKS = ("stack_2", "stack_4")


def test_the_batch_has_every_stacker_task_of_the_suite(suite):
    assert set(STACKER_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "stacker"}


@pytest.mark.parametrize("task", STACKER_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "stacker", task) == []


def test_without_the_boxes_and_target_the_observation_is_dm_controls(suite):
    kwargs = {"fully_observable": False}
    batch = suite_batch.load(
        "stacker", "stack_2", len(SEEDS), task_kwargs=kwargs, random_states=SEEDS, threads=1
    )
    cpus = [
        suite.load("stacker", "stack_2", task_kwargs={"random": seed, **kwargs}) for seed in SEEDS
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


@pytest.mark.parametrize("task", STACKER_TASKS)
def test_the_reward_and_touch_are_dm_controls_with_boxes_at_the_target_and_in_the_hand(suite, task):
    # Random actions seldom bring a box onto the target or into the hand: put them there
    # (and near there) in each world, and compare with dm_control's reward and observation
    # of the same state.
    batch = suite_batch.load("stacker", task, len(SEEDS), random_states=SEEDS, threads=1)
    cpus = [suite.load("stacker", task, task_kwargs={"random": seed}) for seed in SEEDS]
    batch.reset()
    starts = [cpu.reset() and cpu.physics.get_state() for cpu in cpus]
    batched = BatchStack(cpus[0].task, cpus[0].physics, batch.physics)
    noise = np.random.RandomState(0)
    rewards, touches = [], []
    for offset in (0.0, 0.01, 0.04):
        for place in ("target", "grasp"):
            expected = []
            for world, (cpu, start) in enumerate(zip(cpus, starts)):
                cpu.physics.set_state(start)
                data = cpu.physics.named.data
                x, _, z = data.site_xpos[place]
                for box in cpu.task._box_names:
                    shift = offset * noise.standard_normal(3)
                    data.qpos[[f"{box}_x", f"{box}_z", f"{box}_y"]] = [x, z, 0.0] + shift
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
    # The states covered a box on the target and a touching hand.
    assert max(rewards) > 0.9
    assert np.any(np.array(touches) > 0)
