"""Tests for composer.utils.inverse_kinematics.qpos_from_site_pose on a 6-DOF arm."""

import copy
from unittest import mock

import mujoco
import numpy as np
import pytest

import mjcf
from composer.utils import inverse_kinematics

# A 6-DOF arm: base yaw, shoulder and elbow pitch, then a roll-pitch-roll wrist.
ARM_XML = """
<mujoco>
  <worldbody>
    <body name="base">
      <joint name="yaw" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.04"/>
      <body name="upper_arm" pos="0 0 0.2">
        <joint name="shoulder" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.035"/>
        <body name="forearm" pos="0 0 0.4">
          <joint name="elbow" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 0.35" size="0.03"/>
          <body name="wrist_1" pos="0 0 0.35">
            <joint name="wrist_roll" axis="0 0 1"/>
            <geom type="capsule" fromto="0 0 0 0 0 0.05" size="0.025"/>
            <body name="wrist_2" pos="0 0 0.05">
              <joint name="wrist_pitch" axis="0 1 0"/>
              <geom type="capsule" fromto="0 0 0 0 0 0.05" size="0.025"/>
              <body name="hand" pos="0 0 0.05">
                <joint name="hand_roll" axis="0 0 1"/>
                <geom type="box" size="0.02 0.02 0.02"/>
                <site name="tcp" pos="0 0 0.08"/>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

REACH = 0.2 + 0.4 + 0.35 + 0.05 + 0.05 + 0.08


@pytest.fixture
def physics():
    physics = mjcf.Physics.from_xml_string(ARM_XML)
    physics.data.qpos[:] = 0.1
    physics.forward()
    return physics


def _site_pose(model, qpos):
    """Forward kinematics of the tcp site for `qpos`, computed on separate data."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, data.site_xmat[0])
    return data.site_xpos[0].copy(), quat


def _random_reachable_poses(model, count, seed):
    rng = np.random.default_rng(seed)
    return [_site_pose(model, rng.uniform(-1.5, 1.5, model.nq)) for _ in range(count)]


def test_reaches_reachable_positions_within_1e4_m(physics):
    for target_pos, _ in _random_reachable_poses(physics.model.ptr, 10, seed=0):
        result = inverse_kinematics.qpos_from_site_pose(physics, "tcp", target_pos=target_pos)
        reached, _ = _site_pose(physics.model.ptr, result.qpos)
        assert result.success
        assert np.linalg.norm(reached - target_pos) < 1e-4


def test_reaches_reachable_poses_in_position_and_orientation(physics):
    for target_pos, target_quat in _random_reachable_poses(physics.model.ptr, 10, seed=1):
        result = inverse_kinematics.qpos_from_site_pose(
            physics, "tcp", target_pos=target_pos, target_quat=target_quat, max_steps=200
        )
        reached_pos, reached_quat = _site_pose(physics.model.ptr, result.qpos)
        assert result.success
        assert np.linalg.norm(reached_pos - target_pos) < 1e-4
        assert abs(reached_quat @ target_quat) == pytest.approx(1.0, abs=1e-8)


def test_reaches_orientation_only_target(physics):
    _, target_quat = _random_reachable_poses(physics.model.ptr, 1, seed=2)[0]
    result = inverse_kinematics.qpos_from_site_pose(physics, "tcp", target_quat=target_quat)
    _, reached_quat = _site_pose(physics.model.ptr, result.qpos)
    assert result.success
    assert abs(reached_quat @ target_quat) == pytest.approx(1.0, abs=1e-8)


def test_reports_failure_for_target_beyond_reach(physics):
    result = inverse_kinematics.qpos_from_site_pose(
        physics, "tcp", target_pos=[2 * REACH, 0.0, 0.2]
    )
    assert not result.success
    assert result.err_norm > REACH - 0.1


def test_result_is_a_namedtuple_with_the_documented_fields(physics):
    result = inverse_kinematics.qpos_from_site_pose(physics, "tcp", target_pos=[0.3, 0.2, 0.6])
    assert result._fields == ("qpos", "err_norm", "steps", "success")
    assert result.qpos.shape == (physics.model.nq,)
    assert 0 <= result.steps < 100


def test_default_leaves_physics_untouched(physics):
    before = physics.data.qpos.copy()
    site_before = physics.data.site_xpos.copy()
    inverse_kinematics.qpos_from_site_pose(physics, "tcp", target_pos=[0.3, 0.2, 0.6])
    np.testing.assert_array_equal(physics.data.qpos, before)
    np.testing.assert_array_equal(physics.data.site_xpos, site_before)


