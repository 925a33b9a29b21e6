"""Gymnasium spaces from dm_env specs, and the flattening of feature observations.

`BoundedArray` becomes a `Box` with the same bounds, shape and dtype; `Array` an unbounded
`Box` (the widest range its dtype holds); a mapping of specs a `Dict` in the same order.
`FlatObservations` is what `GymnasiumEnv(flatten_observations=True)` returns instead of the
dict of observations: its space and its packing are chosen in one place.
"""

import collections
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from dm_env import specs
from gymnasium import spaces

from composer.observation.flattening import flat_split

__all__ = ["FlatObservations", "box_from_spec", "space_from_spec"]


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


class FlatObservations:
    """Flattens observations of one spec: the features into one vector, images kept apart.

    Which observations are features and which images is `composer.observation.flattening`'s
    rule (`flat_split`, images apart). What an observation becomes depends only on which
    kinds the spec has:

    | the spec has        | observation (and `space`)                               |
    |---------------------|---------------------------------------------------------|
    | features only       | the feature vector (a `Box`)                            |
    | features and images | a dict: 'features' (the vector), then each image        |
    | images only         | a dict of the images                                    |

    Args:
      observation_spec: a flat mapping of names to array specs.

    Raises:
      TypeError: if a value is not an array spec (nested observations cannot be flattened).
    """

    def __init__(self, observation_spec: Mapping[str, specs.Array]):
        split = flat_split(observation_spec)
        self.features: tuple[str, ...] = split.features
        self.images: tuple[str, ...] = split.images
        feature_boxes = [box_from_spec(observation_spec[name]) for name in self.features]
        self.space: spaces.Space = self._pack(
            _concatenated_box(feature_boxes) if feature_boxes else None,
            {name: box_from_spec(observation_spec[name]) for name in self.images},
            lambda packed: spaces.Dict(collections.OrderedDict(packed)),
        )

    def __call__(self, observation: Mapping[str, np.ndarray], out: Any = None) -> Any:
        """Returns `observation` (a dict of the spec's arrays) flattened as `space` says;
        with `out` (arrays laid out as `space`), written into `out`, which is returned."""
        if out is not None:
            features = out if not self.images else out.get("features")
            if self.features:
                np.concatenate([observation[name].ravel() for name in self.features], out=features)
            for name in self.images:
                out[name][...] = observation[name]
            return out
        return self._pack(
            np.concatenate([observation[name].ravel() for name in self.features])
            if self.features
            else None,
            {name: observation[name] for name in self.images},
            dict,
        )

    def rows(self, observations: Mapping[str, np.ndarray]) -> Any:
        """Observations of many environments (a dict of the spec's arrays, each with a
        leading axis of environments) flattened environment by environment: `space`'s
        layout behind that axis."""
        count = len(next(iter(observations.values())))
        return self._pack(
            np.concatenate(
                [observations[name].reshape(count, -1) for name in self.features], axis=1
            )
            if self.features
            else None,
            {name: observations[name] for name in self.images},
            dict,
        )

    def _pack(self, features: Any, images: dict[str, Any], mapping: Callable[[dict], Any]) -> Any:
        """The one choice of the table above, for spaces and for observations alike."""
        if self.features and not self.images:
            return features
        packed = {"features": features} if self.features else {}
        return mapping({**packed, **images})


def _concatenated_box(boxes: list[spaces.Box]) -> spaces.Box:
    dtype = np.result_type(*(box.dtype for box in boxes))
    return spaces.Box(
        low=np.concatenate([box.low.ravel() for box in boxes]).astype(dtype),
        high=np.concatenate([box.high.ravel() for box in boxes]).astype(dtype),
        dtype=dtype,
    )
