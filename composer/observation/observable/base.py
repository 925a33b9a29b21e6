"""Observables: named, configurable quantities that an agent can observe.

An observable turns a `Physics` into a NumPy array. How often it is sampled, how many
samples the agent sees, how late they arrive and how they are reduced and corrupted are
options of the observable; the `Updater` applies them.
"""

import abc
import functools
import numbers
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np
from dm_env import specs


def _with_bounds_flag(function: Callable, preserves_bounds: bool) -> Callable:
    function.preserves_bounds = preserves_bounds
    return function


def _mean(buffer: np.ndarray) -> np.ndarray:
    """np.mean over axis 0; for float64 the same arithmetic without np.mean's dispatch."""
    if buffer.dtype == np.float64:
        return np.add.reduce(buffer, axis=0) / buffer.shape[0]
    return np.mean(buffer, axis=0)


# Reductions over the leading (buffer) axis, equal to np.min/max/mean/median/sum(axis=0).
# `preserves_bounds` tells the updater whether a bounded observable stays within its bounds
# once aggregated.
AGGREGATORS = {
    "min": _with_bounds_flag(functools.partial(np.minimum.reduce, axis=0), True),
    "max": _with_bounds_flag(functools.partial(np.maximum.reduce, axis=0), True),
    "mean": _with_bounds_flag(_mean, True),
    "median": _with_bounds_flag(functools.partial(np.median, axis=0), True),
    "sum": _with_bounds_flag(functools.partial(np.add.reduce, axis=0), False),
}


def _resolve_aggregator(name_or_callable: str | Callable | None) -> Callable | None:
    """Returns the reduction for a name, callable or None.

    Raises:
      KeyError: for a name that is not one of `AGGREGATORS`, as dm_control does.
      TypeError: for anything else that is not callable.
    """
    if name_or_callable is None or callable(name_or_callable):
        return name_or_callable
    if isinstance(name_or_callable, str):
        try:
            return AGGREGATORS[name_or_callable]
        except KeyError:
            raise KeyError(
                f"aggregator: unknown name {name_or_callable!r}; expected one of "
                f"{sorted(AGGREGATORS)} or a callable reducing the buffer axis"
            ) from None
    raise TypeError(
        f"aggregator: expected a name from {sorted(AGGREGATORS)}, a callable or None, "
        f"got {name_or_callable!r}"
    )


def _check_count_option(owner: Any, option: str, value: Any, minimum: int) -> Any:
    """Validates an option that is None, a callable, or an integer >= `minimum`."""
    if value is None or callable(value):
        return value
    if isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= minimum:
        return int(value)
    raise ValueError(
        f"{owner!r}: option {option!r} must be an integer >= {minimum}, a callable or None; "
        f"got {value!r}"
    )


def _check_image_size(owner: Any, option: str, value: Any) -> int:
    if isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= 1:
        return int(value)
    raise ValueError(f"{owner!r}: option {option!r} must be an integer >= 1; got {value!r}")


