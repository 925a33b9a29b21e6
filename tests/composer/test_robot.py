"""composer.Robot: actuators and applying actions."""

import numpy as np
import pytest
from composer_scene import ReachTask

import composer


def test_apply_action_writes_the_robots_actuator_controls():
    task = ReachTask()
    env = composer.Environment(task)
    env.reset()
    task.arm.apply_action(env.physics, np.array([0.3, 0.4]), env.random_state)
    np.testing.assert_array_equal(env.physics.bind(task.arm.actuators).ctrl, [0.3, 0.4])


def test_robot_without_actuators_cannot_be_instantiated():
    class NoActuators(composer.Robot):
        def _build(self):
            pass

        @property
        def mjcf_model(self):
            return None

    with pytest.raises(TypeError, match="actuators"):
        NoActuators()
