"""MuJoCo Warp's CUDA kernels for one batch, compiled ahead of time on a machine without a GPU.

A cold start of a batch on a GPU compiles every kernel module MuJoCo Warp generates for the
model (minutes per model). Warp compiles CUDA code with NVRTC, which it ships and which needs
no GPU and no driver, so the modules can be built beforehand into Warp's kernel cache and
the cache copied to the GPU machine.

Which modules a batch needs is found by running it: `build_cuda_cache` runs a reset and a
few steps of a batch on Warp's CPU device, recording every kernel launched and the block
size CUDA would launch it with (a module's cache entry depends on it; Warp's CPU device
launches with one thread per block), then compiles each of those modules for the
architecture, as CUBIN and as PTX (Warp loads PTX when the driver is as new as Warp's CUDA
toolkit, CUBIN otherwise), into `warp.config.kernel_cache_dir`, under the names Warp looks
up when it loads the module on the GPU.

Limits: the few kernels MuJoCo Warp shapes differently on CUDA than on the CPU device (a
handful of solver and collision kernels size their thread groups from the device) are not
in the recording and still compile at their first launch on the GPU. A cache is valid only
for the same versions of Warp, MuJoCo Warp and this package, and for the same model.
"""

import concurrent.futures
import contextlib
import os
import time
from collections.abc import Callable, Iterator
from typing import Any, NamedTuple

import numpy as np

from composer.batch import _warp

__all__ = ["CacheBuild", "build_cuda_cache", "recorded_launches"]

# CUDA's block size of a launch that asks for none (Warp's default on CUDA).
_CUDA_DEFAULT_BLOCK_DIM = 256


class CacheBuild(NamedTuple):
    """What `build_cuda_cache` did.

    Attributes:
      modules: the kernel modules (by block size) the batch launched.
      compiled: the binaries compiled (CUBIN and PTX per module; cached ones are skipped).
      seconds: the time the compilation took.
      directory: Warp's kernel cache directory that holds them.
    """

    modules: int
    compiled: int
    seconds: float
    directory: str


@contextlib.contextmanager
def recorded_launches() -> Iterator[dict[tuple[int, int], tuple[Any, int]]]:
    """Records every `warp.launch` and `warp.launch_tiled` while the context is open.

    Yields:
      A dict filled as kernels launch: (id of the module, CUDA block size) -> (the
      `warp` module object, the block size a CUDA launch would use).
    """
    wp = _warp.load().warp
    launched: dict[tuple[int, int], tuple[Any, int]] = {}
    launch, launch_tiled = wp.launch, wp.launch_tiled

    def record(kernel, block_dim) -> None:
        cuda_block_dim = (
            _CUDA_DEFAULT_BLOCK_DIM if block_dim is None or block_dim <= 0 else int(block_dim)
        )
        launched[(id(kernel.module), cuda_block_dim)] = (kernel.module, cuda_block_dim)

    def recording_launch(kernel, *args, **kwargs):
        record(kernel, kwargs.get("block_dim"))
        return launch(kernel, *args, **kwargs)

    def recording_launch_tiled(kernel, *args, **kwargs):
        record(kernel, kwargs.get("block_dim"))
        return launch_tiled(kernel, *args, **kwargs)

    wp.launch, wp.launch_tiled = recording_launch, recording_launch_tiled
    try:
        yield launched
    finally:
        wp.launch, wp.launch_tiled = launch, launch_tiled


def build_cuda_cache(
    make_env: Callable[[], Any], *, arch: int, steps: int = 3, jobs: int | None = None
) -> CacheBuild:
    """Compiles the CUDA kernel modules of a batch for `arch` into Warp's kernel cache.

    Args:
      make_env: builds the `BatchEnvironment` on Warp's CPU device (with the torch
        namespace, the code path CUDA runs, and a time limit short enough that some worlds
        reset within `steps`).
      arch: the CUDA compute capability as an integer, 90 for sm_90 (H100, H200).
      steps: control steps to run after the reset (random actions within the spec).
      jobs: modules compiled at once (default: the host's cores).

    Returns:
      A `CacheBuild`.

    Raises:
      ValueError: for an environment that is not on Warp's CPU device, or an `arch` Warp's
        NVRTC cannot compile for (the message lists those it can).
    """
    wp = _warp.load().warp
    supported = sorted(wp._src.context.runtime.nvrtc_supported_archs)
    if arch not in supported:
        raise ValueError(f"arch: expected one of NVRTC's architectures {supported}, got {arch}")
    with recorded_launches() as launched:
        env = make_env()
        try:
            if env.physics.is_cuda:
                raise ValueError(
                    f"make_env: expected a batch on Warp's CPU device, got {env.physics.device}"
                )
            spec = env.action_spec()
            rng = np.random.default_rng(0)
            env.reset()
            for _ in range(steps):
                action = rng.uniform(spec.minimum, spec.maximum, (env.num_envs, *spec.shape))
                env.step(action.astype(np.float32))
        finally:
            env.close()
    begin = time.perf_counter()
    targets = []
    for module, block_dim in launched.values():
        module.get_module_hash(block_dim)  # resolves the module's options for block_dim
        targets += [(module, module.resolved_options[block_dim], ptx) for ptx in (False, True)]

    def compile_one(target) -> bool:
        module, options, use_ptx = target
        return bool(module._compile(None, output_arch=arch, use_ptx=use_ptx, options=options))

    # Warp runs NVRTC outside Python's lock: modules compile in parallel.
    with concurrent.futures.ThreadPoolExecutor(jobs or os.cpu_count() or 1) as pool:
        compiled = sum(pool.map(compile_one, targets))
    return CacheBuild(
        modules=len(launched),
        compiled=compiled,
        seconds=time.perf_counter() - begin,
        directory=str(wp.config.kernel_cache_dir),
    )
