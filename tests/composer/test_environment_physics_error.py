"""composer.Environment when the physics diverges."""

import logging

import dm_env
import numpy as np
import pytest
from composer_scene import Diverges

import composer
import mjcf


class DivergesWithSubstepHook(Diverges):
    """The same, stepping one sub-step at a time because of a sub-step hook."""

    substeps = 0

    def before_substep(self, physics, action, random_state):
        self.substeps += 1


def test_physics_error_propagates_by_default():
    env = composer.Environment(Diverges(diverge_at=2))
    env.reset()
    env.step(np.zeros(2))
    with pytest.raises(mjcf.PhysicsError):
        env.step(np.zeros(2))


@pytest.mark.parametrize("task_type", [Diverges, DivergesWithSubstepHook])
def test_physics_error_ends_episode_with_zero_reward_and_discount(task_type, caplog):
    env = composer.Environment(task_type(diverge_at=2), raise_exception_on_physics_error=False)
    env.reset()
    assert env.step(np.zeros(2)).mid()
    with caplog.at_level(logging.WARNING):
        timestep = env.step(np.zeros(2))
    assert timestep.step_type == dm_env.StepType.LAST
    assert timestep.reward == 0.0
    assert timestep.discount == 0.0
    assert "Physics error" in caplog.text


def test_step_after_physics_error_starts_a_new_episode():
    env = composer.Environment(Diverges(diverge_at=1), raise_exception_on_physics_error=False)
    env.reset()
    assert env.step(np.zeros(2)).last()
    assert env.step(np.zeros(2)).first()
    assert np.isfinite(env.physics.data.qpos).all()
    assert env.step(np.zeros(2)).last()


def test_physics_error_during_episode_leaves_next_episode_unaffected():
    task = Diverges(diverge_at=1)
    env = composer.Environment(task, raise_exception_on_physics_error=False, random_state=0)
    env.reset()
    env.step(np.zeros(2))
    task.diverge_at = -1
    env.step(np.zeros(2))
    assert env.step(np.zeros(2)).mid()
    assert np.isfinite(env.physics.bind(task.box.root_body).mass)


def test_composer_reexports_mjcf_physics_error():
    assert composer.PhysicsError is mjcf.PhysicsError
