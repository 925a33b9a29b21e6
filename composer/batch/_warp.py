"""Imports Warp and MuJoCo Warp on first use, with an install hint, and sets up their cache.

`import composer.batch` must work without the extra `[warp]` (so that its names can be
documented and its errors tested); only building a batch environment imports Warp.

Warp's native start-up prints "Warp CUDA warning: Could not find or load the NVIDIA CUDA
driver..." to the process's stderr on a machine without one. Warp has no setting that skips
looking for the driver, so unless a CUDA device was asked for, `load` runs Warp's start-up
with stderr caught and passes on everything but that line: a user who asked for the CPU
device (or for none) is not told about a GPU they did not ask for.
"""

import os
import sys
import tempfile
from types import ModuleType
from typing import NamedTuple

#: The environment variable naming the directory for Warp's compiled kernels. Unset, Warp
#: keeps its own default (a per-user cache directory).
KERNEL_CACHE_ENV = "COMPOSER_WARP_KERNEL_CACHE"

_INSTALL_HINT = "composer.batch needs MuJoCo Warp: pip install 'mujoco-composer[warp]'"


class WarpModules(NamedTuple):
    """The two modules a batch runs on, as `load` returns them.

    Attributes:
      warp: the `warp` module (NVIDIA Warp), initialised: arrays, kernels, launches.
      mujoco_warp: the `mujoco_warp` module: `put_model`, `put_data`, `step`, `forward`.
    """

    warp: ModuleType
    mujoco_warp: ModuleType


_modules: WarpModules | None = None

# The line Warp's native start-up prints where no CUDA driver loads.
_NO_DRIVER_WARNING = "Could not find or load the NVIDIA CUDA driver"


def load(device: str | None = None) -> WarpModules:
    """Returns the `warp` and `mujoco_warp` modules, imported and initialised once.

    Args:
      device: the Warp device the caller will use, if it knows: unless it names a CUDA
        device, Warp's warning that it found no CUDA driver is left out (see the module
        docstring). Only the first call's initialises Warp.

    Returns:
      `WarpModules`: `warp` (logging warnings only, its kernel cache in
      `$COMPOSER_WARP_KERNEL_CACHE` when that is set) and `mujoco_warp`.

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
        if device is not None and str(device).startswith("cuda"):
            warp.init()
        else:
            _init_without_driver_warning(warp)
        _modules = WarpModules(warp=warp, mujoco_warp=mujoco_warp)
    return _modules


def _init_without_driver_warning(warp: ModuleType) -> None:
    """Runs `warp.init()` with the process's stderr (file descriptor 2, where Warp's native
    code prints) caught, then writes what it printed back to stderr, less the no-driver
    warning."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        warp.init()  # no stderr descriptor to catch
        return
    with tempfile.TemporaryFile() as caught:
        os.dup2(caught.fileno(), 2)
        try:
            warp.init()
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
        caught.seek(0)
        printed = caught.read().decode("utf-8", errors="replace")
    kept = [line for line in printed.splitlines(True) if _NO_DRIVER_WARNING not in line]
    if kept:
        sys.stderr.write("".join(kept))
        sys.stderr.flush()


def is_available() -> bool:
    """Whether `mujoco_warp` and `warp` can be imported (without importing them)."""
    import importlib.util

    return all(importlib.util.find_spec(name) is not None for name in ("mujoco_warp", "warp"))
