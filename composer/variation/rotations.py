"""Variations of 3D rotations, as unit quaternions (w, x, y, z)."""

from __future__ import annotations

import numpy as np

from composer.utils import transformations
from composer.variation import base

IDENTITY_QUATERNION = np.array([1.0, 0.0, 0.0, 0.0])


class UniformQuaternion(base.Variation):
    """Unit quaternions distributed uniformly over the rotation group."""

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        random_state = np.random if random_state is None else random_state
        u1, u2, u3 = random_state.uniform([0.0, 0.0, 0.0], [1.0, 2.0 * np.pi, 2.0 * np.pi])
        # Shoemake's construction: two angles uniform on the circle, mixed by sqrt(u1).
        a, b = np.sqrt(1.0 - u1), np.sqrt(u1)
        return np.array([a * np.sin(u2), a * np.cos(u2), b * np.sin(u3), b * np.cos(u3)])


class QuaternionFromAxisAngle(base.Variation):
    """The rotation by `angle` (radians) about `axis`; either may be a variation."""

    def __init__(self, axis, angle):
        self._axis = axis
        self._angle = angle

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        # The quaternion being varied is no initial value for an axis or an angle, so the
        # parts are evaluated without it: a distribution draws one angle, not four.
        axis = np.asarray(base.evaluate(self._axis, random_state=random_state))
        angle = base.evaluate(self._angle, random_state=random_state)
        norm = np.linalg.norm(axis)
        if axis.shape != (3,) or norm == 0:
            raise ValueError(
                f"QuaternionFromAxisAngle: axis must be a non-zero 3-vector, got {axis!r}"
            )
        return transformations.axisangle_to_quat(axis / norm * angle)


class QuaternionPreMultiply(base.Variation):
    """Pre-multiplies the initial value (current value if `cumulative`) by `quat`'s value.

    The result applies the existing rotation first, then the sampled one (in the world frame).
    """

    def __init__(self, quat, cumulative: bool = False):
        self._quat = quat
        self._cumulative = cumulative

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        quat = base.evaluate(self._quat, initial_value, current_value, random_state)
        existing = current_value if self._cumulative else initial_value
        if existing is None:
            raise ValueError("QuaternionPreMultiply needs an existing quaternion value to rotate")
        return transformations.quat_mul(np.asarray(quat), np.asarray(existing))


class QuaternionRotate(base.Variation):
    """Rotates a vector by `quat`'s value.

    The vector is `vec` (a constant or variation) when given; otherwise the initial value, or
    the current value if `cumulative`.
    """

    def __init__(self, quat, vec=None, cumulative: bool = False):
        self._quat = quat
        self._vec = vec
        self._cumulative = cumulative

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        quat = base.evaluate(self._quat, initial_value, current_value, random_state)
        if self._vec is None:
            vec = current_value if self._cumulative else initial_value
            if vec is None:
                raise ValueError("QuaternionRotate needs `vec` or an existing vector value")
        else:
            vec = base.evaluate(self._vec, initial_value, current_value, random_state)
        return transformations.quat_rotate(np.asarray(quat), np.asarray(vec))
