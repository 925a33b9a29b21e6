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


class RecordsAfterStep(Diverges):
    def __init__(self, diverge_at):
        super().__init__(diverge_at)
        self.after_step_calls = []

    def after_step(self, physics, random_state):
        self.after_step_calls.append((physics.model.nbody, random_state))


def test_divergence_is_logged_and_after_step_gets_the_physics_and_random_state(caplog):
    task = RecordsAfterStep(diverge_at=1)
    env = composer.Environment(task, raise_exception_on_physics_error=False)
    env.reset()
    with caplog.at_level(logging.WARNING):
        assert env.step(np.zeros(2)).last()
    assert any(
        r.getMessage().startswith("Physics error, ending the episode: Physics state is invalid")
        for r in caplog.records
    )
    ((nbody, random_state),) = task.after_step_calls
    assert nbody == env.physics.model.nbody and random_state is env.random_state


class DivergesAfterCompile(Diverges):
    """Its after_compile hook records its arguments and makes the physics diverge."""

    def __init__(self):
        super().__init__(diverge_at=None)
        self.after_compile_calls = []

    def after_compile(self, physics, random_state):
        self.after_compile_calls.append((physics.model.nbody, random_state))
        physics.data.qpos[:] = np.nan
        physics.step()


def test_a_divergence_in_after_compile_is_logged_and_the_episode_still_starts(caplog):
    task = DivergesAfterCompile()
    with caplog.at_level(logging.WARNING):
        env = composer.Environment(task)
    assert any(
        r.getMessage().startswith("Physics error in after_compile hooks: Physics state is invalid")
        for r in caplog.records
    )
    ((nbody, random_state),) = task.after_compile_calls
    assert nbody == env.physics.model.nbody and random_state is env.random_state
    assert env.reset().first()
