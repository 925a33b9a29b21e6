"""Tests for mujoco_physics.math: quaternions from Euler angles and MuJoCo's quaternion ops."""

import numpy as np
import pytest

from mujoco_physics import math as mjmath

_HALF = np.sqrt(0.5)


@pytest.mark.parametrize(
    "angles, expected",
    [
        ((90, 0, 0), [_HALF, _HALF, 0, 0]),
        ((0, 90, 0), [_HALF, 0, _HALF, 0]),
        ((0, 0, 90), [_HALF, 0, 0, _HALF]),
        # Yaw first, then pitch about the new y: 90 about z then 90 about y.
        ((0, 90, 90), [0.5, -0.5, 0.5, 0.5]),
    ],
)
def test_euler2quat_turns_about_z_then_y_then_x_in_degrees(angles, expected):
    np.testing.assert_allclose(mjmath.euler2quat(*angles), expected, atol=1e-12)


def test_quatdiff_is_the_rotation_from_source_to_target():
    source = mjmath.euler2quat(0, 0, 30)
    target = mjmath.euler2quat(0, 0, 75)
    np.testing.assert_allclose(mjmath.mj_quatdiff(source, target), mjmath.euler2quat(0, 0, 45))


def test_quat2vel_of_a_quarter_turn_in_one_second_is_pi_over_two_about_the_axis():
    velocity = mjmath.mj_quat2vel(mjmath.euler2quat(0, 0, 90), 1.0)
    np.testing.assert_allclose(velocity, [0, 0, np.pi / 2])
