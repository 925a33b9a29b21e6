"""Tests for composer.utils.transformations, checked against MuJoCo's own rotation functions."""

import mujoco
import numpy as np
import pytest

from composer.utils import transformations as tr

ORDERINGS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX", "XYX", "XZX", "YXY", "YZY", "ZXZ", "ZYZ")


def _random_unit_quat(rng):
    quat = rng.standard_normal(4)
    return quat / np.linalg.norm(quat)


def test_quat_mul_matches_mujoco():
    rng = np.random.default_rng(0)
    q1, q2 = _random_unit_quat(rng), _random_unit_quat(rng)
    expected = np.empty(4)
    mujoco.mju_mulQuat(expected, q1, q2)
    np.testing.assert_allclose(tr.quat_mul(q1, q2), expected, atol=1e-12)


def test_quat_mul_broadcasts_over_leading_dimensions():
    rng = np.random.default_rng(1)
    q1 = np.stack([_random_unit_quat(rng) for _ in range(5)])
    q2 = _random_unit_quat(rng)
    batched = tr.quat_mul(q1, q2)
    assert batched.shape == (5, 4)
    np.testing.assert_allclose(batched[3], tr.quat_mul(q1[3], q2))


def test_quat_conj_times_quat_is_identity():
    quat = _random_unit_quat(np.random.default_rng(2))
    np.testing.assert_allclose(tr.quat_mul(tr.quat_conj(quat), quat), [1, 0, 0, 0], atol=1e-12)


def test_quat_inv_inverts_a_non_unit_quaternion():
    quat = np.array([1.0, 2.0, -0.5, 3.0])
    np.testing.assert_allclose(tr.quat_mul(quat, tr.quat_inv(quat)), [1, 0, 0, 0], atol=1e-12)


def test_quat_diff_composes_source_into_target():
    rng = np.random.default_rng(3)
    source, target = _random_unit_quat(rng), _random_unit_quat(rng)
    np.testing.assert_allclose(
        tr.quat_mul(source, tr.quat_diff(source, target)), target, atol=1e-12
    )


def test_quat_rotate_matches_mujoco():
    rng = np.random.default_rng(4)
    quat, vec = _random_unit_quat(rng), rng.standard_normal(3)
    expected = np.empty(3)
    mujoco.mju_rotVecQuat(expected, vec, quat)
    np.testing.assert_allclose(tr.quat_rotate(quat, vec), expected, atol=1e-12)


def test_quat_to_mat_matches_mujoco_and_is_homogeneous():
    quat = _random_unit_quat(np.random.default_rng(5))
    expected = np.empty(9)
    mujoco.mju_quat2Mat(expected, quat)
    mat = tr.quat_to_mat(quat)
    assert mat.shape == (4, 4)
    np.testing.assert_allclose(mat[:3, :3], expected.reshape(3, 3), atol=1e-12)
    np.testing.assert_array_equal(mat[3], [0, 0, 0, 1])


def test_quat_to_mat_normalises_its_input():
    quat = _random_unit_quat(np.random.default_rng(6))
    np.testing.assert_allclose(tr.quat_to_mat(3.0 * quat), tr.quat_to_mat(quat), atol=1e-12)


def test_mat_to_quat_inverts_quat_to_mat_up_to_sign():
    quat = _random_unit_quat(np.random.default_rng(7))
    recovered = tr.mat_to_quat(tr.quat_to_mat(quat))
    assert abs(recovered @ quat) == pytest.approx(1.0, abs=1e-12)


def test_axisangle_to_quat_matches_mujoco():
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    expected = np.empty(4)
    mujoco.mju_axisAngle2Quat(expected, axis, 0.8)
    np.testing.assert_allclose(tr.axisangle_to_quat(axis * 0.8), expected, atol=1e-12)


def test_quat_to_axisangle_of_quarter_turn_about_z():
    quat = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])
    np.testing.assert_allclose(tr.quat_to_axisangle(quat), [0, 0, np.pi / 2], atol=1e-12)


