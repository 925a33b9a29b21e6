"""`FlatLayout`: a batch of values of one space held in one contiguous buffer.

Each leaf of the space (an array of fixed shape and dtype: a `Box`, `Discrete`,
`MultiDiscrete` or `MultiBinary`, possibly inside `Dict`s and `Tuple`s) takes a fixed
span of bytes in every row, in the order of `gymnasium.vector.utils.create_empty_array`'s
leaves, each span starting at a multiple of 8 bytes. A batch of `rows` values is a
(rows, `row_bytes`) uint8 buffer whose leaves are views of it, so the whole batch
crosses a process boundary as one `bytes`, and two processes that build the layout of
equal spaces read each other's buffers. `FlatBatch` is such a buffer with its rows. A
`RayVectorEnv` sends its actions and receives its observations that way.
"""

from typing import Any, NamedTuple

import gymnasium
import numpy as np
from gymnasium.vector.utils import create_empty_array

from composer.gym.rows import row_views, row_writer

__all__ = ["FlatBatch", "FlatLayout", "leaves", "rebuilt"]

_ALIGNMENT = 8


class _Leaf(NamedTuple):
    """Where one leaf lies in a row: bytes [start, start + nbytes), as `dtype` of `shape`."""

    start: int
    nbytes: int
    shape: tuple[int, ...]
    dtype: np.dtype


def leaves(batch) -> list[np.ndarray]:
    """The arrays of `batch` (an array, or dict/tuple of them), depth first, in order."""
    if isinstance(batch, dict):
        return [leaf for part in batch.values() for leaf in leaves(part)]
    if isinstance(batch, tuple):
        return [leaf for part in batch for leaf in leaves(part)]
    return [batch]


class FlatLayout:
    """The byte layout of a batch of values of `space` (see the module docstring).

    Args:
      space: the space of one value (an observation or an action).

    Raises:
      TypeError: naming the leaf that is not an array of numbers (of a `Text`,
        `Sequence` or `Graph` space, say, which no vector env of this package batches).
    """

    def __init__(self, space: gymnasium.Space):
        self._template = create_empty_array(space, 1, fn=np.zeros)
        self._leaves: list[_Leaf] = []
        start = 0
        for position, leaf in enumerate(leaves(self._template)):
            if not isinstance(leaf, np.ndarray) or leaf.dtype.hasobject:
                got = (
                    f"an array of dtype {leaf.dtype}"
                    if isinstance(leaf, np.ndarray)
                    else type(leaf).__name__
                )
                raise TypeError(
                    f"{space}: leaf {position}: expected an array of numbers, got {got}"
                )
            self._leaves.append(_Leaf(start, leaf.nbytes, leaf.shape[1:], leaf.dtype))
            start += -(-leaf.nbytes // _ALIGNMENT) * _ALIGNMENT
        self.row_bytes: int = start

    def allocate(self, rows: int) -> np.ndarray:
        """A zeroed (rows, `row_bytes`) uint8 buffer."""
        return np.zeros((rows, self.row_bytes), np.uint8)

    def views(self, buffer: np.ndarray) -> Any:
        """The batch whose bytes are `buffer` (shaped as `allocate` makes it): arrays of
        shape (rows, *leaf shape), in the structure `create_empty_array` gives, that are
        views of `buffer`."""
        arrays = iter(
            buffer[:, leaf.start : leaf.start + leaf.nbytes]
            .view(leaf.dtype)
            .reshape(buffer.shape[:1] + leaf.shape)
            for leaf in self._leaves
        )
        return rebuilt(self._template, arrays)


def rebuilt(template, arrays):
    """`template`'s structure (an array, or dict/tuple of them) with its leaves taken in
    order from the iterator `arrays`: the inverse of `leaves`."""
    if isinstance(template, dict):
        return type(template)((key, rebuilt(part, arrays)) for key, part in template.items())
    if isinstance(template, tuple):
        return tuple(rebuilt(part, arrays) for part in template)
    return next(arrays)


class FlatBatch:
    """`size` values of one space in one buffer of its `FlatLayout`.

    `buffer` is the (size, row_bytes) uint8 buffer, `batch` its views (see
    `FlatLayout.views`), `rows[i]` the views of row i (see `row_views`).
    """

    def __init__(self, layout: FlatLayout, size: int):
        self.buffer = layout.allocate(size)
        self.batch = layout.views(self.buffer)
        self.rows = [row_views(self.batch, i) for i in range(size)]
        self._writers = [row_writer(row) for row in self.rows]

    def write(self, index: int, value: Any) -> None:
        """Copies `value` (laid out as the space) into row `index`, unless it is that row."""
        if value is not self.rows[index]:
            self._writers[index](value)
