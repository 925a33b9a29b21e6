"""Physics of the manipulation models, checked with raw `mujoco` (no framework).

Scenes are assembled with `mujoco.MjSpec.attach`, using the same prefixes the framework
gives them ('jaco_arm/', 'jaco_arm/jaco_hand/'), and driven at the suite's timing: a
0.04 s control step of 20 physics steps of 0.002 s.
"""

import mujoco
import numpy as np
import pytest

from manipulation.models import arena, arm, constants, hand, props

_PINCH_SITE = "jaco_arm/jaco_hand/pinch_site"
_ARM_JOINTS = tuple(f"jaco_arm/{name}" for name in arm.JOINT_NAMES)
_SUBSTEPS = constants.SUBSTEPS_PER_CONTROL_STEP
_CONTROL_DT = constants.CONTROL_TIMESTEP
# The pads reach PAD_LENGTH / 2 below the pinch site: grasp 3 mm above the table.
_GRASP_HEIGHT = constants.PAD_LENGTH / 2 + 0.003


def _add_brick(root, name, pos, yaw, free, rgba, easy_align):
    quat = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    body = root.worldbody.add_body(name=name, pos=list(pos), quat=quat)
    if free:
        body.add_freejoint()
    brick = mujoco.MjSpec.from_string(props.duplo_brick_xml(rgba=rgba, easy_align=easy_align))
    root.attach(brick, prefix=f"{name}/", frame=body.add_frame())


def _scene(free_bricks=(), static_bricks=(), robot=True, easy_align=False):
    """Arena, optionally the arm with the hand on its wrist, and bricks (x, y, z, yaw)."""
    root = mujoco.MjSpec.from_string(arena.table_arena_xml())
    if robot:
        arm_spec = mujoco.MjSpec.from_string(arm.jaco_arm_xml())
        hand_spec = mujoco.MjSpec.from_string(hand.jaco_hand_xml())
        arm_spec.attach(hand_spec, prefix="jaco_hand/", site=arm_spec.site(arm.WRIST_SITE_NAME))
        base = root.worldbody.add_frame(pos=list(constants.ARM_OFFSET))
        root.attach(arm_spec, prefix="jaco_arm/", frame=base)
    for i, (x, y, z, yaw) in enumerate(free_bricks):
        _add_brick(root, f"brick_{i}", (x, y, z), yaw, True, (0.8, 0.1, 0.1, 1), easy_align)
    for i, (x, y, z, yaw) in enumerate(static_bricks):
        _add_brick(root, f"static_{i}", (x, y, z), yaw, False, (0.1, 0.3, 0.8, 1), easy_align)
    model = root.compile()
    return model, mujoco.MjData(model)


def _down(yaw=0.0):
    """Rotation of the pinch site pointing down, its y axis (the grip axis) at `yaw`."""
    cos, sin = np.cos(yaw), np.sin(yaw)
    return np.array([[-sin, cos, 0.0], [cos, sin, 0.0], [0.0, 0.0, -1.0]]).T


