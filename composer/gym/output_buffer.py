"""`OutputBuffer`: a vector env's batched step outputs in one buffer, copied out at once.

A vector env returns fresh arrays from every `step`: the observations (one array per leaf
of the observation space), the rewards, terminations and truncations. Copied one by one,
each is an allocation and a copy of its own (about 0.8 us apiece here, 9 us per step for
the 11 leaves of a manipulation task's observations). Here they are the fields of one
zero-dimensional structured array over one byte buffer, so a copy is one copy of the buffer
and a view per field (0.2 us apiece).

A copy nobody holds any more is recycled: `copy()` writes into the buffer of one of its
last two copies when nothing outside refers to it, its arrays or any view of them (their
reference counts are those it had when it was made), and returns the same arrays again.
So a loop that drops (or rebinds) what `step` returned gets its outputs without making a
Python object, and one that keeps them gets new arrays: an array is never written again
while anything refers to it. (Two copies, because `obs, *_ = env.step(policy(obs))` still
holds the previous step's outputs while the step runs.) Recycling needs exact reference
counts, so it is off where the interpreter runs without its global lock.

Each field is a C-contiguous array of shape (num_envs, *leaf shape) starting at a multiple
of 64 bytes. An observation space with a leaf that is not an array of numbers keeps its
observations out of the buffer: they are batched by
`gymnasium.vector.utils.create_empty_array` and copied leaf by leaf.
"""

import collections
import sys
from collections.abc import Callable
from typing import Any, NamedTuple

import gymnasium
import numpy as np
from gymnasium.vector.utils import create_empty_array

from composer.gym.flat_layout import leaves, rebuilt
from composer.gym.rows import batch_copier

__all__ = ["OutputBuffer", "StepOutputs"]

_ALIGNMENT = 64
_RECYCLED = 2  # copies kept for reuse (see the module docstring)
_new_tuple = tuple.__new__
_getrefcount = getattr(sys, "getrefcount", None)


class StepOutputs(NamedTuple):
    """The batched outputs of a vector step, each with one row per sub-environment."""

    observations: Any
    rewards: np.ndarray  # float64
    terminations: np.ndarray  # bool
    truncations: np.ndarray  # bool


class _Copy:
    """A copy's outputs, its buffer, and every object of it that a caller may hold, with
    their reference counts when nothing outside referred to them."""

    __slots__ = ("outputs", "buffer", "held", "counts")

    def __init__(self, outputs: StepOutputs, buffer: np.ndarray):
        self.outputs = outputs
        self.buffer = buffer
        # The record too: it is what `copy` returns, and it holds the rest.
        self.held = [buffer, outputs, *_containers_and_leaves(outputs.observations), *outputs[1:]]
        self.counts: list[int] = []

    def reference_counts(self) -> list[int]:
        return list(map(_getrefcount, self.held))


