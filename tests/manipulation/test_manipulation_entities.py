"""The arm, hand, props and arena as composer entities: names, attachment, observables."""

import mujoco
import numpy as np
import pytest

import composer
import mjcf
from manipulation.arenas import TableArena
from manipulation.arms import JacoArm
from manipulation.hands import JacoHand
from manipulation.props import BoxWithSites, Cradle, Duplo2x4, LargeBox, Pedestal


class _Scene(composer.Task):
    """A table with the arm (hand on its wrist) and whatever entities a test adds."""

    def __init__(self):
        self.arena = TableArena()
        self.arm = JacoArm()
        self.hand = JacoHand()
        self.arm.attach(self.hand)
        self.arena.attach_offset(self.arm, (0.0, 0.4, 0.0))
        self.arm.observables.enable_all()
        self.hand.observables.enable_all()

    @property
    def root_entity(self):
        return self.arena

    def get_reward(self, physics):
        return 0.0


def _physics(scene):
    return mjcf.Physics.from_mjcf_model(scene.arena.mjcf_model)


def _observe(entity, name, physics):
    return np.asarray(getattr(entity.observables, name)(physics))


def test_arm_and_hand_are_named_as_the_suite_expects():
    scene = _Scene()
    assert scene.arm.mjcf_model.model == "jaco_arm"
    assert scene.hand.tool_center_point.full_identifier == "jaco_arm/jaco_hand/pinch_site"
    assert [joint.full_identifier for joint in scene.arm.joints] == [
        f"jaco_arm/joint_{i}" for i in range(1, 7)
    ]


def test_attach_mounts_the_hand_at_the_wrist_site():
    scene = _Scene()
    physics = _physics(scene)
    np.testing.assert_allclose(
        physics.bind(scene.hand.root_body).xpos, physics.bind(scene.arm.wrist_site).xpos
    )


def test_arm_actuators_are_velocity_servos_with_the_jaco_bounds():
    physics = _physics(_Scene())
    arm = JacoArm()
    assert len(arm.actuators) == 6
    ranges = physics.named.model.actuator_ctrlrange
    np.testing.assert_allclose(ranges["jaco_arm/joint_1_velocity"], [-0.6283, 0.6283])
    np.testing.assert_allclose(ranges["jaco_arm/joint_6_velocity"], [-0.8378, 0.8378])
    np.testing.assert_allclose(ranges["jaco_arm/jaco_hand/finger_1_velocity"], [-5.0, 5.0])


def test_arm_joints_pos_is_the_sine_and_cosine_of_each_joint_angle():
    scene = _Scene()
    physics = _physics(scene)
    angles = np.array([0.1, -0.5, 1.2, 2.5, -1.0, 3.0])
    physics.bind(scene.arm.joints).qpos = angles
    observed = _observe(scene.arm, "joints_pos", physics)
    assert observed.shape == (6, 2)
    np.testing.assert_allclose(observed[:, 0], np.sin(angles))
    np.testing.assert_allclose(observed[:, 1], np.cos(angles))


def _split_step_sets_torque_sensors() -> bool:
    """Whether `mj_step2` (which `Physics.step` runs) computes torque sensors: mujoco
    3.5.0's leaves them at zero; `mj_forward` at the same state gives the true reading."""
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><option integrator="implicitfast"/><worldbody><body>'
        '<joint name="hinge" axis="0 1 0" damping="1"/><site name="pivot"/>'
        '<geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05" mass="1"/></body>'
        '</worldbody><actuator><velocity joint="hinge" kv="100"/></actuator>'
        '<sensor><torque site="pivot"/></sensor></mujoco>'
    )
    data = mujoco.MjData(model)
    for _ in range(200):
        mujoco.mj_step2(model, data)
        mujoco.mj_step1(model, data)
    stepped = data.sensordata.copy()
    mujoco.mj_forward(model, data)
    return bool(np.allclose(stepped, data.sensordata, rtol=0.01))


@pytest.mark.skipif(
    not _split_step_sets_torque_sensors(),
    reason=f"mujoco {mujoco.__version__}'s mj_step2 leaves torque sensors at zero "
    "(a MuJoCo bug of 3.5.0, fixed in 3.6.0)",
)
def test_arm_joints_torque_matches_the_servo_torques_when_the_arm_holds_still():
    scene = _Scene()
    physics = _physics(scene)
    for _ in range(500):
        physics.step()
    torque = _observe(scene.arm, "joints_torque", physics)
    servo = physics.bind(scene.arm.actuators).force
    # Joint 2 carries the weight of the whole arm: a torque far from zero.
    assert abs(servo[1]) > 1.0
    np.testing.assert_allclose(torque, servo, atol=0.05 * np.abs(servo).max())