class _Arm:
    """Addresses of the arm in a compiled scene, and its pinch-site kinematics."""

    def __init__(self, model, data):
        self.model, self.data = model, data
        self.site = model.site(_PINCH_SITE).id
        self.qpos = np.array([model.joint(j).qposadr[0] for j in _ARM_JOINTS])
        self.dofs = np.array([model.joint(j).dofadr[0] for j in _ARM_JOINTS])
        self.limited = [model.joint(j).limited[0] for j in _ARM_JOINTS]
        self.ranges = [model.joint(j).range for j in _ARM_JOINTS]
        self.speed_limits = model.actuator_ctrlrange[: len(_ARM_JOINTS), 1]
        self._jacp = np.zeros((3, model.nv))
        self._jacr = np.zeros((3, model.nv))

    @property
    def pinch_pos(self):
        return self.data.site_xpos[self.site]

    def pose_error(self, target_pos, target_rot):
        rot = self.data.site_xmat[self.site].reshape(3, 3)
        rot_error = 0.5 * sum(np.cross(rot[:, i], target_rot[:, i]) for i in range(3))
        return np.concatenate([target_pos - self.pinch_pos, rot_error])

    def jacobian(self):
        mujoco.mj_jacSite(self.model, self.data, self._jacp, self._jacr, self.site)
        return np.vstack([self._jacp, self._jacr])[:, self.dofs]

    def solve_ik(self, target_pos, target_rot, iterations=200, damping=1e-3):
        """Damped least squares on the arm joints from the model's default configuration."""
        self.data.qpos[self.qpos] = self.model.qpos0[self.qpos]
        for _ in range(iterations):
            mujoco.mj_kinematics(self.model, self.data)
            mujoco.mj_comPos(self.model, self.data)
            error = self.pose_error(target_pos, target_rot)
            if np.linalg.norm(error) < 1e-6:
                break
            jac = self.jacobian()
            step = jac.T @ np.linalg.solve(jac @ jac.T + damping * np.eye(6), error)
            self.data.qpos[self.qpos] += step
            for i, address in enumerate(self.qpos):
                if self.limited[i]:
                    self.data.qpos[address] = np.clip(self.data.qpos[address], *self.ranges[i])
        mujoco.mj_forward(self.model, self.data)
        return self.pose_error(target_pos, target_rot)

    def velocity_command(self, target_pos, target_rot, gain=8.0):
        """Joint velocities that move the pinch site towards a pose, within the bounds."""
        jac = self.jacobian()
        twist = gain * self.pose_error(target_pos, target_rot)
        qvel = jac.T @ np.linalg.solve(jac @ jac.T + 1e-4 * np.eye(6), twist)
        return qvel / max(1.0, np.max(np.abs(qvel) / self.speed_limits))


def _control_step(model, data, ctrl):
    data.ctrl[:] = ctrl
    mujoco.mj_step(model, data, nstep=_SUBSTEPS)


def _raised_warnings(data):
    return {mujoco.mjtWarning(i).name: w.number for i, w in enumerate(data.warning) if w.number}


def test_arm_model_compiles_alone_with_velocity_actuators_at_jaco_speed_limits():
    model = mujoco.MjModel.from_xml_string(arm.jaco_arm_xml())

    names = [model.actuator(i).name for i in range(model.nu)]
    bounds = model.actuator_ctrlrange

    assert names == list(arm.ACTUATOR_NAMES)
    np.testing.assert_allclose(bounds[:3], [[-0.6283, 0.6283]] * 3)
    np.testing.assert_allclose(bounds[3:], [[-0.8378, 0.8378]] * 3)
    assert model.nsensor == 6


def test_hand_model_compiles_alone_with_three_finger_actuators_and_pinch_site():
    model = mujoco.MjModel.from_xml_string(hand.jaco_hand_xml())

    np.testing.assert_allclose(model.actuator_ctrlrange, [[-5.0, 5.0]] * 3)
    assert model.site(hand.PINCH_SITE_NAME).id >= 0
    assert model.njnt == 3


@pytest.mark.parametrize(
    "xml",
    [
        arena.table_arena_xml(),
        props.duplo_brick_xml(),
        props.box_with_sites_xml(),
        props.large_box_xml(),
        props.pedestal_xml(),
        props.cradle_xml(),
    ],
    ids=["arena", "brick", "box", "large_box", "pedestal", "cradle"],
)
def test_scenery_models_compile_alone(xml):
    model = mujoco.MjModel.from_xml_string(xml)

    assert model.ngeom > 0


@pytest.mark.parametrize("target", [(0.0, 0.0, 0.3), (0.1, -0.1, 0.2), (-0.15, 0.1, 0.45)])
def test_zero_velocity_command_holds_pinch_site_within_1cm_for_2s(target):
    model, data = _scene()
    robot = _Arm(model, data)
    robot.solve_ik(np.array(target), _down())
    start = robot.pinch_pos.copy()

    for _ in range(int(2.0 / _CONTROL_DT)):
        _control_step(model, data, np.zeros(model.nu))

    assert np.linalg.norm(robot.pinch_pos - start) < 0.01


def test_ik_from_default_pose_puts_pinch_site_pointing_down_on_targets_across_workspace():
    model, data = _scene()
    robot = _Arm(model, data)
    span = (-0.15, 0.0, 0.15)
    grid = [(x, y, z) for x in span for y in span for z in (0.02, 0.2, 0.4)]

    misses = []
    for target in grid:
        error = robot.solve_ik(np.array(target), _down(yaw=0.5))
        if np.linalg.norm(error[:3]) > 1e-3 or np.linalg.norm(error[3:]) > 1e-2:
            misses.append((target, error.round(4)))

    assert misses == []