class OutputBuffer:
    """The batched outputs of `num_envs` sub-environments of `observation_space`.

    `live` holds the arrays the vector env writes into; `copy()` returns copies of all of
    them (possibly recycled ones, see the module docstring), `copy_observations()` a new
    copy of the observations only.

    Args:
      observation_space: one sub-environment's observation space.
      num_envs: the number of sub-environments (rows).
    """

    def __init__(self, observation_space: gymnasium.Space, num_envs: int):
        template = create_empty_array(observation_space, num_envs, fn=np.zeros)
        observation_leaves = leaves(template)
        in_buffer = all(
            isinstance(leaf, np.ndarray) and not leaf.dtype.hasobject for leaf in observation_leaves
        )
        shapes = [((num_envs,), np.float64), ((num_envs,), np.bool_), ((num_envs,), np.bool_)]
        if in_buffer:
            shapes += [(leaf.shape, leaf.dtype) for leaf in observation_leaves]
        self._dtype = _fields_dtype(shapes)
        self._bytes = np.zeros(self._dtype.itemsize, np.uint8)
        live = np.ndarray((), self._dtype, self._bytes)
        names = self._dtype.names
        if in_buffer:
            observations = rebuilt(template, iter(live[name] for name in names[3:]))
            self._read_observations = _reader(template, iter(names[3:]))
            self._copy_observations: Callable[[], Any] | None = None
        else:
            observations = template
            self._copy_observations = batch_copier(template)
        self.live = StepOutputs(observations, live[names[0]], live[names[1]], live[names[2]])
        gil = getattr(sys, "_is_gil_enabled", lambda: True)()
        self._recycles = bool(in_buffer and gil and _getrefcount is not None)
        # The last copies made, oldest first: a new one pushes out the oldest.
        self._copies: collections.deque[_Copy] = collections.deque(maxlen=_RECYCLED)

    def copy(self) -> StepOutputs:
        """Copies of every live array: a recycled copy nobody holds, or new arrays."""
        if self._recycles:
            for kept in self._copies:
                if kept.reference_counts() == kept.counts:
                    kept.buffer[...] = self._bytes
                    return kept.outputs
        new = self._new_copy()
        if self._recycles:
            new.counts = new.reference_counts()
            self._copies.append(new)
        return new.outputs

    def copy_observations(self) -> Any:
        """A new copy of the live observations (never a recycled one)."""
        return self._new_copy().outputs.observations

    def _new_copy(self) -> _Copy:
        buffer = self._bytes.copy()
        block = np.ndarray((), self._dtype, buffer)
        if self._copy_observations is None:
            observations = self._read_observations(block)
        else:
            observations = self._copy_observations()
        # tuple.__new__ skips the NamedTuple's Python-level __new__, on every step that
        # makes a copy.
        outputs = _new_tuple(StepOutputs, (observations, block["0"], block["1"], block["2"]))
        return _Copy(outputs, buffer)


def _fields_dtype(shapes: list[tuple[tuple[int, ...], np.dtype]]) -> np.dtype:
    """A structured dtype with fields "0", "1", ... of the given (shape, dtype), each at an
    offset that is a multiple of `_ALIGNMENT`."""
    names, formats, offsets = [], [], []
    offset = 0
    for position, (shape, dtype) in enumerate(shapes):
        names.append(str(position))
        formats.append((np.dtype(dtype), shape))
        offsets.append(offset)
        nbytes = int(np.prod(shape, dtype=np.int64)) * np.dtype(dtype).itemsize
        offset += -(-nbytes // _ALIGNMENT) * _ALIGNMENT
    return np.dtype(
        {"names": names, "formats": formats, "offsets": offsets, "itemsize": max(offset, 1)}
    )


def _containers_and_leaves(batch) -> list:
    """Every dict, tuple and array of `batch`, depth first."""
    if isinstance(batch, dict):
        return [batch, *(item for part in batch.values() for item in _containers_and_leaves(part))]
    if isinstance(batch, tuple):
        return [batch, *(item for part in batch for item in _containers_and_leaves(part))]
    return [batch]


def _reader(template, names) -> Callable[[np.ndarray], Any]:
    """A function of a block (a 0-d array of the fields dtype) returning `template`'s
    structure with each leaf the block's field, names taken in order from `names`.

    Built once: a flat dict of arrays, the usual observation, is one comprehension over
    the fields rather than a call per leaf.
    """
    if isinstance(template, dict):
        kind = type(template)
        if kind is dict and all(isinstance(part, np.ndarray) for part in template.values()):
            pairs = tuple((key, next(names)) for key in template)
            return lambda block: {key: block[field] for key, field in pairs}
        parts = [(key, _reader(part, names)) for key, part in template.items()]
        return lambda block: kind((key, read(block)) for key, read in parts)
    if isinstance(template, tuple):
        readers = [_reader(part, names) for part in template]
        return lambda block: tuple(read(block) for read in readers)
    field = next(names)
    return lambda block: block[field]
