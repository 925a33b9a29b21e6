"""Tests for composer.variation.rotations."""

import mujoco
import numpy as np
import pytest

from composer.variation import deterministic, distributions, rotations


def test_uniform_quaternion_is_unit_and_uniform_over_rotations():
    variation = rotations.UniformQuaternion()
    random_state = np.random.RandomState(0)
    quats = np.array([variation(random_state=random_state) for _ in range(8000)])
    np.testing.assert_allclose(np.linalg.norm(quats, axis=1), 1.0)
    # For the uniform distribution on the unit 3-sphere each squared component has mean 1/4.
    np.testing.assert_allclose((quats**2).mean(axis=0), 0.25, atol=0.015)


def test_uniform_quaternion_is_reproducible_from_a_seed():
    variation = rotations.UniformQuaternion()
    first = variation(random_state=np.random.RandomState(5))
    np.testing.assert_array_equal(first, variation(random_state=np.random.RandomState(5)))


def test_quaternion_from_axis_angle_matches_mujoco():
    axis = np.array([0.0, 3.0, 4.0])
    expected = np.empty(4)
    mujoco.mju_axisAngle2Quat(expected, axis / 5.0, 0.7)
    quat = rotations.QuaternionFromAxisAngle(axis=axis, angle=0.7)()
    np.testing.assert_allclose(quat, expected, atol=1e-12)


def test_quaternion_from_axis_angle_evaluates_variable_angle():
    variation = rotations.QuaternionFromAxisAngle(
        axis=[0.0, 0.0, 1.0], angle=distributions.Uniform(0.0, np.pi)
    )
    quat = variation(random_state=np.random.RandomState(0))
    assert np.linalg.norm(quat) == pytest.approx(1.0)
    assert quat[1] == 0.0 and quat[2] == 0.0


def test_quaternion_from_zero_axis_is_rejected():
    with pytest.raises(ValueError, match="axis must be a non-zero 3-vector"):
        rotations.QuaternionFromAxisAngle(axis=[0.0, 0.0, 0.0], angle=1.0)()


def test_pre_multiply_applies_the_sampled_rotation_after_the_initial_one():
    quarter_z = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])
    quarter_x = np.array([np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0])
    result = rotations.QuaternionPreMultiply(quarter_z)(initial_value=quarter_x)
    expected = np.empty(4)
    mujoco.mju_mulQuat(expected, quarter_z, quarter_x)
    np.testing.assert_allclose(result, expected, atol=1e-12)


def test_cumulative_pre_multiply_keeps_rotating_the_current_value():
    eighth_turn = np.array([np.cos(np.pi / 8), 0.0, 0.0, np.sin(np.pi / 8)])
    variation = rotations.QuaternionPreMultiply(eighth_turn, cumulative=True)
    quat = rotations.IDENTITY_QUATERNION
    for _ in range(4):
        quat = variation(initial_value=rotations.IDENTITY_QUATERNION, current_value=quat)
    np.testing.assert_allclose(np.abs(quat), [0.0, 0.0, 0.0, 1.0], atol=1e-12)


def test_quaternion_rotate_rotates_the_initial_vector():
    quarter_z = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])
    rotated = rotations.QuaternionRotate(quarter_z)(initial_value=np.array([1.0, 0.0, 0.5]))
    np.testing.assert_allclose(rotated, [0.0, 1.0, 0.5], atol=1e-12)


def test_quaternion_rotate_uses_explicit_vector_when_given():
    half_x = np.array([0.0, 1.0, 0.0, 0.0])
    variation = rotations.QuaternionRotate(half_x, vec=deterministic.Constant([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(variation(initial_value=np.ones(3)), [0.0, -1.0, 0.0], atol=1e-12)


def test_quaternion_from_axis_angle_draws_one_angle_when_varying_a_quaternion():
    variation = rotations.QuaternionFromAxisAngle([0.0, 0.0, 1.0], distributions.Uniform(0, 1))
    quat = variation(
        initial_value=rotations.IDENTITY_QUATERNION, random_state=np.random.RandomState(0)
    )
    assert quat.shape == (4,)
    assert np.linalg.norm(quat) == pytest.approx(1.0)