def test_inplace_writes_the_solution_into_physics(physics):
    target = np.array([0.3, 0.2, 0.6])
    result = inverse_kinematics.qpos_from_site_pose(physics, "tcp", target_pos=target, inplace=True)
    np.testing.assert_array_equal(physics.data.qpos, result.qpos)
    np.testing.assert_allclose(physics.data.site_xpos[0], target, atol=1e-6)


def test_only_listed_joints_move(physics):
    joints = ["shoulder", "elbow", "wrist_pitch"]
    target, _ = _site_pose(physics.model.ptr, [0.1, 0.5, -0.4, 0.1, 0.3, 0.1])
    result = inverse_kinematics.qpos_from_site_pose(
        physics, "tcp", target_pos=target, joint_names=joints
    )
    assert result.success
    fixed = [0, 3, 5]  # yaw, wrist_roll and hand_roll keep their initial 0.1
    np.testing.assert_array_equal(result.qpos[fixed], 0.1)


def test_requires_a_target(physics):
    with pytest.raises(ValueError) as raised:
        inverse_kinematics.qpos_from_site_pose(physics, "tcp")
    assert str(raised.value) == (
        "qpos_from_site_pose: expected target_pos, target_quat or both, got neither"
    )


def test_unknown_site_is_rejected_by_name(physics):
    with pytest.raises(ValueError, match="no site named 'gripper'"):
        inverse_kinematics.qpos_from_site_pose(physics, "gripper", target_pos=[0, 0, 1])


def test_unknown_joint_is_rejected_by_name(physics):
    with pytest.raises(ValueError, match="no joint named 'knee'"):
        inverse_kinematics.qpos_from_site_pose(
            physics, "tcp", target_pos=[0, 0, 1], joint_names=["elbow", "knee"]
        )


@pytest.mark.parametrize("joint_names", ["elbow", 3, {"elbow": 1}])
def test_joint_names_of_another_type_are_rejected_naming_the_type(physics, joint_names):
    with pytest.raises(ValueError) as raised:
        inverse_kinematics.qpos_from_site_pose(
            physics, "tcp", target_pos=[0, 0, 1], joint_names=joint_names
        )
    assert str(raised.value) == (
        "qpos_from_site_pose: joint_names: expected None or a list, tuple or numpy array of "
        f"joint names, got {type(joint_names)}"
    )


def test_error_messages_are_the_module_constants_dm_control_tests_read(physics):
    # dm_control's own IK tests compare raised messages with these two module constants.
    with pytest.raises(ValueError) as raised:
        inverse_kinematics.qpos_from_site_pose(physics, "tcp", target_pos=[0, 0, 1], joint_names=1)
    assert str(raised.value) == inverse_kinematics._INVALID_JOINT_NAMES_TYPE.format(int)
    with pytest.raises(ValueError) as raised:
        inverse_kinematics.qpos_from_site_pose(physics, "tcp")
    assert str(raised.value) == inverse_kinematics._REQUIRE_TARGET_POS_OR_QUAT


def test_target_of_wrong_shape_is_rejected(physics):
    with pytest.raises(ValueError, match=r"target_pos: expected shape \(3,\), got \(2,\)"):
        inverse_kinematics.qpos_from_site_pose(physics, "tcp", target_pos=[0, 1])


def test_nullspace_method_without_regularization_is_least_squares():
    jac = np.array([[1.0, 0.0], [0.0, 2.0], [0.0, 0.0]])
    step = inverse_kinematics.nullspace_method(jac, np.array([1.0, 2.0, 3.0]))
    np.testing.assert_allclose(step, [1.0, 1.0])


def test_nullspace_method_regularization_shrinks_the_step():
    jac = np.eye(2)
    step = inverse_kinematics.nullspace_method(jac, np.array([1.0, 2.0]), 1.0)
    np.testing.assert_allclose(step, [0.5, 1.0])


def test_running_out_of_steps_logs_a_warning(physics):
    with mock.patch.object(inverse_kinematics.logging, "warning") as warning:
        inverse_kinematics.qpos_from_site_pose(
            physics, "tcp", target_pos=[2 * REACH, 0.0, 0.2], max_steps=3, progress_thresh=np.inf
        )
    warning.assert_called_once()
    assert "Failed to converge after 2 steps" in warning.call_args[0][0] % warning.call_args[0][1:]