def _grasp_and_lift(x, y, yaw):
    """Scripted pick-up of a brick at (x, y, yaw); returns its lift over the final 1 s hold."""
    model, data = _scene(free_bricks=[(x, y, 0.0, yaw)])
    robot = _Arm(model, data)
    brick = model.body("brick_0").id
    robot.solve_ik(np.array([0.0, 0.0, 0.3]), _down())
    start = data.xpos[brick].copy()
    # The grip is symmetric under a half turn: turn the hand by less than 90 degrees.
    grip = _down((yaw + np.pi / 2) % np.pi - np.pi / 2)
    open_fingers, close_fingers = -2.0, 3.0
    # (duration in s, pinch-site target, finger velocity command)
    above, grasp, lifted = (start + [0.0, 0.0, dz] for dz in (0.12, _GRASP_HEIGHT, 0.25))
    phases = [
        (1.5, above, open_fingers),
        (1.2, grasp, open_fingers),
        (0.6, grasp, close_fingers),
        (1.5, lifted, close_fingers),
    ]
    ctrl = np.zeros(model.nu)
    for duration, target, fingers in phases:
        for _ in range(round(duration / _CONTROL_DT)):
            ctrl[:6] = robot.velocity_command(target, grip)
            ctrl[6:] = fingers
            _control_step(model, data, ctrl)
    lifts = []
    for _ in range(round(1.0 / _CONTROL_DT)):
        ctrl[:6] = robot.velocity_command(lifted, grip)
        _control_step(model, data, ctrl)
        lifts.append(data.xpos[brick][2] - start[2])
    return min(lifts)


def test_scripted_grasp_lifts_brick_over_10cm_and_holds_it_for_1s_at_4_of_5_positions():
    placements = [
        (0.0, 0.0, 0.0),
        (0.1, -0.1, 0.5),
        (-0.1, 0.1, -0.7),
        (0.1, 0.1, 1.2),
        (-0.1, -0.1, 2.0),
    ]

    lifts = [_grasp_and_lift(*placement) for placement in placements]

    assert sum(lift > 0.1 for lift in lifts) >= 4, lifts


def test_brick_placed_on_another_brick_stays_seated_for_2s():
    seated_height = constants.BRICK_HEIGHT
    model, data = _scene(
        free_bricks=[(0.0, 0.0, 0.0, 0.3), (0.0, 0.0, seated_height + 5e-4, 0.3)], robot=False
    )
    top = model.body("brick_1").id
    mujoco.mj_forward(model, data)
    start = data.xpos[top].copy()

    mujoco.mj_step(model, data, nstep=1000)

    np.testing.assert_allclose(data.xpos[top][:2], start[:2], atol=1e-3)
    assert abs(data.xpos[top][2] - seated_height) < 1e-3


def _push_sideways(on_brick):
    """Pushes a brick with 0.5 N along x for 1 s; returns how far it moved."""
    base = [(0.0, 0.0, 0.0, 0.0)] if on_brick else []
    height = constants.BRICK_HEIGHT + 5e-4 if on_brick else 0.0
    model, data = _scene(free_bricks=[(0.0, 0.0, height, 0.0)], static_bricks=base, robot=False)
    brick = model.body("brick_0").id
    mujoco.mj_forward(model, data)
    start = data.xpos[brick].copy()
    data.xfrc_applied[brick, :3] = (0.5, 0.0, 0.0)
    mujoco.mj_step(model, data, nstep=500)
    return np.linalg.norm(data.xpos[brick][:2] - start[:2])


def test_sideways_push_that_slides_a_brick_on_the_table_leaves_a_stacked_brick_in_place():
    on_table = _push_sideways(on_brick=False)
    stacked = _push_sideways(on_brick=True)

    assert on_table > 0.05
    assert stacked < 1e-3


