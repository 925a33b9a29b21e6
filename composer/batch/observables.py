"""Batched observables: each enabled observable of a task read for every world at once.

`batch_reader(observable, physics)` returns a function that reads the observable's value in
every world, an array with a leading `num_envs` axis. It dispatches on the observable's type
(`functools.singledispatch`). MJCF features (`MJCFFeature`) and entity root-body features
(`composer.entity.RootBodyFeature`, the pose and velocity of `FreePropObservableMixin`) are
read through their public `selection`, the `MJCFSelection` their CPU reading uses too
(`selection_reader`). A package registers readers for its own observable types with
`batch_reader.register`. Camera observables (`MJCFCamera`) are rendered together, once
per observation: with OpenGL on the CPU batch, exactly the CPU environment's images
(`composer.batch.gl_cameras`), by MuJoCo Warp's ray tracer on Warp
(`composer.batch.cameras`).

Readers that are `composer.batch.gather.FieldGather`s (the MJCF features, and readers
registered as such) are read together by one kernel launch; other readers are called one
by one and their values copied.

Only options that act on one sample are supported (a batch keeps no per-world buffers):
`update_interval` 1, `buffer_size` 1, `delay` 0, no corruptor; a named aggregator is the
identity on a buffer of one sample.
"""

import functools
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from composer.batch.gather import FieldGather, ObservationGather
from composer.entity import RootBodyFeature
from composer.observation.observable import base
from composer.observation.observable.mjcf import MJCFCamera, MJCFFeature
from composer.observation.observable.selection import MJCFSelection

__all__ = ["BatchObservables", "batch_reader", "selection_reader"]

Reader = Callable[[], Any]


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


def selection_reader(selection: MJCFSelection, physics) -> FieldGather:
    """Returns a reader of `selection` in every world of `physics`.

    The batched twin of `selection.reader(host_physics)`: it reads the entries of
    `physics.bind(selection.element).<selection.field>` that `selection.indices` pick, in
    every world.

    Args:
      selection: what to read, such as an observable's `selection`.
      physics: the `BatchPhysics` to read.

    Returns:
      A zero-argument function returning an array of shape (num_envs, *value shape).

    Raises:
      AttributeError: for a field the elements' kind has no batched attribute for.
    """
    field, index = physics.bind(selection.element).selection(selection.field)
    if not isinstance(index, (int, slice, np.integer)):
        index = physics.arrays.to_host(index)
    entries = np.arange(int(np.prod(field.c_shape))).reshape(field.c_shape)
    return FieldGather(physics, field, np.asarray(selection.select(entries[index]))[..., None])


@batch_reader.register(MJCFFeature)
@batch_reader.register(RootBodyFeature)
def _selected_feature(observable: MJCFFeature | RootBodyFeature, physics) -> Reader:
    return selection_reader(observable.selection, physics)


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


def _batch_cameras(cameras: Mapping[str, MJCFCamera], physics):
    """The renderer of the camera observables `cameras`: OpenGL on the CPU batch, bit for
    bit the CPU environment's images; MuJoCo Warp's ray tracer on Warp."""
    if physics.on_warp:
        from composer.batch.cameras import BatchCameras

        return BatchCameras(cameras, physics)
    from composer.batch.gl_cameras import GLBatchCameras

    return GLBatchCameras(cameras, physics)


class BatchObservables:
    """Reads the enabled observables of a task for every world, on the device.

    Args:
      observables: the task's observables by key (`task.observables`); disabled ones are
        skipped.
      physics: the `BatchPhysics` to read.
      strip_singleton_obs_buffer_dim: as in `composer.Environment`: False keeps each
        observation's leading buffer axis of length 1, so a world's observation has the
        shape the CPU environment gives it.
      readers: batched readers that replace the generic ones, by key
        (`BatchTask.observable_readers`).

    Raises:
      ValueError: for an option a batch cannot apply (see the module docstring).
      TypeError: for an observable no batched reader is registered for.
    """

    def __init__(
        self,
        observables: Mapping[str, base.Observable],
        physics,
        strip_singleton_obs_buffer_dim: bool,
        readers: Mapping[str, Reader] | None = None,
    ):
        readers = dict(readers or {})
        enabled = {name: o for name, o in observables.items() if o.enabled}
        cameras = {
            name: o
            for name, o in enabled.items()
            if isinstance(o, MJCFCamera) and name not in readers
        }
        for name, observable in enabled.items():
            _check_options(name, observable)
        self._cameras = _batch_cameras(cameras, physics) if cameras else None
        if self._cameras is not None:
            readers.update(self._cameras.readers())
        try:
            self._readers = self._make_readers(enabled, physics, readers)
        except BaseException:
            self.close()
            raise
        self._image_names = frozenset(cameras)
        self._add_buffer_axis = not strip_singleton_obs_buffer_dim
        self._xp = physics.xp
        self._float_dtype = physics.float_dtype
        self._float_type = getattr(physics.xp, physics.float_dtype.name)
        gathered = {
            name: reader
            for name, reader in self._readers.items()
            if isinstance(reader, FieldGather) and reader.gatherable
        }
        self._gather = ObservationGather(physics, gathered) if gathered else None
        self._called = {name: r for name, r in self._readers.items() if name not in gathered}

    @staticmethod
    def _make_readers(enabled, physics, readers: Mapping[str, Reader]) -> dict[str, Reader]:
        """A reader per enabled observable: the given one, or the registered one."""
        made = {}
        for name, observable in enabled.items():
            reader = readers.get(name)
            made[name] = batch_reader(observable, physics) if reader is None else reader
        return made

    @property
    def cameras(self):
        """What renders the camera observables (`composer.batch.gl_cameras.GLBatchCameras`
        on the CPU batch, `composer.batch.cameras.BatchCameras` on MuJoCo Warp), or None
        when no enabled observable is a camera."""
        return self._cameras

    def close(self) -> None:
        """Releases what the cameras hold (the CPU batch's OpenGL contexts and threads)."""
        if self._cameras is not None:
            self._cameras.close()

    def dtype(self, name: str) -> np.dtype:
        """The NumPy dtype of observation `name`: the batch's float dtype, or a camera
        image's own."""
        if name in self._image_names:
            return self._cameras.dtype(name)
        return self._float_dtype

    def read(self) -> dict[str, Any]:
        """Returns the current observation of every world, by key, as new arrays.

        Features have the batch's float dtype; camera images have their CPU observable's
        dtype (`dtype`).

        Returns:
          A dict of arrays of the batch's namespace, of shape (num_envs, 1, *value shape),
          or (num_envs, *value shape) with `strip_singleton_obs_buffer_dim`.
        """
        xp = self._xp
        if self._cameras is not None:
            self._cameras.render()
        values = self._gather.read() if self._gather is not None else {}
        for name, read in self._called.items():
            value = read()
            dtype = value.dtype if name in self._image_names else self._float_type
            values[name] = xp.astype(value, dtype, copy=True)
        if not self._add_buffer_axis:
            return {name: values[name] for name in self._readers}
        return {name: values[name][:, None, ...] for name in self._readers}
