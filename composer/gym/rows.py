"""Rows of a batched observation: views of one row, writers into it, copies of it.

A batched observation is an array, or a dict/tuple of them, whose leading axis is the
sub-environment. The vector envs (`sub_env_vector`, `flat_layout`) and the adapter
(`env.GymnasiumEnv.write_observations_to`) share these helpers; they import nothing of
this package, so neither side imports the other.
"""

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["attach_row", "batch_copier", "copied", "read_row", "row_views", "row_writer"]


def attach_row(env: Any, row: Any) -> None:
    """Makes `env` write its observations into `row` and return it, if its class has
    `write_observations_to` (a `GymnasiumEnv`). Looked up on the class, not the
    instance: a Gymnasium wrapper may keep or change what it returns, so it gets none."""
    if callable(getattr(type(env), "write_observations_to", None)):
        env.write_observations_to(row)


def batch_copier(batch) -> Callable[[], Any]:
    """A function returning a copy of `batch` (an array, or dict/tuple of them).

    Built once per vector env: walking the structure anew on every step costs twice
    as much, and it runs on every step of every vector env.
    """
    if isinstance(batch, dict):
        kind = type(batch)
        parts = [(key, batch_copier(part)) for key, part in batch.items()]
        if kind is dict:  # built as it is returned, not copied into another dict
            return lambda: {key: copy() for key, copy in parts}
        return lambda: kind({key: copy() for key, copy in parts})
    if isinstance(batch, tuple):
        copiers = [batch_copier(part) for part in batch]
        return lambda: tuple(copy() for copy in copiers)
    return batch.copy


def row_views(batch, index: int):
    """Row `index` of a batched observation (array, or dict/tuple of them), as views.

    A row of a batch of scalars is a 0-d array, so that it can be written in place.
    """
    if isinstance(batch, dict):
        return type(batch)((key, row_views(part, index)) for key, part in batch.items())
    if isinstance(batch, tuple):
        return tuple(row_views(part, index) for part in batch)
    return batch[index, ...]


def copied(observation):
    """`observation` (an array, or dict/tuple of them) with every array copied."""
    if isinstance(observation, dict):
        return type(observation)((key, copied(part)) for key, part in observation.items())
    if isinstance(observation, tuple):
        return tuple(copied(part) for part in observation)
    return observation.copy() if isinstance(observation, np.ndarray) else observation


def read_row(batch, index: int):
    """A copy of row `index` of a batched observation (array, or dict/tuple of them)."""
    return copied(row_views(batch, index))


def row_writer(row) -> Callable[[Any], None]:
    """A function `write(value)` that copies `value` into `row` (the views `row_views`
    returns), built once per row: assigning to a kept view costs half as much as
    indexing the batch anew."""
    if isinstance(row, dict):
        # Arrays are assigned here rather than by a writer each, which saves a Python
        # call per array on every step.
        arrays = [(key, part) for key, part in row.items() if isinstance(part, np.ndarray)]
        nested = [
            (key, row_writer(part)) for key, part in row.items() if not isinstance(part, np.ndarray)
        ]

        def write_dict(value) -> None:
            for key, view in arrays:
                view[...] = value[key]
            for key, write_part in nested:
                write_part(value[key])

        return write_dict
    if isinstance(row, tuple):
        writers = [row_writer(part) for part in row]

        def write_tuple(value) -> None:
            for write_part, item in zip(writers, value):
                write_part(item)

        return write_tuple

    def write_array(value) -> None:
        row[...] = value

    return write_array
