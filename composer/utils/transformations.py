"""Rotations in MuJoCo's conventions: quaternions are (w, x, y, z), matrices act on columns.

Quaternion functions accept leading batch dimensions unless stated otherwise. Euler angle
`ordering` strings name the axes of the elementary rotations in matrix multiplication order:
'XYZ' means rotX(e[0]) @ rotY(e[1]) @ rotZ(e[2]). Every Tait-Bryan ('XYZ', 'XZY', 'YXZ',
'YZX', 'ZXY', 'ZYX') and proper Euler ('XYX', 'XZX', 'YXY', 'YZY', 'ZXZ', 'ZYZ') ordering
is supported.
"""

from __future__ import annotations

import mujoco
import numpy as np

_TOL = 1e-10
_AXES = "XYZ"


def _as_quat(quat, name: str = "quat") -> np.ndarray:
    quat = np.asarray(quat, dtype=np.float64)
    if quat.shape[-1:] != (4,):
        raise ValueError(
            f"{name}: expected a quaternion (w, x, y, z) of 4 values, got shape {quat.shape}"
        )
    return quat


def quat_conj(quat) -> np.ndarray:
    """Returns the conjugate (w, -x, -y, -z), the inverse rotation of a unit quaternion."""
    quat = _as_quat(quat)
    return quat * np.array([1.0, -1.0, -1.0, -1.0])


def quat_inv(quat) -> np.ndarray:
    """Returns the multiplicative inverse of `quat` (which need not be normalised)."""
    quat = _as_quat(quat)
    return quat_conj(quat) / np.sum(quat * quat, axis=-1, keepdims=True)


def quat_mul(quat1, quat2) -> np.ndarray:
    """Returns the Hamilton product `quat1 * quat2`: rotation `quat2` followed by `quat1`."""
    q1 = _as_quat(quat1, "quat1")
    q2 = _as_quat(quat2, "quat2")
    w1, x1, y1, z1 = np.moveaxis(q1, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(q2, -1, 0)
    return np.stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ],
        axis=-1,
    )


def quat_diff(source, target) -> np.ndarray:
    """Returns the quaternion `d` with `source * d == target`: the rotation from source to target,
    expressed in the source frame."""
    return quat_mul(quat_conj(source), target)


def quat_log(quat, tol: float = _TOL) -> np.ndarray:
    """Returns the quaternion logarithm (log|q|, axis * half-angle); zero vector part when the
    rotation is smaller than `tol`."""
    quat = _as_quat(quat)
    norm = np.linalg.norm(quat, axis=-1, keepdims=True)
    vec = quat[..., 1:]
    vec_norm = np.linalg.norm(vec, axis=-1, keepdims=True)
    half_angle = np.arccos(np.clip(quat[..., :1] / norm, -1.0, 1.0))
    safe_norm = np.where(vec_norm > tol, vec_norm, 1.0)
    vec_part = np.where(vec_norm > tol, vec / safe_norm * half_angle, 0.0)
    return np.concatenate([np.log(norm), vec_part], axis=-1)


def quat_dist(source, target) -> np.ndarray:
    """Returns the rotational distance (half the angle of `source * inv(target)`), keeping a
    trailing axis of size 1. Both arguments are assumed to be unit quaternions."""
    product = quat_mul(source, quat_inv(target))
    product = product / np.linalg.norm(product, axis=-1, keepdims=True)
    return np.linalg.norm(quat_log(product), axis=-1, keepdims=True)


def quat_rotate(quat, vec) -> np.ndarray:
    """Returns `vec` rotated by `quat` (the vector part of `quat * (0, vec) * conj(quat)`)."""
    vec = np.asarray(vec, dtype=np.float64)
    if vec.shape[-1:] != (3,):
        raise ValueError(f"vec: expected a 3-vector, got shape {vec.shape}")
    padded = np.concatenate([np.zeros(vec.shape[:-1] + (1,)), vec], axis=-1)
    return quat_mul(quat_mul(quat, padded), quat_conj(quat))[..., 1:]


