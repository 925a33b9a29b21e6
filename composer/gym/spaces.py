"""Gymnasium spaces from dm_env specs, and the flattening of feature observations.

`BoundedArray` becomes a `Box` with the same bounds, shape and dtype; `Array` an unbounded
`Box` (the widest range its dtype holds); a mapping of specs a `Dict` in the same order.
"""

import collections
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from dm_env import specs
from gymnasium import spaces


def box_from_spec(spec: specs.Array) -> spaces.Box:
    """Returns the `Box` holding exactly the arrays `spec` accepts.

    Raises:
      TypeError: if `spec` is not a `dm_env.specs.Array`.
    """
    if not isinstance(spec, specs.Array):
        raise TypeError(f"expected a dm_env.specs.Array, got {type(spec).__name__}: {spec!r}")
    dtype = np.dtype(spec.dtype)
    if isinstance(spec, specs.BoundedArray):
        low = np.broadcast_to(spec.minimum, spec.shape).astype(dtype)
        high = np.broadcast_to(spec.maximum, spec.shape).astype(dtype)
    elif np.issubdtype(dtype, np.integer):
        low = np.full(spec.shape, np.iinfo(dtype).min, dtype)
        high = np.full(spec.shape, np.iinfo(dtype).max, dtype)
    else:
        low = np.full(spec.shape, -np.inf, dtype)
        high = np.full(spec.shape, np.inf, dtype)
    return spaces.Box(low=low, high=high, shape=spec.shape, dtype=dtype)


def space_from_spec(spec) -> spaces.Space:
    """Returns a `Box` for an array spec, a `Dict` (same keys, same order) for a mapping.

    Raises:
      TypeError: if `spec` or one of its values is neither an array spec nor a mapping.
    """
    if isinstance(spec, Mapping):
        return spaces.Dict(
            collections.OrderedDict((name, space_from_spec(value)) for name, value in spec.items())
        )
    return box_from_spec(spec)


def is_image_spec(spec: specs.Array) -> bool:
    """True for a camera image: (height, width, channels), possibly behind buffer axes."""
    return np.dtype(spec.dtype) == np.uint8 and len(spec.shape) >= 3


class FeatureLayout(NamedTuple):
    """Which observations are flattened into the features (in order) and which are images."""

    names: tuple[str, ...]
    images: tuple[str, ...]


def feature_layout(observation_spec: Mapping) -> FeatureLayout:
    """Splits a flat mapping of observation specs into features and camera images.

    Raises:
      TypeError: if a value is not an array spec (nested observations cannot be flattened).
    """
    names, images = [], []
    for name, spec in observation_spec.items():
        if not isinstance(spec, specs.Array):
            raise TypeError(
                f"observation {name!r}: expected an array spec to flatten, got "
                f"{type(spec).__name__}"
            )
        if is_image_spec(spec):
            images.append(name)
        else:
            names.append(name)
    return FeatureLayout(tuple(names), tuple(images))


def flat_space(observation_spec: Mapping, layout: FeatureLayout) -> spaces.Space:
    """Returns one `Box` of all features, or a `Dict` of it (as 'features') and the images.

    With images but no features, the `Dict` holds just the images.
    """
    images = {name: box_from_spec(observation_spec[name]) for name in layout.images}
    if not layout.names:
        return spaces.Dict(collections.OrderedDict(images))
    boxes = [box_from_spec(observation_spec[name]) for name in layout.names]
    dtype = np.result_type(*(box.dtype for box in boxes))
    features = spaces.Box(
        low=np.concatenate([box.low.ravel() for box in boxes]).astype(dtype),
        high=np.concatenate([box.high.ravel() for box in boxes]).astype(dtype),
        dtype=dtype,
    )
    if not images:
        return features
    return spaces.Dict(collections.OrderedDict(features=features, **images))