def test_arm_joint_observables_name_the_joints_and_sensors_they_read():
    arm = JacoArm()
    joints = [f"joint_{i}" for i in range(1, 7)]
    assert [joint.name for joint in arm.observables.joints_pos.joints] == joints
    assert [joint.name for joint in arm.observables.joints_torque.joints] == joints
    sensors = [sensor.name for sensor in arm.observables.joints_torque.sensors]
    assert sensors == [f"{joint}_torque" for joint in joints]


def test_hand_observes_its_finger_joints_and_the_pinch_site_pose():
    scene = _Scene()
    physics = _physics(scene)
    physics.bind(scene.hand.joints).qpos = [0.2, 0.3, 0.4]
    physics.forward()
    np.testing.assert_allclose(_observe(scene.hand, "joints_pos", physics), [0.2, 0.3, 0.4])
    pinch = physics.named.data.site_xpos["jaco_arm/jaco_hand/pinch_site"]
    np.testing.assert_allclose(_observe(scene.hand, "pinch_site_pos", physics), pinch)
    assert _observe(scene.hand, "pinch_site_rmat", physics).shape == (9,)


def test_hand_set_grasp_moves_the_fingers_between_open_and_closed():
    scene = _Scene()
    physics = _physics(scene)
    scene.hand.set_grasp(physics, [0.0, 0.5, 1.0])
    np.testing.assert_allclose(physics.bind(scene.hand.joints).qpos, [0.0, 0.5, 1.0])
    with pytest.raises(ValueError, match="close_factors"):
        scene.hand.set_grasp(physics, 1.5)


def test_free_brick_observes_the_pose_it_was_given():
    scene = _Scene()
    brick = Duplo2x4()
    scene.arena.add_free_entity(brick)
    physics = _physics(scene)
    quaternion = np.array([np.cos(0.3), 0.0, 0.0, np.sin(0.3)])
    brick.set_pose(physics, position=[0.05, -0.02, 0.0], quaternion=quaternion)
    physics.forward()
    np.testing.assert_allclose(_observe(brick, "position", physics), [0.05, -0.02, 0.0])
    np.testing.assert_allclose(_observe(brick, "orientation", physics), quaternion)


def test_brick_dropped_on_the_table_comes_to_rest_on_its_bottom_face():
    scene = _Scene()
    brick = Duplo2x4()
    scene.arena.add_free_entity(brick)
    physics = _physics(scene)
    brick.set_pose(physics, position=[0.0, -0.1, 0.01])
    for _ in range(500):
        physics.step()
    assert physics.bind(brick.root_body).xpos[2] == pytest.approx(0.0, abs=5e-4)


def test_brick_put_on_a_brick_stays_seated_at_the_brick_height():
    scene = _Scene()
    lower, upper = Duplo2x4(name="lower", easy_align=True), Duplo2x4(name="upper")
    scene.arena.add_free_entity(lower)
    scene.arena.add_free_entity(upper)
    physics = _physics(scene)
    lower.set_pose(physics, position=[0.0, -0.1, 0.0])
    upper.set_pose(physics, position=[0.0, -0.1, Duplo2x4.HEIGHT + 0.002])
    for _ in range(500):
        physics.step()
    np.testing.assert_allclose(
        physics.bind(upper.root_body).xpos, [0.0, -0.1, Duplo2x4.HEIGHT], atol=1e-3
    )


def test_boxes_have_a_centre_site_and_eight_corner_sites():
    for box in (BoxWithSites(), LargeBox()):
        assert box.centre.name == "centre"
        assert len(box.vertices) == 8
    assert LargeBox().geom.size[0] == pytest.approx(LargeBox.HALF_SIZE)


def test_pedestal_position_is_its_top_wherever_it_is_put():
    scene = _Scene()
    pedestal = Pedestal()
    pedestal.attach(Cradle())
    scene.arena.attach(pedestal)
    physics = _physics(scene)
    pedestal.set_pose(physics, position=[0.05, 0.02, 0.12])
    physics.forward()
    np.testing.assert_allclose(_observe(pedestal, "position", physics), [0.05, 0.02, 0.12])


def test_arena_camera_lookup_names_the_missing_camera():
    arena = TableArena(cameras=("front_close",))
    assert arena.camera("front_close").name == "front_close"
    with pytest.raises(ValueError, match="no camera named 'top_down'"):
        arena.camera("top_down")
