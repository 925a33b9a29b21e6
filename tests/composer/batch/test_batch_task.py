"""Which initial states a `BatchTask` asks for follows from the class: overriding
`initialize_episode` chooses array code, anything else the CPU task's initializers. Runs
without Warp."""

import composer
from composer import batch


class _RewardOnly(batch.BatchTask):
    def get_reward(self, physics):
        return physics.xp.zeros(physics.num_envs)


class _ArrayCode(_RewardOnly):
    def initialize_episode(self, physics, mask) -> None:
        physics.data.qpos[...] = 0.0


class _ArrayCodeSubclass(_ArrayCode):
    pass


def _null_task():
    return composer.NullTask(composer.Arena())


def test_a_task_without_an_initialize_episode_override_starts_from_the_cpu_task():
    task = _RewardOnly(_null_task())
    assert task.initial_state_source is batch.InitialStateSource.CPU_TASK


def test_overriding_initialize_episode_chooses_array_code_initial_states():
    task = _ArrayCode(_null_task())
    assert task.initial_state_source is batch.InitialStateSource.ARRAY_CODE


def test_a_subclass_of_an_array_code_task_keeps_array_code_initial_states():
    task = _ArrayCodeSubclass(_null_task())
    assert task.initial_state_source is batch.InitialStateSource.ARRAY_CODE