def quat_to_axisangle(quat) -> np.ndarray:
    """Returns the rotation vector (unit axis times angle in [-pi, pi)) of a unit quaternion."""
    quat = _as_quat(quat)
    if quat.shape != (4,):
        raise ValueError(f"quat: expected a single quaternion of shape (4,), got {quat.shape}")
    angle = 2.0 * np.arccos(np.clip(quat[0], -1.0, 1.0))
    if angle < _TOL:
        return np.zeros(3)
    axis = quat[1:] / np.sin(angle / 2.0)
    return axis * ((angle + np.pi) % (2.0 * np.pi) - np.pi)


def axisangle_to_quat(axisangle) -> np.ndarray:
    """Returns the unit quaternion of a rotation vector (axis scaled by the angle in radians)."""
    axisangle = np.asarray(axisangle, dtype=np.float64)
    if axisangle.shape != (3,):
        raise ValueError(f"axisangle: expected a 3-vector, got shape {axisangle.shape}")
    angle = np.linalg.norm(axisangle)
    if angle < _TOL:
        return np.array([1.0, 0.0, 0.0, 0.0])
    half = angle / 2.0
    return np.concatenate([[np.cos(half)], axisangle / angle * np.sin(half)])


def quat_to_mat(quat) -> np.ndarray:
    """Returns the 4x4 homogeneous transform rotating by `quat` (normalised first).

    A quaternion of (near) zero norm gives the identity.
    """
    quat = _as_quat(quat)
    if quat.shape != (4,):
        raise ValueError(f"quat: expected a single quaternion of shape (4,), got {quat.shape}")
    mat = np.identity(4)
    norm = np.linalg.norm(quat)
    if norm < _TOL:
        return mat
    rotation = np.empty(9)
    mujoco.mju_quat2Mat(rotation, quat / norm)
    mat[:3, :3] = rotation.reshape(3, 3)
    return mat


def mat_to_quat(mat) -> np.ndarray:
    """Returns the unit quaternion of a 3x3 rotation matrix or a 4x4 homogeneous transform."""
    mat = np.asarray(mat, dtype=np.float64)
    if mat.shape not in ((3, 3), (4, 4)):
        raise ValueError(f"mat: expected a 3x3 or 4x4 matrix, got shape {mat.shape}")
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(mat[:3, :3]).ravel())
    return quat


def _axis_rotation(axis: int, theta, full: bool) -> np.ndarray:
    theta = np.asarray(theta, dtype=np.float64)
    cos, sin = np.cos(theta), np.sin(theta)
    size = 4 if full else 3
    rmat = np.zeros(theta.shape + (size, size))
    # The two other axes in cyclic order, so that rmat[j, i] = +sin for every axis.
    i, j = (axis + 1) % 3, (axis + 2) % 3
    rmat[..., axis, axis] = 1.0
    rmat[..., i, i] = cos
    rmat[..., j, j] = cos
    rmat[..., i, j] = -sin
    rmat[..., j, i] = sin
    if full:
        rmat[..., 3, 3] = 1.0
    return rmat


def rotation_x_axis(theta, full: bool = False) -> np.ndarray:
    """Returns the rotation matrix about X by `theta` (4x4 if `full`); batched for array theta."""
    return _axis_rotation(0, theta, full)


def rotation_y_axis(theta, full: bool = False) -> np.ndarray:
    """Returns the rotation matrix about Y by `theta` (4x4 if `full`); batched for array theta."""
    return _axis_rotation(1, theta, full)


def rotation_z_axis(theta, full: bool = False) -> np.ndarray:
    """Returns the rotation matrix about Z by `theta` (4x4 if `full`); batched for array theta."""
    return _axis_rotation(2, theta, full)


def rotation_matrix_2d(theta) -> np.ndarray:
    """Returns the 2x2 matrix rotating the plane by `theta` counter-clockwise."""
    cos, sin = np.cos(theta), np.sin(theta)
    return np.array([[cos, -sin], [sin, cos]])


