"""Imports Warp and MuJoCo Warp on first use, with an install hint, and sets up their cache.

`import composer.batch` must work without the extra `[warp]` (so that its names can be
documented and its errors tested); only building a batch environment imports Warp.
"""

import os
from types import ModuleType

#: The environment variable naming the directory for Warp's compiled kernels. Unset, Warp
#: keeps its own default (a per-user cache directory).
KERNEL_CACHE_ENV = "COMPOSER_WARP_KERNEL_CACHE"

_INSTALL_HINT = "composer.batch needs MuJoCo Warp: pip install 'mujoco-composer[warp]'"

_modules: tuple[ModuleType, ModuleType] | None = None


def load() -> tuple[ModuleType, ModuleType]:
    """Returns `(warp, mujoco_warp)`, imported and initialised once.

    Returns:
      The `warp` module (logging warnings only, its kernel cache in
      `$COMPOSER_WARP_KERNEL_CACHE` when that is set) and the `mujoco_warp` module.

    Raises:
      ImportError: when `mujoco_warp` or `warp` is not installed; the message says how to
        install them.
    """
    global _modules
    if _modules is None:
        try:
            import mujoco_warp
            import warp
        except ImportError as error:
            raise ImportError(f"{_INSTALL_HINT} ({error})") from error
        # Warp logs its start-up banner and every kernel module it loads at INFO.
        warp.config.log_level = warp.LOG_WARNING
        cache = os.environ.get(KERNEL_CACHE_ENV)
        if cache:
            warp.config.kernel_cache_dir = os.path.abspath(cache)
        warp.init()
        _modules = (warp, mujoco_warp)
    return _modules


def is_available() -> bool:
    """Whether `mujoco_warp` and `warp` can be imported (without importing them)."""
    import importlib.util

    return all(importlib.util.find_spec(name) is not None for name in ("mujoco_warp", "warp"))


def default_device() -> str:
    """'cuda:0' when Warp sees a CUDA device, else 'cpu', with a one-line warning that says so.

    Returns:
      A Warp device name.
    """
    import warnings

    warp = load()[0]
    if warp.get_cuda_device_count() > 0:
        return "cuda:0"
    warnings.warn(
        "composer.batch: Warp sees no CUDA device; the batch runs on Warp's CPU device "
        "(pass device='cpu' to say so and silence this)",
        RuntimeWarning,
        stacklevel=3,
    )
    return "cpu"
