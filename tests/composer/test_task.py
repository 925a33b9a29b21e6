"""composer.Task and composer.NullTask: timing, action spec, observables and defaults."""

import abc
import collections

import numpy as np
import pytest
from composer_scene import Arm, Floor, ReachTask

import composer
import mjcf
from composer.observation import observable


def _bare_task():
    return composer.NullTask(composer.ModelWrapperEntity(mjcf.RootElement(model="bare")))


def test_physics_timestep_is_mujoco_default_when_option_is_unset():
    task = _bare_task()
    assert task.physics_timestep == 0.002
    assert task.control_timestep == 0.002
    assert task.physics_steps_per_control_step == 1


def test_set_timesteps_sets_option_timestep_and_steps_per_control_step():
    task = _bare_task()
    task.set_timesteps(control_timestep=0.05, physics_timestep=0.005)
    assert task.root_entity.mjcf_model.option.timestep == 0.005
    assert task.control_timestep == 0.05
    assert task.physics_steps_per_control_step == 10


def test_set_timesteps_accepts_ratios_within_rounding_error():
    task = _bare_task()
    task.set_timesteps(control_timestep=0.3, physics_timestep=0.1)
    assert task.physics_steps_per_control_step == 3


def test_set_timesteps_rejects_non_integer_ratio_and_names_both_values():
    task = _bare_task()
    with pytest.raises(ValueError, match=r"integer multiple.*0\.025.*0\.01"):
        task.set_timesteps(control_timestep=0.025, physics_timestep=0.01)
    assert task.root_entity.mjcf_model.option.timestep is None


def test_set_timesteps_rejects_control_step_shorter_than_physics_step():
    with pytest.raises(ValueError, match="integer multiple"):
        _bare_task().set_timesteps(control_timestep=0.001, physics_timestep=0.002)


def test_set_timesteps_rejects_non_positive_timestep():
    with pytest.raises(ValueError, match="physics_timestep: expected a positive"):
        _bare_task().set_timesteps(control_timestep=0.01, physics_timestep=0.0)


def test_control_timestep_setter_checks_divisibility():
    task = _bare_task()
    task.control_timestep = 0.01
    assert task.physics_steps_per_control_step == 5
    with pytest.raises(ValueError, match="integer multiple"):
        task.control_timestep = 0.003


def test_physics_timestep_setter_checks_against_control_timestep():
    task = _bare_task()
    task.control_timestep = 0.01
    task.physics_timestep = 0.001
    assert task.physics_steps_per_control_step == 10
    with pytest.raises(ValueError, match="integer multiple"):
        task.physics_timestep = 0.003


def test_timestep_access_before_root_entity_exists_is_a_clear_error():
    class EarlyTask(composer.Task):
        def __init__(self):
            self.set_timesteps(0.02, 0.002)
            self._arena = Floor()

        @property
        def root_entity(self):
            return self._arena

        def get_reward(self, physics):
            return 0.0

    with pytest.raises(AttributeError, match="set_timesteps needs root_entity"):
        EarlyTask()


def test_task_without_root_entity_or_get_reward_cannot_be_instantiated():
    class NoReward(composer.Task):
        @property
        def root_entity(self):
            return Floor()

    class NoRoot(composer.Task):
        def get_reward(self, physics):
            return 0.0

    with pytest.raises(TypeError, match="get_reward"):
        NoReward()
    with pytest.raises(TypeError, match="root_entity"):
        NoRoot()


def test_action_spec_bounds_come_from_ctrlrange_and_names_are_tab_joined():
    task = ReachTask()
    task.arena.mjcf_model.actuator.add(
        "motor", name="free_motor", joint=task.arm.joints[0], ctrllimited=False
    )
    physics = mjcf.Physics.from_mjcf_model(task.root_entity.mjcf_model)
    spec = task.action_spec(physics)
    assert spec.shape == (3,)
    assert spec.dtype == np.float64
    np.testing.assert_array_equal(spec.minimum, [-np.inf, -1, -1])
    np.testing.assert_array_equal(spec.maximum, [np.inf, 1, 1])
    assert spec.name == "free_motor\tarm/shoulder_motor\tarm/elbow_motor"


def test_observables_put_task_observables_first_then_entities_with_scoped_keys():
    class WithTaskObservable(ReachTask):
        @property
        def task_observables(self):
            return collections.OrderedDict(time=observable.Generic(lambda physics: 0.0))

    keys = list(WithTaskObservable().observables)
    assert keys[0] == "time"
    assert "arm/tip_position" in keys
    assert "box/position" in keys


def test_observables_include_disabled_entity_observables():
    task = ReachTask()
    assert not task.observables["arm/joint_velocities"].enabled


def test_iter_entities_walks_the_root_entity_tree():
    task = ReachTask()
    assert list(task.iter_entities()) == [task.arena, task.arm, task.box]


def test_default_before_step_writes_action_into_controls():
    task = ReachTask()
    physics = mjcf.Physics.from_mjcf_model(task.root_entity.mjcf_model)
    task.before_step(physics, np.array([0.25, -0.5]), np.random.RandomState(0))
    np.testing.assert_array_equal(physics.bind(task.arm.actuators).ctrl, [0.25, -0.5])


def test_defaults_never_terminate_discount_one_and_no_custom_specs():
    task = ReachTask()
    assert task.should_terminate_episode(None) is False
    assert _bare_task().get_discount(None) == 1.0
    assert task.get_reward_spec() is None
    assert task.get_discount_spec() is None


def test_null_task_gives_zero_reward_and_wraps_its_root_entity():
    arm = Arm()
    task = composer.NullTask(arm)
    assert task.root_entity is arm
    assert task.get_reward(None) == 0.0


def test_subclass_listing_abc_abc_before_task_runs_in_an_environment():
    class RewardOne(abc.ABC, composer.NullTask):
        def get_reward(self, physics):
            return 1.0

    task = RewardOne(composer.ModelWrapperEntity(mjcf.RootElement(model="bare")))
    env = composer.Environment(task)
    env.reset()
    assert env.step([]).reward == 1.0
