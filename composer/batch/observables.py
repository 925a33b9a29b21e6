"""Batched observables: each enabled observable of a task read for every world at once.

`batch_reader(observable, physics)` returns a function that reads the observable's value in
every world, an array with a leading `num_envs` axis. It dispatches on the observable's type
(`functools.singledispatch`): MJCF features (`MJCFFeature`) and entity root-body features
(the pose and velocity of `FreePropObservableMixin`) are handled here; a package registers
readers for its own observable types with `batch_reader.register`.

Only options that act on one sample are supported (a batch keeps no per-world buffers):
`update_interval` 1, `buffer_size` 1, `delay` 0, no corruptor; a named aggregator is the
identity on a buffer of one sample.
"""

import functools
from collections.abc import Callable, Mapping

import numpy as np

from composer.entity import _RootBodyFeature
from composer.observation.observable import base
from composer.observation.observable.mjcf import MJCFFeature

__all__ = ["BatchObservables", "batch_reader"]

Reader = Callable[[], np.ndarray]


@functools.singledispatch
def batch_reader(observable: base.Observable, physics) -> Reader:
    """Returns a function reading `observable` in every world of `physics`.

    Returns:
      A zero-argument function returning an array of shape (num_envs, *value shape).

    Raises:
      TypeError: for an observable type no reader is registered for.
    """
    raise TypeError(
        f"observable {observable!r}: no batched reader for {type(observable).__name__}; "
        "register one with composer.batch.batch_reader.register"
    )


def _per_world(index) -> tuple:
    """The index that applies `index` (an index of one world's value) to every world."""
    return (slice(None),) + (index if isinstance(index, tuple) else (index,))


@batch_reader.register
def _mjcf_feature(observable: MJCFFeature, physics) -> Reader:
    # MJCFFeature keeps its field name, elements and indices private; this reader is its
    # batched twin in the same package.
    binding = physics.bind(observable._mjcf_element)
    kind = observable._kind
    keys = [_per_world(index) for index in observable._indices]

    def read():
        value = getattr(binding, kind)
        for key in keys:
            value = value[key]
        return value

    return read


@batch_reader.register
def _root_body_feature(observable: _RootBodyFeature, physics) -> Reader:
    binding = physics.bind(observable._entity.root_body)
    kind, key = observable._kind, _per_world(observable._index)
    return lambda: getattr(binding, kind)[key]


def _check_options(name: str, observable: base.Observable) -> None:
    """Raises ValueError naming `name` for an option a batch cannot apply."""
    unsupported = {
        "update_interval": (observable.update_interval, (None, 1)),
        "buffer_size": (observable.buffer_size, (None, 1)),
        "delay": (observable.delay, (None, 0)),
        "corruptor": (observable.corruptor, (None,)),
    }
    for option, (value, allowed) in unsupported.items():
        if value not in allowed:
            raise ValueError(
                f"observable {name!r}: option {option}={value!r} is not supported in a batch "
                f"(expected one of {allowed}); batched observables take one sample per step"
            )
    aggregator = observable.aggregator
    if aggregator is not None and aggregator not in base.AGGREGATORS.values():
        raise ValueError(
            f"observable {name!r}: a custom aggregator {aggregator!r} is not supported in a "
            f"batch (expected None or one of {sorted(base.AGGREGATORS)})"
        )


class BatchObservables:
    """Reads the enabled observables of a task for every world.

    Args:
      observables: the task's observables by key (`task.observables`); disabled ones are
        skipped.
      physics: the `BatchPhysics` to read.
      strip_singleton_obs_buffer_dim: as in `composer.Environment`: False keeps each
        observation's leading buffer axis of length 1, so a world's observation has the
        shape the CPU environment gives it.

    Raises:
      ValueError: for an option a batch cannot apply (see the module docstring).
      TypeError: for an observable no batched reader is registered for.
    """

    def __init__(
        self, observables: Mapping[str, base.Observable], physics, strip_singleton_obs_buffer_dim
    ):
        self._readers: dict[str, Reader] = {}
        for name, observable in observables.items():
            if not observable.enabled:
                continue
            _check_options(name, observable)
            self._readers[name] = batch_reader(observable, physics)
        self._add_buffer_axis = not strip_singleton_obs_buffer_dim

    def read(self) -> dict[str, np.ndarray]:
        """Returns the current observation of every world, by key.

        Returns:
          A dict of arrays of shape (num_envs, 1, *value shape), or (num_envs, *value shape)
          with `strip_singleton_obs_buffer_dim`.
        """
        observation = {}
        for name, read in self._readers.items():
            value = np.asarray(read())
            observation[name] = value[:, None] if self._add_buffer_axis else value
        return observation
