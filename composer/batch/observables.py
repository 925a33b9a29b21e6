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
from typing import Any, NamedTuple

import numpy as np

from composer.batch import _warp, kernels
from composer.batch.outputs import DeviceOutputs
from composer.entity import _RootBodyFeature
from composer.observation.observable import base
from composer.observation.observable.mjcf import MJCFFeature

__all__ = ["BatchObservables", "FieldSelection", "batch_reader"]

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


class FieldSelection(NamedTuple):
    """An observable that is a fixed selection of one field's entries in every world.

    Calling it reads the selection on the host; `BatchObservables.read_device` gathers it on
    the device instead, without a host round trip.

    Attributes:
      field: the batched MjModel/MjData field (`BatchPhysics.field`).
      columns: int array, the flat indices into one world's field of the observation's
        entries, in the shape of one world's observation.
    """

    field: Any
    columns: np.ndarray

    def __call__(self) -> np.ndarray:
        values = self.field.read()
        return values.reshape(values.shape[0], -1)[:, self.columns]


def _selection(binding, kind: str, indices) -> FieldSelection:
    """The entries of `binding.<kind>` that the per-world `indices` select, in turn."""
    field, index = binding._field_and_index(kind)
    columns = np.arange(int(np.prod(field.c_shape))).reshape(field.c_shape)[index]
    for key in indices:
        columns = columns[key]
    return FieldSelection(field, np.asarray(columns))


@batch_reader.register
def _mjcf_feature(observable: MJCFFeature, physics) -> Reader:
    # MJCFFeature keeps its field name, elements and indices private; this reader is its
    # batched twin in the same package.
    binding = physics.bind(observable._mjcf_element)
    return _selection(binding, observable._kind, observable._indices)


@batch_reader.register
def _root_body_feature(observable: _RootBodyFeature, physics) -> Reader:
    binding = physics.bind(observable._entity.root_body)
    return _selection(binding, observable._kind, (observable._index,))


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
        self._num_envs = physics.num_envs
        self._gathers: dict[str, _DeviceGather] | None = None

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

    def read_device(self, outputs: DeviceOutputs) -> dict[str, Any]:
        """Returns the current observation of every world as new Warp arrays on the device.

        A `FieldSelection` of a float32 field is gathered on the device by one kernel launch,
        without a host round trip; any other observable is read on the host and copied to
        the device.

        Returns:
          A dict of Warp arrays, shaped as `read` shapes its arrays.
        """
        if self._gathers is None:
            self._gathers = _plan_gathers(self._readers, outputs)
        wp = _warp.load()[0]
        observation = {}
        for name, read in self._readers.items():
            gather = self._gathers.get(name)
            if gather is None:
                value = outputs.upload(np.asarray(read()))
            else:
                value = outputs.empty((self._num_envs, gather.columns.shape[0]))
                wp.launch(
                    kernels.kernels().gather_columns,
                    dim=value.shape,
                    inputs=[gather.source, gather.columns, value],
                    device=outputs.device,
                )
                value = value.reshape((self._num_envs, *gather.shape))
            if self._add_buffer_axis:
                value = value.reshape((value.shape[0], 1, *value.shape[1:]))
            observation[name] = value
        return observation


class _DeviceGather(NamedTuple):
    """What `read_device` launches for one observable: source rows and their columns."""

    source: Any
    columns: Any
    shape: tuple[int, ...]


def _plan_gathers(readers: Mapping[str, Reader], outputs: DeviceOutputs) -> dict:
    """The device gathers of the readers that are float32 `FieldSelection`s, by key."""
    wp = _warp.load()[0]
    gathers = {}
    for name, read in readers.items():
        if not isinstance(read, FieldSelection):
            continue
        source = read.field.device_rows()
        if source is None:
            continue
        columns = wp.array(read.columns.ravel().astype(np.int32), device=outputs.device)
        gathers[name] = _DeviceGather(source, columns, read.columns.shape)
    return gathers