def view_source(value) -> tuple[np.ndarray, np.ndarray] | None:
    """Where a view of memory that NumPy does not own (such as a MuJoCo array's) reads from.

    Returns (flat, indices): `flat` a 1-D view of the whole C-contiguous array that `value`
    is a view of, and `indices` of `value`'s shape with `flat[indices]` equal to `value`.
    None for anything else: a copy, a scalar, or a view that does not step through whole
    elements.
    """
    if not isinstance(value, np.ndarray):
        return None
    root = value
    while isinstance(root.base, np.ndarray):
        root = root.base
    if root.flags.owndata or root.base is None:
        return None
    if not root.flags.c_contiguous or root.dtype != value.dtype:
        return None
    itemsize = value.itemsize
    offset = value.__array_interface__["data"][0] - root.__array_interface__["data"][0]
    if offset % itemsize or any(stride % itemsize for stride in value.strides):
        return None
    # Element offsets in C order, in plain Python: observed values have a few elements.
    indices = [offset // itemsize]
    for length, stride in zip(value.shape, value.strides):
        step = stride // itemsize
        indices = [index + k * step for index in indices for k in range(length)]
    if indices and (min(indices) < 0 or max(indices) >= root.size):
        return None
    return root.reshape(-1), np.array(indices, dtype=np.intp).reshape(value.shape)


def _camera_id(physics, camera) -> int:
    """Returns the id of `camera` (an id, or a name in the compiled model) in `physics`."""
    if isinstance(camera, str):
        index = mujoco.mj_name2id(physics.model.ptr, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        if index < 0:
            raise ValueError(f"no camera named {camera!r} in the compiled model")
        return index
    return int(camera)


class Observable(metaclass=abc.ABCMeta):
    """A quantity an agent can observe, with the options that say how it is observed.

    Subclasses implement `_callable(physics)`, returning a zero-argument function that reads
    the current value from `physics`.

    Options (all settable after construction, and through `configure(**options)`):
      update_interval: physics steps between two samples (default 1). An int >= 1, or a
        callable drawn again for every sample; a callable that accepts a `random_state`
        keyword (such as a `composer.variation` object) receives the environment's.
      buffer_size: number of most recent samples in each observation (default 1). The
        observation gets a leading axis of this length.
      delay: physics steps between taking a sample and the agent seeing it (default 0).
        An int >= 0 or a callable, like `update_interval`.
      aggregator: reduces the buffer axis: one of 'min', 'max', 'mean', 'median', 'sum', or a
        callable taking the buffered array.
      corruptor: `corruptor(value, random_state=...)` returning a corrupted value (noise,
        dropout), applied to every sample.
      enabled: whether an environment observes it. False until a task enables it.
    """

    def __init__(self, update_interval, buffer_size, delay, aggregator, corruptor):
        self.update_interval = update_interval
        self.buffer_size = buffer_size
        self.delay = delay
        self.aggregator = aggregator
        self.corruptor = corruptor
        self._enabled = False

    @property
    def update_interval(self):
        return self._update_interval

    @update_interval.setter
    def update_interval(self, value):
        self._update_interval = _check_count_option(self, "update_interval", value, 1)

    @property
    def buffer_size(self):
        return self._buffer_size

    @buffer_size.setter
    def buffer_size(self, value):
        if callable(value):
            raise ValueError(f"{self!r}: option 'buffer_size' must be an integer >= 1 or None")
        self._buffer_size = _check_count_option(self, "buffer_size", value, 1)

    @property
    def delay(self):
        return self._delay

    @delay.setter
    def delay(self, value):
        self._delay = _check_count_option(self, "delay", value, 0)

    @property
    def aggregator(self):
        return self._aggregator

    @aggregator.setter
    def aggregator(self, value):
        try:
            self._aggregator = _resolve_aggregator(value)
        except KeyError as exc:
            raise KeyError(f"{self!r}: {exc.args[0]}") from None
        except TypeError as exc:
            raise TypeError(f"{self!r}: {exc}") from None

    @property
    def corruptor(self):
        return self._corruptor

    @corruptor.setter
    def corruptor(self, value):
        if value is not None and not callable(value):
            raise TypeError(f"{self!r}: option 'corruptor' must be a callable or None")
        self._corruptor = value

    @property
    def enabled(self) -> bool:
        return self._enabled

    @enabled.setter
    def enabled(self, value: bool):
        self._enabled = bool(value)

    @property
    def array_spec(self) -> specs.Array | None:
        """The spec of one sample, or None when it is found by sampling once at reset."""
        return None

    @abc.abstractmethod
    def _callable(self, physics) -> Callable[[], Any]:
        """Returns a zero-argument function reading this observable's value from `physics`."""

    def observation_callable(self, physics, random_state=None) -> Callable[[], Any]:
        """Returns a zero-argument function returning the (corrupted) value for `physics`."""
        raw = self._callable(physics)
        corruptor = self._corruptor
        if corruptor is None:
            return raw

        def corrupted():
            return corruptor(raw(), random_state=random_state)

        return corrupted

    def live_source(self, physics) -> tuple[np.ndarray, np.ndarray] | None:
        """Where in the physics' memory this observable's value always is, or None.

        Returns (array, indices), `array` 1-D, such that `array[indices]` equals what the
        observation callable would return at any time, provided the physics has no pending
        `forward()` (`physics.is_dirty` is False). The updater samples such observables by
        gathering many at once, instead of calling them; it asks once per physics and keeps
        the answer for later episodes while the observable's options stay the same. None for
        an observable with a corruptor, and by default; subclasses whose value is a fixed
        part of a MuJoCo array implement `_live_source(physics)`, often with
        `view_source(view)`.
        """
        if self._corruptor is not None:
            return None
        return self._live_source(physics)

    def _live_source(self, physics) -> tuple[np.ndarray, np.ndarray] | None:
        """The (array, indices) `live_source` returns without a corruptor, or None."""
        return None

    def observation_writer(self, physics, out: np.ndarray) -> Callable[[], Any] | None:
        """A zero-argument function that writes the current value into `out`, or None.

        `out` is an array of the shape and dtype of one sample. Like `live_source`, the
        function reads the physics' memory directly, is only used while the physics has no
        pending `forward()`, and is kept for later episodes with the same physics; the
        updater calls it instead of the observation callable for observables that keep one
        undelayed sample. None for an observable with a corruptor, and by default;
        subclasses that compute their value into a preallocated array implement
        `_writer(physics, out)`.
        """
        if self._corruptor is not None:
            return None
        return self._writer(physics, out)

    def _writer(self, physics, out: np.ndarray) -> Callable[[], Any] | None:
        """The function `observation_writer` returns without a corruptor, or None."""
        return None

    def __call__(self, physics, random_state=None):
        """Returns the current (corrupted) value for `physics`."""
        return self.observation_callable(physics, random_state)()

    def configure(self, **options) -> None:
        """Sets several options at once; an unknown option name is an AttributeError."""
        for name, value in options.items():
            if not hasattr(self, name):
                raise AttributeError(f"{self!r}: cannot configure unknown option {name!r}")
            setattr(self, name, value)

    def __getitem__(self, key) -> "Observable":
        """Returns a new, disabled observable whose value is this one's value indexed by `key`.

        The new observable starts with this one's options; afterwards each has its own. A
        corruptor is applied to the indexed value. (`MJCFFeature` returns an `MJCFFeature`.)
        """
        return _Indexed(self, key)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} observable>"


class _Indexed(Observable):
    """`source[key]`: the value of another observable, indexed."""

    def __init__(self, source: Observable, key):
        self._source = source
        self._key = key
        super().__init__(
            source.update_interval,
            source.buffer_size,
            source.delay,
            source.aggregator,
            source.corruptor,
        )

    def _callable(self, physics):
        read, key = self._source._callable(physics), self._key
        return lambda: np.asarray(read())[key]

    def _live_source(self, physics):
        source = self._source._live_source(physics)
        if source is None:
            return None
        flat, indices = source
        return flat, np.asarray(indices[self._key])

    def __repr__(self) -> str:
        return f"{self._source!r}[{self._key!r}]"


class Generic(Observable):
    """An observable computed by `raw_observation_callable(physics)`."""

    def __init__(
        self,
        raw_observation_callable: Callable,
        update_interval=1,
        buffer_size=None,
        delay=None,
        aggregator=None,
        corruptor=None,
    ):
        if not callable(raw_observation_callable):
            raise TypeError(
                f"Generic: raw_observation_callable must be callable, got "
                f"{raw_observation_callable!r}"
            )
        self._raw_callable = raw_observation_callable
        super().__init__(update_interval, buffer_size, delay, aggregator, corruptor)

    def _callable(self, physics):
        return functools.partial(self._raw_callable, physics)

    def __repr__(self) -> str:
        name = getattr(self._raw_callable, "__qualname__", repr(self._raw_callable))
        return f"<Generic observable of {name}>"


class MujocoFeature(Observable):
    """An observable reading `physics.named.data.<kind>[feature_name]`.

    `feature_name` is a name or list of names in the compiled model, or a zero-argument
    callable returning them (evaluated at every sample).
    """

    def __init__(
        self,
        kind: str,
        feature_name,
        update_interval=1,
        buffer_size=None,
        delay=None,
        aggregator=None,
        corruptor=None,
    ):
        self._kind = kind
        self._feature_name = feature_name
        super().__init__(update_interval, buffer_size, delay, aggregator, corruptor)

    def _callable(self, physics):
        indexer = getattr(physics.named.data, self._kind)
        feature_name = self._feature_name
        if callable(feature_name):
            return lambda: indexer[feature_name()]
        return lambda: indexer[feature_name]

    def _live_source(self, physics):
        if callable(self._feature_name):
            return None
        return view_source(getattr(physics.named.data, self._kind)[self._feature_name])

    def __repr__(self) -> str:
        return f"<MujocoFeature observable {self._kind}[{self._feature_name!r}]>"


_BOTH_SEGMENTATION_AND_DEPTH_ENABLED = "'depth' and 'segmentation' cannot both be True"


class _ImageObservable(Observable):
    """Shared image options and spec of the camera observables."""

    def __init__(
        self,
        *,
        height,
        width,
        update_interval,
        buffer_size,
        delay,
        aggregator,
        corruptor,
        depth,
        segmentation,
        scene_option,
        render_flag_overrides,
    ):
        self.height = height
        self.width = width
        self._depth = bool(depth)
        self._segmentation = bool(segmentation)
        self._check_image_kind()
        self.scene_option = scene_option
        self.render_flag_overrides = render_flag_overrides
        super().__init__(update_interval, buffer_size, delay, aggregator, corruptor)

    def _check_image_kind(self):
        if self._depth and self._segmentation:
            raise ValueError(f"{self!r}: {_BOTH_SEGMENTATION_AND_DEPTH_ENABLED}")

    @property
    def height(self) -> int:
        return self._height

    @height.setter
    def height(self, value):
        self._height = _check_image_size(self, "height", value)

    @property
    def width(self) -> int:
        return self._width

    @width.setter
    def width(self, value):
        self._width = _check_image_size(self, "width", value)

    @property
    def depth(self) -> bool:
        return self._depth

    @depth.setter
    def depth(self, value):
        self._depth = bool(value)
        self._check_image_kind()

    @property
    def segmentation(self) -> bool:
        return self._segmentation

    @segmentation.setter
    def segmentation(self, value):
        self._segmentation = bool(value)
        self._check_image_kind()

    @property
    def scene_option(self):
        return self._scene_option

    @scene_option.setter
    def scene_option(self, value):
        self._scene_option = value

    @property
    def render_flag_overrides(self):
        return self._render_flag_overrides

    @render_flag_overrides.setter
    def render_flag_overrides(self, value):
        self._render_flag_overrides = value

    @property
    def array_spec(self) -> specs.BoundedArray:
        """The spec of one image, with the bounds of its pixel values.

        (height, width, 3) uint8 RGB in [0, 255]; (height, width, 1) float32 depth in
        metres, in [0, inf); or (height, width, 2) int32 segmentation (object id, object
        type), from -1 (background) up.
        """
        if self._depth:
            shape, dtype, minimum, maximum = (1,), np.float32, 0.0, np.inf
        elif self._segmentation:
            shape, dtype, minimum, maximum = (2,), np.int32, -1, np.iinfo(np.int32).max
        else:
            shape, dtype, minimum, maximum = (3,), np.uint8, 0, 255
        return specs.BoundedArray(
            (self._height, self._width) + shape, dtype, minimum=minimum, maximum=maximum
        )

    def _render_function(self, physics, camera):
        """Returns a zero-argument function rendering `camera` (a name or an id)."""
        kwargs = dict(
            height=self._height,
            width=self._width,
            camera_id=_camera_id(physics, camera),
            depth=self._depth,
            segmentation=self._segmentation,
            scene_option=self._scene_option,
        )
        if self._render_flag_overrides is not None:
            kwargs["render_flag_overrides"] = self._render_flag_overrides

        def render():
            return np.atleast_3d(physics.render(**kwargs))

        return render


class MujocoCamera(_ImageObservable):
    """Images rendered from the camera named `camera_name` in the compiled model."""

    def __init__(
        self,
        camera_name,
        height=240,
        width=320,
        update_interval=1,
        buffer_size=None,
        delay=None,
        aggregator=None,
        corruptor=None,
        depth=False,
        segmentation=False,
        scene_option=None,
        render_flag_overrides=None,
    ):
        self._camera_name = camera_name
        super().__init__(
            height=height,
            width=width,
            update_interval=update_interval,
            buffer_size=buffer_size,
            delay=delay,
            aggregator=aggregator,
            corruptor=corruptor,
            depth=depth,
            segmentation=segmentation,
            scene_option=scene_option,
            render_flag_overrides=render_flag_overrides,
        )

    def _callable(self, physics):
        return self._render_function(physics, self._camera_name)

    def __repr__(self) -> str:
        return f"<MujocoCamera observable {self._camera_name!r}>"
