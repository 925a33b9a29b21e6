"""Where a batch's results live and in which array type the caller gets them.

A `BatchEnvironment` built with `array_type="numpy"` (the default) hands out NumPy arrays,
computed on the host. With another array type its observations, rewards, discounts and step
types are Warp arrays on the batch's device, handed out without a copy:

| array_type | what the caller gets                  | how                              |
|------------|---------------------------------------|----------------------------------|
| "warp"     | the `warp.array` itself               | -                                |
| "torch"    | a `torch.Tensor` on the same device   | `warp.to_torch` (shared memory)  |
| "jax"      | a `jax.Array` on the same device      | `warp.to_jax` (DLPack)           |

Observations that are MJCF features of float32 fields (positions, orientations, joint
positions and velocities, sensor data) are gathered on the device by a kernel: on a GPU they
never pass through the host. Rewards, discounts, step types and other observables are
computed by the task's NumPy code on the host and copied to the device once.

On Warp's CPU device a Warp array is also a NumPy array without a copy
(`array.numpy()`, `np.asarray(array)` through `__array_interface__`). torch and JAX are
imported only when asked for, and are not dependencies of the extra `[warp]`.

Each step's results are new arrays: a result the caller keeps is never overwritten by a
later step.
"""

from typing import Any

import numpy as np

__all__ = ["ARRAY_TYPES", "DeviceOutputs", "array_library"]

#: The values of `BatchEnvironment(array_type=...)`.
ARRAY_TYPES = ("numpy", "warp", "torch", "jax")

# The top-level module of an array's type -> the library `array_library` names.
_LIBRARIES = {"warp": "warp", "torch": "torch", "jax": "jax", "jaxlib": "jax"}


def array_library(values) -> str:
    """'warp', 'torch' or 'jax' for an array of that library (none is imported), else ''."""
    return _LIBRARIES.get(type(values).__module__.split(".", 1)[0], "")


def check_array_type(array_type: str) -> str:
    """Returns `array_type` if it is one of `ARRAY_TYPES`; raises ValueError naming it."""
    if array_type not in ARRAY_TYPES:
        raise ValueError(f"array_type: expected one of {list(ARRAY_TYPES)}, got {array_type!r}")
    return array_type


class DeviceOutputs:
    """Makes device arrays for a batch's results and hands them out as `array_type`.

    Args:
      warp: the `warp` module.
      device: the Warp device the batch runs on.
      array_type: one of `ARRAY_TYPES` ("numpy" hands out `array.numpy()`: the same memory
        on the CPU device, a host copy on CUDA).

    Raises:
      ImportError: when `array_type` is "torch" or "jax" and that library is missing; the
        message names it.
    """

    def __init__(self, warp, device, array_type: str):
        self._wp = warp
        self.device = device
        self.array_type = array_type
        if array_type in ("torch", "jax"):
            try:
                __import__(array_type)
            except ImportError as error:
                raise ImportError(
                    f"array_type={array_type!r} needs {array_type} installed ({error})"
                ) from error
        converters = {"numpy": warp.array.numpy, "torch": warp.to_torch, "jax": warp.to_jax}
        self._convert = converters.get(array_type)

    def empty(self, shape: tuple[int, ...], dtype=np.float32):
        """A new uninitialised Warp array on the device."""
        return self._wp.empty(
            shape, dtype=self._wp.dtype_from_numpy(np.dtype(dtype)), device=self.device
        )

    def upload(self, values: np.ndarray):
        """A new Warp array on the device holding `values` (host values: one copy)."""
        values = np.ascontiguousarray(values)
        return self._wp.array(
            values, dtype=self._wp.dtype_from_numpy(values.dtype), device=self.device
        )

    def hand_out(self, array) -> Any:
        """`array` (a Warp array on the device) as `array_type`, sharing its memory."""
        return array if self._convert is None else self._convert(array)

    def to_device(self, values):
        """A Warp, torch or JAX array (an action) as a Warp array sharing its memory.

        Warp arrays are used as they are; torch and JAX arrays go through DLPack
        (`warp.from_torch`, `warp.from_jax`). The array stays on its own device: the
        caller checks that it is this batch's.
        """
        library = array_library(values)
        if library == "torch":
            return self._wp.from_torch(values)
        if library == "jax":
            return self._wp.from_jax(values)
        return values
