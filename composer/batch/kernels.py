"""The Warp kernels of `composer.batch`, defined on first use (importing this needs no Warp).

Every kernel works on two-dimensional arrays whose first axis is the world, as views of
MuJoCo Warp's per-world arrays made by `rows`.
"""

from types import SimpleNamespace
from typing import Any

from composer.batch import _warp

__all__ = ["kernels", "rows"]

_kernels: SimpleNamespace | None = None


def kernels() -> SimpleNamespace:
    """The kernels, compiled by Warp at their first launch.

    Returns:
      A namespace with `restore_columns`, `copy_worlds`, `gather_columns`, `count_nonfinite`
      and `write_float32` (documented on each).
    """
    global _kernels
    if _kernels is None:
        _kernels = _define(_warp.load()[0])
    return _kernels


def rows(array, dtype, nrows: int):
    """A (nrows, entries per row) alias of the contiguous Warp `array`, read as `dtype`.

    `nrows` is the number of worlds the array holds (1 for a model field shared by every
    world); the memory is the array's own.
    """
    wp = _warp.load()[0]
    per_row = array.capacity // nrows // wp.types.type_size_in_bytes(dtype)
    return wp.array(
        ptr=array.ptr, dtype=dtype, shape=(nrows, per_row), device=array.device, copy=False
    )


def _define(wp) -> SimpleNamespace:
    @wp.kernel(module="unique")
    def restore_columns(
        columns: wp.array(dtype=wp.int32),
        saved: wp.array2d(dtype=wp.float32),
        target: wp.array2d(dtype=wp.float32),
    ):
        """target[world, c] = saved[world, c] for each c in `columns`."""
        world, k = wp.tid()
        column = columns[k]
        target[world, column] = saved[world, column]

    @wp.kernel(module="unique")
    def copy_worlds(
        keep: wp.array(dtype=wp.bool),
        source: wp.array2d(dtype=wp.uint8),
        target: wp.array2d(dtype=wp.uint8),
    ):
        """Copies the bytes of the worlds where `keep` is true from `source` to `target`."""
        world, k = wp.tid()
        if keep[world]:
            target[world, k] = source[world, k]

    @wp.kernel(module="unique")
    def gather_columns(
        source: wp.array2d(dtype=wp.float32),
        columns: wp.array(dtype=wp.int32),
        out: wp.array2d(dtype=wp.float32),
    ):
        """out[world, j] = source[world, columns[j]]; a one-row source serves every world."""
        world, j = wp.tid()
        out[world, j] = source[world % source.shape[0], columns[j]]

    @wp.kernel(module="unique")
    def count_nonfinite(values: wp.array2d(dtype=Any), count: wp.array(dtype=wp.int32)):
        """Adds the number of NaN or infinite entries of `values` to count[0]."""
        i, j = wp.tid()
        if not wp.isfinite(values[i, j]):
            wp.atomic_add(count, 0, 1)

    @wp.kernel(module="unique")
    def write_float32(source: wp.array2d(dtype=Any), target: wp.array2d(dtype=wp.float32)):
        """target[i, j] = float32(source[i, j])."""
        i, j = wp.tid()
        target[i, j] = wp.float32(source[i, j])

    return SimpleNamespace(
        restore_columns=restore_columns,
        copy_worlds=copy_worlds,
        gather_columns=gather_columns,
        count_nonfinite=count_nonfinite,
        write_float32=write_float32,
    )