def _parse_ordering(ordering: str) -> tuple[int, int, int]:
    if (
        not isinstance(ordering, str)
        or len(ordering) != 3
        or any(axis not in _AXES for axis in ordering)
        or ordering[0] == ordering[1]
        or ordering[1] == ordering[2]
    ):
        raise ValueError(
            f"ordering: expected three axes from 'XYZ' with no axis repeated consecutively "
            f"(e.g. 'XYZ', 'ZXZ'), got {ordering!r}"
        )
    return tuple(_AXES.index(axis) for axis in ordering)


def euler_to_rmat(euler_vec, ordering: str = "ZXZ", full: bool = False) -> np.ndarray:
    """Returns the rotation matrix (4x4 transform if `full`) of Euler angles.

    Args:
      euler_vec: Angles of shape (3,) or (N, 3), in radians.
      ordering: Axes in matrix multiplication order, e.g. 'XYZ' = rotX @ rotY @ rotZ.
      full: Whether to return a 4x4 homogeneous transform.
    """
    axes = _parse_ordering(ordering)
    euler_vec = np.asarray(euler_vec, dtype=np.float64)
    if euler_vec.shape[-1:] != (3,) or euler_vec.ndim > 2:
        raise ValueError(f"euler_vec: expected shape (3,) or (N, 3), got {euler_vec.shape}")
    first, second, third = (
        _axis_rotation(axis, euler_vec[..., k], full) for k, axis in enumerate(axes)
    )
    return first @ second @ third


def rmat_to_euler(rmat, ordering: str = "ZXZ") -> np.ndarray:
    """Returns Euler angles `e` with `euler_to_rmat(e, ordering) == rmat`.

    The middle angle lies in [-pi/2, pi/2] for Tait-Bryan orderings and in [0, pi] for proper
    Euler orderings. At a singularity (gimbal lock) the third angle is set to 0.
    """
    i, j, k_or_i = _parse_ordering(ordering)
    rmat = np.asarray(rmat, dtype=np.float64)
    if rmat.shape not in ((3, 3), (4, 4)):
        raise ValueError(f"rmat: expected a 3x3 or 4x4 matrix, got shape {rmat.shape}")
    proper = k_or_i == i
    k = 3 - i - j
    # +1 when (i, j, k) is a cyclic permutation of (0, 1, 2): then e_i x e_j = e_k.
    sign = 1.0 if (j - i) % 3 == 1 else -1.0
    if proper:
        sin_b = np.hypot(rmat[i, j], rmat[i, k])
        second = np.arctan2(sin_b, rmat[i, i])
        singular = sin_b < _TOL
        if not singular:
            first = np.arctan2(rmat[j, i], -sign * rmat[k, i])
            third = np.arctan2(rmat[i, j], sign * rmat[i, k])
    else:
        cos_b = np.hypot(rmat[i, i], rmat[i, j])
        second = np.arctan2(sign * rmat[i, k], cos_b)
        singular = cos_b < _TOL
        if not singular:
            first = np.arctan2(-sign * rmat[j, k], rmat[k, k])
            third = np.arctan2(-sign * rmat[i, j], rmat[i, i])
    if singular:
        # Only first +/- third is determined; with third = 0, column j of the matrix is
        # rot_i(first) e_j = cos(first) e_j + sign * sin(first) e_k.
        first = np.arctan2(sign * rmat[k, j], rmat[j, j])
        third = 0.0
    return np.array([first, second, third])


def euler_to_quat(euler_vec, ordering: str = "XYZ") -> np.ndarray:
    """Returns the unit quaternion of the Euler angles `euler_vec` (shape (3,))."""
    return mat_to_quat(euler_to_rmat(euler_vec, ordering=ordering))


def quat_to_euler(quat, ordering: str = "XYZ") -> np.ndarray:
    """Returns Euler angles in `ordering` for the rotation of a single quaternion."""
    return rmat_to_euler(quat_to_mat(quat)[:3, :3], ordering=ordering)
