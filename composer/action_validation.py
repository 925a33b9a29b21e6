"""Checks the agent's actions against the environment's action spec before they are applied."""

import math

import numpy as np
from dm_env import specs


class ActionValidator:
    """Converts an action to an array of the spec's dtype and rejects malformed ones.

    Checks what can be checked cheaply on every step: that the action converts to the
    spec's dtype, has the spec's shape, and (for float specs) holds no NaN or infinity.
    Bounds are not enforced: MuJoCo clamps controls to their ctrlrange.
    """

    __slots__ = ("_spec", "_dtype", "_shape", "_check_finite", "_sum_floats")

    def __init__(self, spec: specs.Array):
        self._spec = spec
        self._dtype = np.dtype(spec.dtype)
        self._shape = tuple(spec.shape)
        self._check_finite = np.issubdtype(self._dtype, np.inexact)
        # A vector of real floats is summed as Python floats: less work than a NumPy call.
        self._sum_floats = self._dtype.kind == "f" and len(self._shape) == 1

    def __call__(self, action) -> np.ndarray:
        """Returns `action` as an array of the spec's dtype.

        Raises:
          ValueError: naming the expected shape, dtype, bounds and actuators, if the
            action cannot be cast, has another shape, or holds NaN or infinity.
        """
        if type(action) is np.ndarray and action.dtype == self._dtype:
            array = action
        else:
            try:
                array = np.asarray(action, dtype=self._dtype)
            except (TypeError, ValueError) as error:
                raise ValueError(self._message(f"a value that cannot be cast: {error}")) from None
        if array.shape != self._shape:
            raise ValueError(self._message(f"shape {array.shape}"))
        # A finite sum proves every value finite, and costs a fraction of isfinite().all();
        # only a sum that overflowed needs the exact check.
        if self._check_finite:
            if self._sum_floats:
                total = sum(array.tolist())
            else:
                total = np.vdot(array, array).real
            if not math.isfinite(total) and not np.isfinite(array).all():
                raise ValueError(self._message(f"non-finite values {array}"))
        return array

    def _message(self, got: str) -> str:
        spec = self._spec
        bounds = ""
        if isinstance(spec, specs.BoundedArray):
            bounds = f", bounds [{spec.minimum}, {spec.maximum}]"
        names = spec.name.replace("\t", ", ") if spec.name else "unnamed"
        return (
            f"action: expected shape {self._shape}, dtype {self._dtype}{bounds} "
            f"(actuators: {names}); got {got}"
        )