def test_quat_to_axisangle_wraps_large_angles_into_minus_pi_to_pi():
    # A rotation by 3pi/2 about +x is a rotation by -pi/2 about +x.
    quat = np.array([np.cos(3 * np.pi / 4), np.sin(3 * np.pi / 4), 0.0, 0.0])
    np.testing.assert_allclose(tr.quat_to_axisangle(quat), [-np.pi / 2, 0, 0], atol=1e-12)


def test_quat_to_axisangle_of_identity_is_zero():
    np.testing.assert_array_equal(tr.quat_to_axisangle([1.0, 0.0, 0.0, 0.0]), np.zeros(3))


def test_quat_dist_is_half_the_rotation_angle():
    quarter_turn = np.array([np.cos(np.pi / 4), 0.0, np.sin(np.pi / 4), 0.0])
    dist = tr.quat_dist(quarter_turn, [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(dist, [np.pi / 4], atol=1e-9)


def test_quat_log_of_identity_is_zero():
    np.testing.assert_allclose(tr.quat_log([1.0, 0.0, 0.0, 0.0]), np.zeros(4), atol=1e-12)


def test_rotation_z_axis_turns_x_into_y():
    np.testing.assert_allclose(tr.rotation_z_axis(np.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-12)


def test_rotation_y_axis_turns_z_into_x():
    np.testing.assert_allclose(tr.rotation_y_axis(np.pi / 2) @ [0, 0, 1], [1, 0, 0], atol=1e-12)


def test_axis_rotations_batch_over_angles_and_support_full_transforms():
    assert tr.rotation_x_axis(np.zeros(4)).shape == (4, 3, 3)
    np.testing.assert_array_equal(tr.rotation_x_axis(0.0, full=True), np.eye(4))


def test_euler_xyz_matches_mujoco_intrinsic_xyz_compiler_convention():
    euler = np.array([0.1, -0.7, 1.3])
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><compiler angle="radian" eulerseq="xyz"/><worldbody>'
        f'<body euler="{euler[0]} {euler[1]} {euler[2]}"><geom size="0.1"/></body>'
        "</worldbody></mujoco>"
    )
    quat = tr.euler_to_quat(euler, ordering="XYZ")
    assert abs(quat @ model.body_quat[1]) == pytest.approx(1.0, abs=1e-12)


def test_euler_to_rmat_multiplies_axis_rotations_in_ordering():
    euler = np.array([0.3, -0.2, 0.9])
    expected = tr.rotation_z_axis(0.3) @ tr.rotation_x_axis(-0.2) @ tr.rotation_z_axis(0.9)
    np.testing.assert_allclose(tr.euler_to_rmat(euler, "ZXZ"), expected, atol=1e-12)


@pytest.mark.parametrize("ordering", ORDERINGS)
def test_rmat_to_euler_round_trips_random_rotations(ordering):
    rng = np.random.default_rng(8)
    for _ in range(50):
        rmat = tr.quat_to_mat(_random_unit_quat(rng))[:3, :3]
        euler = tr.rmat_to_euler(rmat, ordering)
        np.testing.assert_allclose(tr.euler_to_rmat(euler, ordering), rmat, atol=1e-9)


@pytest.mark.parametrize("ordering", ORDERINGS)
@pytest.mark.parametrize("middle", [0.0, np.pi / 2, -np.pi / 2, np.pi])
def test_rmat_to_euler_round_trips_at_gimbal_lock(ordering, middle):
    rmat = tr.euler_to_rmat([0.4, middle, -0.3], ordering)
    np.testing.assert_allclose(
        tr.euler_to_rmat(tr.rmat_to_euler(rmat, ordering), ordering), rmat, atol=1e-9
    )


def test_quat_to_euler_inverts_euler_to_quat_in_range():
    euler = np.array([0.2, -0.4, 1.1])
    np.testing.assert_allclose(tr.quat_to_euler(tr.euler_to_quat(euler, "ZYX"), "ZYX"), euler)


def test_invalid_ordering_is_rejected():
    with pytest.raises(ValueError, match="ordering.*'XXY'"):
        tr.euler_to_rmat([0.0, 0.0, 0.0], "XXY")


def test_quaternion_of_wrong_length_is_rejected():
    with pytest.raises(ValueError, match="quat1: expected a quaternion"):
        tr.quat_mul([1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])
