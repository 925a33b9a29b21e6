"""Builds MuJoCo Warp's CUDA kernel cache of a batched manipulation task, without a GPU.

    python -m manipulation.batch.kernel_cache --task reach_site_features --arch sm_90 \\
        --out .cache/warp

then point the GPU run at the same directory (`COMPOSER_WARP_KERNEL_CACHE=.cache/warp`):
the modules load from it instead of compiling. See `composer.batch.kernel_cache` for how
and its limits.
"""

import argparse
import os
import re
from collections.abc import Sequence

from composer.batch import _warp
from manipulation.tasks import task_constants as tc

__all__ = ["main", "parse_arch"]


def parse_arch(text: str) -> int:
    """'sm_90', 'sm90' or '90' as the integer 90."""
    match = re.fullmatch(r"(?:sm_?)?(\d{2,3})", text.strip())
    if not match:
        raise argparse.ArgumentTypeError(
            f"expected a CUDA architecture such as sm_90, got {text!r}"
        )
    return int(match.group(1))


def main(argv: Sequence[str] | None = None) -> None:
    """The command line: builds the cache of each `--task` for `--arch` in `--out`."""
    parser = argparse.ArgumentParser(
        prog="python -m manipulation.batch.kernel_cache", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--task", action="append", required=True, help="a batched task name")
    parser.add_argument("--arch", type=parse_arch, required=True, help="e.g. sm_90 (H100, H200)")
    parser.add_argument("--out", required=True, help="the kernel cache directory")
    parser.add_argument("--jobs", type=int, default=None, help="parallel compiles (cores)")
    args = parser.parse_args(argv)
    # Read by composer.batch._warp when it first initialises Warp, below.
    os.environ[_warp.KERNEL_CACHE_ENV] = args.out
    from composer.batch.kernel_cache import build_cuda_cache
    from manipulation import batch as manipulation_batch

    for name in args.task:
        build = build_cuda_cache(
            lambda name=name: manipulation_batch.load(
                name,
                2,
                seed=0,
                device="warp-cpu",
                namespace="torch",
                # Two control steps: the worlds reset within the steps run.
                time_limit=1.5 * tc.CONTROL_TIMESTEP,
            ),
            arch=args.arch,
            jobs=args.jobs,
        )
        print(
            f"{name}: {build.modules} modules for sm_{args.arch}, {build.compiled} binaries "
            f"compiled in {build.seconds:.0f} s into {build.directory}"
        )


if __name__ == "__main__":
    main()
