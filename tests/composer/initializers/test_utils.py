"""composer.initializers.utils.JointStaticIsolator: other joints end where they started."""

import numpy as np
import pytest

import mjcf
from composer.initializers import utils


def _arm_and_ball():
    """A two-joint arm, and a free ball in an attached model with a joint of its own."""
    model = mjcf.RootElement(model="scene")
    upper = model.worldbody.add("body", name="upper")
    shoulder = upper.add("joint", name="shoulder", axis=[0, 1, 0])
    upper.add("geom", type="capsule", fromto=[0, 0, 0, 0, 0, 0.3], size=[0.03])
    lower = upper.add("body", name="lower", pos=[0, 0, 0.3])
    elbow = lower.add("joint", name="elbow", axis=[0, 1, 0])
    lower.add("geom", type="capsule", fromto=[0, 0, 0, 0, 0, 0.3], size=[0.03])
    prop = mjcf.RootElement(model="prop")
    prop.worldbody.add("geom", type="box", size=[0.05, 0.05, 0.05])
    ball = prop.worldbody.add("body", name="ball")
    ball.add("joint", name="spin", axis=[0, 0, 1])
    ball.add("geom", type="sphere", size=[0.05])
    frame = model.attach(prop)
    frame.pos = [1.0, 0.0, 0.5]
    ball_joint = frame.add("freejoint")
    physics = mjcf.Physics.from_mjcf_model(model)
    return physics, shoulder, elbow, ball_joint, prop.find("joint", "spin")


def test_joints_outside_the_set_get_their_construction_time_state_back():
    physics, shoulder, elbow, ball, spin = _arm_and_ball()
    physics.bind(elbow).qpos = 0.4
    physics.bind(elbow).qvel = -1.0
    isolator = utils.JointStaticIsolator(physics, [shoulder])
    physics.bind(elbow).qpos = 1.2
    physics.bind(ball).qvel = [1, 2, 3, 0, 0, 0]
    physics.bind(spin).qpos = 0.5
    with isolator:
        physics.bind(shoulder).qpos = 0.7
        physics.step(5)
    assert physics.bind(elbow).qpos[0] == 0.4
    assert physics.bind(elbow).qvel[0] == -1.0
    assert physics.bind(spin).qpos[0] == 0.0
    np.testing.assert_array_equal(physics.bind(ball).qvel, np.zeros(6))
    np.testing.assert_array_equal(physics.bind(ball).qpos, [1.0, 0.0, 0.5, 1, 0, 0, 0])
    assert physics.bind(shoulder).qpos[0] != 0.0


def test_a_single_joint_element_is_accepted_and_state_is_restored_after_an_error():
    physics, shoulder, elbow, _, _ = _arm_and_ball()
    with pytest.raises(RuntimeError, match="inside"):
        with utils.JointStaticIsolator(physics, shoulder):
            physics.bind(elbow).qpos = 2.0
            raise RuntimeError("inside")
    assert physics.bind(elbow).qpos[0] == 0.0


def test_isolating_every_joint_restores_nothing():
    physics, shoulder, elbow, ball, spin = _arm_and_ball()
    with utils.JointStaticIsolator(physics, [shoulder, elbow, ball, spin]):
        physics.bind(elbow).qpos = 0.3
    assert physics.bind(elbow).qpos[0] == 0.3


def test_joints_of_two_models_are_refused_naming_both():
    physics, shoulder, _, _, _ = _arm_and_ball()
    other = mjcf.RootElement(model="other")
    stray = other.worldbody.add("body").add("joint", name="stray")
    with pytest.raises(ValueError, match="different models.*'scene'.*'other'"):
        utils.JointStaticIsolator(physics, [shoulder, stray])


def test_empty_or_non_joint_input_is_refused():
    physics, shoulder, _, _, _ = _arm_and_ball()
    with pytest.raises(ValueError, match="at least one joint"):
        utils.JointStaticIsolator(physics, [])
    with pytest.raises(ValueError, match="expected joint elements.*upper"):
        utils.JointStaticIsolator(physics, [shoulder.parent])
