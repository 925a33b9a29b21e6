"""A world of the CPU batch whose physics diverges ends its own episode, as its CPU env does.

The same absurd applied force is written into world 1 of a batch and into world 1's
`composer.Environment`: its accelerations become huge and MuJoCo resets both. The CPU env
(raise_exception_on_physics_error False) ends its episode with reward 0 and discount 0, and
so must the batch's world 1, while worlds 0 and 2 go on, each still equal to its CPU env.
"""

import logging

import numpy as np
import pytest

import composer
import mjcf
from manipulation import batch as manipulation_batch
from manipulation.tasks import registry

pytest.importorskip("mujoco.batch", reason="the CPU batch needs MuJoCo >= 4 (mujoco.batch)")

NAME = "reach_site_features"
SEEDS = (3, 4, 5)
HUGE = 1e30  # a force whose qacc passes MuJoCo's mjMAXVAL (1e10): mj_checkAcc resets


def _batch(**kwargs):
    return manipulation_batch.load(NAME, len(SEEDS), random_states=SEEDS, device="cpu", **kwargs)


def _cpu_envs():
    return [
        composer.Environment(
            registry.build_task(NAME), random_state=seed, raise_exception_on_physics_error=False
        )
        for seed in SEEDS
    ]


def _assert_worlds_equal(batch_step, cpu_steps, where):
    for world, cpu in enumerate(cpu_steps):
        label = f"world {world} {where}"
        assert int(batch_step.step_type[world]) == int(cpu.step_type), label
        assert batch_step.reward[world] == (cpu.reward or 0.0), label
        assert batch_step.discount[world] == (1.0 if cpu.discount is None else cpu.discount), label
        for key, value in cpu.observation.items():
            np.testing.assert_array_equal(batch_step.observation[key][world], value, label + key)


def test_a_diverging_world_ends_its_own_episode_as_its_cpu_env_does(caplog):
    batch_env, cpu_envs = _batch(raise_exception_on_physics_error=False), _cpu_envs()
    spec = cpu_envs[0].action_spec()
    rng = np.random.RandomState(0)
    batch_env.reset()
    for env in cpu_envs:
        env.reset()
    try:
        for step in range(6):
            if step == 2:
                batch_env.physics.data.qfrc_applied[1, 0] = HUGE
                cpu_envs[1].physics.data.qfrc_applied[0] = HUGE
            action = rng.uniform(spec.minimum, spec.maximum, (len(SEEDS), *spec.shape))
            with caplog.at_level(logging.WARNING):
                batch_step = batch_env.step(action)
            cpu_steps = [env.step(a) for env, a in zip(cpu_envs, action)]
            _assert_worlds_equal(batch_step, cpu_steps, f"at step {step}")
            if step == 2:
                assert [int(t) for t in batch_step.step_type] == [1, 2, 1]  # MID, LAST, MID
                assert batch_step.reward[1] == 0.0 and batch_step.discount[1] == 0.0
                assert batch_env.episode_ends().terminated.tolist() == [False, True, False]
                assert "world 1: Physics state is invalid" in caplog.text
                assert "mjWARN_BADQACC" in caplog.text
            if step == 3:  # world 1 starts its next episode; the others go on
                assert [int(t) for t in batch_step.step_type] == [1, 0, 1]
        np.testing.assert_array_equal(batch_env.physics.data.qpos[1], cpu_envs[1].physics.data.qpos)
    finally:
        batch_env.close()


def test_a_diverging_world_raises_a_physics_error_naming_it_by_default():
    batch_env = _batch()
    try:
        batch_env.reset()
        zeros = np.zeros((len(SEEDS), *batch_env.action_spec().shape))
        batch_env.step(zeros)
        batch_env.physics.data.qvel[2, 0] = np.nan
        with pytest.raises(mjcf.PhysicsError, match=r"world 2: .*mjWARN_BADQVEL"):
            batch_env.step(zeros)
        # After a reset every world steps on.
        batch_env.reset()
        assert [int(t) for t in batch_env.step(zeros).step_type] == [1, 1, 1]
    finally:
        batch_env.close()