@pytest.mark.parametrize("steps_per_action", [1, 25])
def test_random_velocity_actions_for_10s_raise_no_mujoco_warnings(steps_per_action):
    bricks = [(0.0, 0.0, 0.0, 0.0), (0.08, -0.05, 0.0, 1.0), (-0.06, 0.05, 0.0, 2.0)]
    model, data = _scene(free_bricks=bricks)
    robot = _Arm(model, data)
    robot.solve_ik(np.array([0.0, 0.0, 0.15]), _down())
    rng = np.random.default_rng(steps_per_action)
    low, high = model.actuator_ctrlrange.T

    for step in range(250):
        if step % steps_per_action == 0:
            ctrl = rng.uniform(low, high)
        _control_step(model, data, ctrl)

    assert _raised_warnings(data) == {}
    assert np.isfinite(data.qpos).all()


def test_joint_torque_sensors_projected_on_joint_axes_equal_actuator_torques_at_rest():
    model, data = _scene()
    robot = _Arm(model, data)
    robot.solve_ik(np.array([0.1, -0.1, 0.2]), _down(0.3))
    mujoco.mj_step(model, data, nstep=500)
    sensors = [f"jaco_arm/{name}" for name in arm.TORQUE_SENSOR_NAMES]
    readings = np.array([data.sensor(name).data for name in sensors])
    axes = model.jnt_axis[[model.joint(j).id for j in _ARM_JOINTS]]

    torques = np.einsum("ij,ij->i", readings, axes)

    np.testing.assert_allclose(torques, data.actuator_force[:6], atol=0.05)
    assert abs(torques[1]) > 1.0  # the shoulder carries the arm's weight


def test_front_close_camera_sees_a_brick_at_the_workspace_centre():
    model, data = _scene(free_bricks=[(0.0, -0.05, 0.0, 0.0)])
    _Arm(model, data).solve_ik(np.array([0.15, 0.15, 0.4]), _down())
    with mujoco.Renderer(model, 84, 84) as renderer:
        renderer.update_scene(data, camera="front_close")
        image = renderer.render().astype(int)

    red = (image[..., 0] > 120) & (image[..., 1] < 60) & (image[..., 2] < 60)

    assert red.sum() >= 6


def test_arena_adds_only_the_cameras_asked_for():
    model = mujoco.MjModel.from_xml_string(arena.table_arena_xml(cameras=["front_close"]))

    assert [model.camera(i).name for i in range(model.ncam)] == ["front_close"]


def test_arena_with_unknown_camera_is_a_value_error_naming_the_argument():
    with pytest.raises(ValueError, match="'cameras'.*front_close.*'back'"):
        arena.table_arena_xml(cameras=["back"])


@pytest.mark.parametrize("rgba", [(1.0, 0.0, 0.0), (1.0, 0.0, 0.0, 2.0)])
def test_brick_colour_other_than_4_numbers_in_0_1_is_a_value_error(rgba):
    with pytest.raises(ValueError, match="duplo_brick_xml argument 'rgba'"):
        props.duplo_brick_xml(rgba=rgba)


def test_box_with_non_positive_size_is_a_value_error_naming_half_size():
    with pytest.raises(ValueError, match="box_with_sites_xml argument 'half_size'.*got 0"):
        props.box_with_sites_xml(half_size=0)


def _drop_off_seat(easy_align):
    """Drops a brick 2 mm off-centre onto a static brick; returns its final offset."""
    stud_height = constants.EASY_ALIGN_STUD_HEIGHT if easy_align else constants.STUD_HEIGHT
    drop_height = constants.BRICK_HEIGHT + stud_height + 1e-3
    model, data = _scene(
        free_bricks=[(0.002, 0.0, drop_height, 0.0)],
        static_bricks=[(0.0, 0.0, 0.0, 0.0)],
        robot=False,
        easy_align=easy_align,
    )
    mujoco.mj_step(model, data, nstep=1000)
    return data.xpos[model.body("brick_0").id] - (0.0, 0.0, constants.BRICK_HEIGHT)


def test_easy_align_studs_guide_a_brick_dropped_2mm_off_into_its_seat():
    plain = _drop_off_seat(easy_align=False)
    easy = _drop_off_seat(easy_align=True)

    assert plain[2] > 1e-3  # left resting on the studs
    np.testing.assert_allclose(easy, 0.0, atol=5e-4)
