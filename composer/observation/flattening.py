"""Which observations a flat observation concatenates, and which it keeps apart: the one rule.

A policy that reads one vector (an MLP) needs the observations flattened; a camera image
flattened into that vector loses the layout a convolution needs and outweighs every
feature by its number of pixels. So, as a dm_control or Gymnasium user expects of pixel
observations, a flat observation keeps images apart unless asked otherwise:

- *features* are every observation that is not a camera image, each flattened in C order
  and concatenated in the observation spec's order;
- *images* are the camera images (uint8 with at least three axes: (height, width,
  channels), possibly behind buffer axes), each kept whole under its own name, unless
  `images=IMAGES_FLATTENED` asks for them to be flattened into the features in their place
  in the spec's order (what `composer.rl.rsl_rl` has always handed its "policy" group).

`composer.gym.spec_spaces.FlatObservations` (one environment, NumPy) and
`composer.rl.rsl_rl.RslRlVecEnv` (a batch, torch) both split their spec with `flat_split`;
docs/concepts/gymnasium.md ("The rules every adapter shares") is its page for users.
"""

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from dm_env import specs

__all__ = ["IMAGES_APART", "IMAGES_FLATTENED", "FlatSplit", "flat_split", "is_image_spec"]

#: Images kept whole, each under its own name (the default).
IMAGES_APART = "apart"
#: Images flattened into the features, in their place in the spec's order.
IMAGES_FLATTENED = "flattened"


def is_image_spec(spec: specs.Array) -> bool:
    """True for a camera image: (height, width, channels), possibly behind buffer axes."""
    return np.dtype(spec.dtype) == np.uint8 and len(spec.shape) >= 3


class FlatSplit(NamedTuple):
    """The names of an observation spec, split as the module docstring says.

    Attributes:
      features: the observations concatenated into the feature vector, in order.
      images: the observations kept apart, in order.
    """

    features: tuple[str, ...]
    images: tuple[str, ...]


def flat_split(
    observation_spec: Mapping[str, specs.Array], *, images: str = IMAGES_APART
) -> FlatSplit:
    """Splits the names of `observation_spec` into features and images kept apart.

    Args:
      observation_spec: a flat mapping of names to array specs.
      images: `IMAGES_APART` (the default) or `IMAGES_FLATTENED`.

    Returns:
      A `FlatSplit`; with `IMAGES_FLATTENED`, its `images` are empty.

    Raises:
      TypeError: if a value is not an array spec (nested observations cannot be flattened).
      ValueError: for any other `images`.
    """
    if images not in (IMAGES_APART, IMAGES_FLATTENED):
        raise ValueError(
            f"images: expected {IMAGES_APART!r} or {IMAGES_FLATTENED!r}, got {images!r}"
        )
    features, apart = [], []
    for name, spec in observation_spec.items():
        if not isinstance(spec, specs.Array):
            raise TypeError(
                f"observation {name!r}: expected an array spec to flatten, got "
                f"{type(spec).__name__}"
            )
        kept_apart = images == IMAGES_APART and is_image_spec(spec)
        (apart if kept_apart else features).append(name)
    return FlatSplit(tuple(features), tuple(apart))
