"""Quaternion helpers on MuJoCo's own `mju_*` functions (served as
`dm_control.mujoco.math`). Quaternions are (w, x, y, z)."""

import mujoco
import numpy as np


def _axis_quaternion(axis: int, degrees: float) -> np.ndarray:
    quaternion = np.empty(4)
    mujoco.mju_axisAngle2Quat(quaternion, np.eye(3)[axis], np.deg2rad(degrees))
    return quaternion


def euler2quat(ax: float, ay: float, az: float) -> np.ndarray:
    """The rotation by `az` about z, then `ay` about the new y, then `ax` about the
    newest x (intrinsic z-y-x, angles in degrees), as a quaternion."""
    yaw_pitch = mj_quatprod(_axis_quaternion(2, az), _axis_quaternion(1, ay))
    return mj_quatprod(yaw_pitch, _axis_quaternion(0, ax))


def mj_quatprod(q, r) -> np.ndarray:
    """The product `q * r` (`mju_mulQuat`)."""
    product = np.empty(4)
    mujoco.mju_mulQuat(product, np.asarray(q, dtype=float), np.asarray(r, dtype=float))
    return product


def mj_quat2vel(q, dt: float) -> np.ndarray:
    """The angular velocity that turns by `q` in `dt` seconds (`mju_quat2Vel`)."""
    velocity = np.empty(3)
    mujoco.mju_quat2Vel(velocity, np.asarray(q, dtype=float), dt)
    return velocity


def mj_quatneg(q) -> np.ndarray:
    """The conjugate (inverse rotation) of `q` (`mju_negQuat`)."""
    negated = np.empty(4)
    mujoco.mju_negQuat(negated, np.asarray(q, dtype=float))
    return negated


def mj_quatdiff(source, target) -> np.ndarray:
    """The rotation from `source` to `target`: `conj(source) * target`."""
    return mj_quatprod(mj_quatneg(source), target)
