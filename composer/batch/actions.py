"""A batch's actions: checked once per step, on the host or on the device where they live.

NumPy arrays, lists and other host values are checked with NumPy. Warp, torch and JAX arrays
stay where they are: their shape and dtype are checked from their metadata, their values by
one kernel that counts NaN and infinite entries (one integer comes back to the host).
"""

from typing import Any

import numpy as np

from composer.batch import _warp, kernels
from composer.batch.outputs import DeviceOutputs, array_library

__all__ = ["check_action"]


def check_action(action, expected: tuple[int, ...], outputs: DeviceOutputs) -> Any:
    """Returns `action` checked: a float64 NumPy array, or for device arrays a Warp array.

    A device action comes back as a 2-D (num_envs, entries per world) Warp array on the
    batch's device, sharing the caller's memory.

    Raises:
      ValueError: naming `action`, for a value that is not a float array of shape
        `expected`, a device array on another device, or NaN or infinite entries (the
        message lists the worlds that have them).
    """
    if not array_library(action):
        return _check_host_action(action, expected)
    wp = _warp.load()[0]
    try:
        array = outputs.to_device(action)
    except (TypeError, ValueError, RuntimeError) as error:
        raise ValueError(f"action: could not read {type(action).__name__} ({error})") from error
    if tuple(array.shape) != expected:
        raise ValueError(
            f"action: expected shape {expected} (num_envs, *action_spec().shape), "
            f"got {tuple(array.shape)}"
        )
    if array.device != outputs.device:
        raise ValueError(
            f"action: expected an array on {outputs.device}, got one on {array.device}"
        )
    if array.dtype not in (wp.float32, wp.float64) or not array.is_contiguous:
        raise ValueError(
            f"action: expected a contiguous float32 or float64 array, got {array.dtype.__name__}"
            f"{'' if array.is_contiguous else ' (not contiguous)'}"
        )
    rows = array.reshape((expected[0], -1))
    count = wp.zeros(1, dtype=wp.int32, device=outputs.device)
    wp.launch(
        kernels.kernels().count_nonfinite,
        dim=rows.shape,
        inputs=[rows, count],
        device=outputs.device,
    )
    if count.numpy()[0]:
        _raise_nonfinite(rows.numpy())
    return rows


def _check_host_action(action, expected: tuple[int, ...]) -> np.ndarray:
    try:
        array = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(
            f"action: expected a float array of shape {expected}, got {action!r}"
        ) from error
    if array.shape != expected:
        raise ValueError(
            f"action: expected shape {expected} (num_envs, *action_spec().shape), got {array.shape}"
        )
    if not np.isfinite(array).all():
        _raise_nonfinite(array)
    return array


def _raise_nonfinite(values: np.ndarray) -> None:
    worlds = np.unique(np.nonzero(~np.isfinite(values))[0])
    raise ValueError(f"action: NaN or infinity in the actions of worlds {worlds.tolist()}")
