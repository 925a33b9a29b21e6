"""A batch's actions: checked once per step, on the host or on the device where they live.

NumPy arrays, lists and other host values are checked with NumPy and copied to the device
once. Warp, torch and JAX arrays stay where they are: their shape, dtype and device are
checked from their metadata. Their values are checked for NaN, infinity and magnitudes
beyond float32's range (infinite once cast to float32) by one kernel that counts them,
whose one integer comes back to the host; on CUDA that read would synchronise every step,
so there it runs only with `check_values=True`.
"""

from typing import Any

import numpy as np

from composer.batch import _warp, kernels
from composer.batch.arrays import ArrayBridge, array_library

__all__ = ["check_action"]

_FLOAT32_MAX = float(np.finfo(np.float32).max)


def check_action(
    action,
    expected: tuple[int, ...],
    arrays: ArrayBridge,
    *,
    check_values: bool,
    dtype=np.float32,
) -> Any:
    """Returns `action` checked, as a `dtype` array of the batch's namespace on its device.

    Args:
      action: a NumPy array (or anything NumPy reads), or a Warp, torch or JAX array.
      expected: the shape, (num_envs, *action shape).
      arrays: the batch's `ArrayBridge`.
      check_values: whether to check device arrays for NaN and infinity.
      dtype: the batch's float dtype: float32 (MuJoCo Warp: values beyond its range are
        refused) or float64 (the CPU batch, on NumPy memory: device arrays are read on the
        host).

    Raises:
      ValueError: naming `action`, for a value that is not a float array of shape
        `expected`, a device array on another device, or NaN, infinite or (float64)
        beyond float32's range entries (the message lists the worlds that have them).
    """
    library = array_library(action)
    dtype = np.dtype(dtype)
    if not library or dtype == np.float64:
        host = action if not library else arrays.to_host(action)
        return arrays.asarray(_check_host_action(host, expected, dtype), dtype)
    wp = _warp.load().warp
    try:
        if library == "torch":
            array = wp.from_torch(action)
        elif library == "jax":
            array = wp.from_jax(action)
        else:
            array = action
    except (TypeError, ValueError, RuntimeError) as error:
        raise ValueError(f"action: could not read {type(action).__name__} ({error})") from error
    if tuple(array.shape) != expected:
        raise ValueError(
            f"action: expected shape {expected} (num_envs, *action_spec().shape), "
            f"got {tuple(array.shape)}"
        )
    if array.device != arrays.device:
        raise ValueError(f"action: expected an array on {arrays.device}, got one on {array.device}")
    if array.dtype not in (wp.float32, wp.float64) or not array.is_contiguous:
        raise ValueError(
            f"action: expected a contiguous float32 or float64 array, got {array.dtype.__name__}"
            f"{'' if array.is_contiguous else ' (not contiguous)'}"
        )
    rows = array.reshape((expected[0], -1))
    if check_values:
        count = wp.zeros(1, dtype=wp.int32, device=arrays.device)
        wp.launch(
            kernels.kernels().count_nonfinite,
            dim=rows.shape,
            inputs=[rows, count],
            device=arrays.device,
        )
        if count.numpy()[0]:
            _raise_bad_values(rows.numpy())
    xp = arrays.xp
    return xp.astype(arrays.view(array, expected), xp.float32)


def _check_host_action(action, expected: tuple[int, ...], dtype: np.dtype) -> np.ndarray:
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
    limit = float(np.finfo(dtype).max)
    if not (np.abs(array) <= limit).all():
        _raise_bad_values(array)
    return array


def _raise_bad_values(values: np.ndarray) -> None:
    nonfinite = np.unique(np.nonzero(~np.isfinite(values))[0])
    if nonfinite.size:
        raise ValueError(f"action: NaN or infinity in the actions of worlds {nonfinite.tolist()}")
    worlds = np.unique(np.nonzero(np.abs(values) > _FLOAT32_MAX)[0])
    raise ValueError(
        f"action: values beyond float32's range (magnitude above {_FLOAT32_MAX:.7g}, which "
        f"the device's float32 makes infinite) in the actions of worlds {worlds.tolist()}"
    )