def test_nullspace_method_regularization_damps_only_the_diagonal():
    # (J^T J + I) dq = J^T delta with J = [[1, 1], [0, 1]], delta = [1, 2]:
    # [[2, 1], [1, 3]] dq = [1, 3]  ->  dq = [0, 1].
    jac = np.array([[1.0, 1.0], [0.0, 1.0]])
    step = inverse_kinematics.nullspace_method(jac, np.array([1.0, 2.0]), 1.0)
    np.testing.assert_allclose(step, [0.0, 1.0], atol=1e-12)


# --- Exactness: the documented algorithm, run plainly with mj_fwdPosition every iteration ---

BALL_CHAIN_XML = """
<mujoco>
  <worldbody>
    <geom type="plane" size="1 1 0.1" pos="0 0 0.3"/>
    <body name="link_1" pos="0 0 0.3">
      <joint name="ball_1" type="ball"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.02"/>
      <body name="link_2" pos="0 0 0.2">
        <joint name="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.02"/>
        <body name="link_3" pos="0 0 0.2">
          <joint name="ball_2" type="ball"/>
          <geom type="capsule" fromto="0 0 0 0 0 0.1" size="0.02"/>
          <site name="tip" pos="0 0 0.1"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

# The arm standing in a floor plane that cuts its base: the data holds contacts.
ARM_ON_FLOOR_XML = ARM_XML.replace(
    "<worldbody>", '<worldbody><geom type="plane" size="1 1 0.1" pos="0 0 0.1"/>', 1
)


def _reference_ik(
    physics,
    site_name,
    target_pos=None,
    target_quat=None,
    joint_names=None,
    tol=1e-14,
    rot_weight=1.0,
    regularization_threshold=0.1,
    regularization_strength=3e-2,
    max_update_norm=2.0,
    progress_thresh=20.0,
    max_steps=100,
):
    """dm_control's documented damped least squares, with full mj_fwdPosition each step:
    returns (qpos, err_norm, steps, success, data)."""
    model = physics.model.ptr
    data = copy.copy(physics.data.ptr)
    mujoco.mj_fwdPosition(model, data)
    site_id = model.site(site_name).id
    dofs = None
    if joint_names is not None:
        dofs = [
            dof
            for name in joint_names
            for dof in np.flatnonzero(model.dof_jntid == model.joint(name).id)
        ]
    err_norm, steps, success = 0.0, 0, False
    for step in range(max_steps):
        steps = step
        parts, jacobians, err_norm = [], [], 0.0
        if target_pos is not None:
            parts.append(np.asarray(target_pos, float) - data.site_xpos[site_id])
            err_norm += np.linalg.norm(parts[-1])
        if target_quat is not None:
            site_quat, conjugate, difference = np.empty(4), np.empty(4), np.empty(4)
            velocity = np.empty(3)
            mujoco.mju_mat2Quat(site_quat, data.site_xmat[site_id])
            mujoco.mju_negQuat(conjugate, site_quat)
            mujoco.mju_mulQuat(difference, np.asarray(target_quat, float), conjugate)
            mujoco.mju_quat2Vel(velocity, difference, 1)
            parts.append(velocity)
            err_norm += np.linalg.norm(velocity) * rot_weight
        if err_norm < tol:
            success = True
            break
        jacp, jacr = np.empty((3, model.nv)), np.empty((3, model.nv))
        mujoco.mj_jacSite(model, data, jacp, jacr, site_id)
        if target_pos is not None:
            jacobians.append(jacp)
        if target_quat is not None:
            jacobians.append(jacr)
        jac, err = np.vstack(jacobians), np.concatenate(parts)
        jac_joints = jac if dofs is None else jac[:, dofs]
        hessian = jac_joints.T.dot(jac_joints)
        gradient = jac_joints.T.dot(err)
        if err_norm > regularization_threshold and regularization_strength > 0:
            hessian += np.eye(len(hessian)) * regularization_strength
            update = np.linalg.solve(hessian, gradient)
        else:
            update = np.linalg.lstsq(hessian, gradient, rcond=-1)[0]
        update_norm = np.linalg.norm(update)
        with np.errstate(divide="ignore", invalid="ignore"):
            if err_norm / update_norm > progress_thresh:
                break
        if update_norm > max_update_norm:
            update *= max_update_norm / update_norm
        update_nv = np.zeros(model.nv)
        update_nv[slice(None) if dofs is None else dofs] = update
        mujoco.mj_integratePos(model, data.qpos, update_nv, 1)
        mujoco.mj_fwdPosition(model, data)
    return data.qpos.copy(), err_norm, steps, success, data


def _assert_same_bits(result, reference):
    qpos, err_norm, steps, success, _ = reference
    assert result.qpos.tobytes() == qpos.tobytes()
    assert np.float64(result.err_norm).tobytes() == np.float64(err_norm).tobytes()
    assert (result.steps, result.success) == (steps, success)


EXACTNESS_CASES = {
    "position, all joints": dict(target_pos=[0.3, 0.2, 0.6]),
    "pose, rot_weight 2, joint list": dict(
        target_pos=[0.35, -0.1, 0.55],
        target_quat=[0.5, 0.5, -0.5, 0.5],
        rot_weight=2,
        joint_names=["yaw", "shoulder", "elbow", "wrist_roll", "wrist_pitch", "hand_roll"],
    ),
    "orientation, joint tuple out of order": dict(
        target_quat=[0.0, 1.0, 0.0, 1.0] / np.sqrt(2),
        joint_names=("wrist_pitch", "yaw", "hand_roll", "elbow"),
    ),
    "position, no regularisation, joint array": dict(
        target_pos=[0.1, 0.3, 0.7],
        regularization_strength=0.0,
        joint_names=np.array(["shoulder", "elbow", "wrist_pitch", "yaw"]),
    ),
    "out of reach, runs out of steps": dict(
        target_pos=[2 * REACH, 0.0, 0.2], max_steps=12, progress_thresh=np.inf
    ),
    "pose, stops for lack of progress": dict(
        target_pos=[0.3, 0.2, 0.6], target_quat=[1.0, 0.0, 0.0, 0.0], joint_names=["yaw"]
    ),
}


@pytest.mark.parametrize("case", EXACTNESS_CASES)
def test_results_are_bitwise_those_of_the_plain_algorithm(physics, case):
    arguments = EXACTNESS_CASES[case]
    result = inverse_kinematics.qpos_from_site_pose(physics, "tcp", **arguments)
    _assert_same_bits(result, _reference_ik(physics, "tcp", **arguments))


def test_ball_joints_move_all_their_dofs_bitwise_as_the_plain_algorithm():
    physics = mjcf.Physics.from_xml_string(BALL_CHAIN_XML)
    arguments = dict(target_pos=[0.15, 0.1, 0.55], joint_names=["ball_2", "hinge", "ball_1"])
    result = inverse_kinematics.qpos_from_site_pose(physics, "tip", **arguments)
    assert result.success
    _assert_same_bits(result, _reference_ik(physics, "tip", **arguments))


@pytest.mark.parametrize("xml", [ARM_ON_FLOOR_XML, BALL_CHAIN_XML])
def test_inplace_leaves_the_data_mj_fwd_position_gives_the_solution(xml):
    physics = mjcf.Physics.from_xml_string(xml)
    physics.data.qpos[:] = physics.model.qpos0
    physics.data.qpos[0] = 0.2
    site = physics.model.site(0).name
    target = physics.data.site_xpos[0] + [0.05, 0.1, -0.05]
    reference_data = _reference_ik(physics, site, target_pos=target)[-1]
    result = inverse_kinematics.qpos_from_site_pose(physics, site, target_pos=target, inplace=True)
    fresh = mujoco.MjData(physics.model.ptr)
    fresh.qpos[:] = result.qpos
    mujoco.mj_fwdPosition(physics.model.ptr, fresh)
    data = physics.data.ptr
    assert result.success and data.ncon > 0
    # The mass matrix is `M` (sparse) on newer MuJoCo releases and `qM` on all of them.
    fields = [
        field
        for field in ("qpos", "xpos", "xmat", "site_xpos", "cdof", "qM", "M", "qLD", "efc_pos")
        if hasattr(data, field)
    ]
    assert "qM" in fields or "M" in fields
    for expected in (fresh, reference_data):
        assert data.ncon == expected.ncon and data.nefc == expected.nefc
        for field in fields:
            assert getattr(data, field).tobytes() == getattr(expected, field).tobytes(), field
        assert data.contact.pos.tobytes() == expected.contact.pos.tobytes()


def test_a_joint_that_cannot_move_the_site_stops_at_once_without_warnings(recwarn):
    # The site lies on the hinge's axis: its Jacobian and so its step are exactly zero.
    physics = mjcf.Physics.from_xml_string(
        '<mujoco><worldbody><body><joint name="spin" axis="0 0 1"/><geom size="0.1"/>'
        '<site name="centre"/></body></worldbody></mujoco>'
    )
    result = inverse_kinematics.qpos_from_site_pose(physics, "centre", target_pos=[0.3, 0, 0])
    assert (result.steps, result.success, result.err_norm) == (0, False, 0.3)
    np.testing.assert_array_equal(result.qpos, [0.0])
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]
