"""Tests for composer.utils.inverse_kinematics.qpos_from_site_pose on a 6-DOF arm."""

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
    with pytest.raises(ValueError, match="target_pos and target_quat"):
        inverse_kinematics.qpos_from_site_pose(physics, "tcp")


def test_unknown_site_is_rejected_by_name(physics):
    with pytest.raises(ValueError, match="no site named 'gripper'"):
        inverse_kinematics.qpos_from_site_pose(physics, "gripper", target_pos=[0, 0, 1])


def test_unknown_joint_is_rejected_by_name(physics):
    with pytest.raises(ValueError, match="no joint named 'knee'"):
        inverse_kinematics.qpos_from_site_pose(
            physics, "tcp", target_pos=[0, 0, 1], joint_names=["elbow", "knee"]
        )


def test_joint_names_given_as_a_string_are_rejected(physics):
    with pytest.raises(ValueError, match="joint_names.*got str"):
        inverse_kinematics.qpos_from_site_pose(
            physics, "tcp", target_pos=[0, 0, 1], joint_names="elbow"
        )


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
