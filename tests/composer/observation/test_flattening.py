"""composer.observation.flattening: which observations a flat observation concatenates."""

import numpy as np
import pytest
from dm_env import specs

from composer.observation import flattening

_SPEC = {
    "joints": specs.Array((6, 2), np.float64),
    "front": specs.Array((1, 84, 84, 3), np.uint8),  # a camera behind a buffer axis
    "touch": specs.Array((3,), np.float32),
    "side": specs.Array((64, 64, 3), np.uint8),
    "mask": specs.Array((64, 64), np.uint8),  # two axes: not a camera image
}


def test_images_are_kept_apart_by_default_and_features_keep_the_specs_order():
    assert flattening.flat_split(_SPEC) == flattening.FlatSplit(
        features=("joints", "touch", "mask"), images=("front", "side")
    )


def test_flattened_images_take_their_place_in_the_specs_order():
    split = flattening.flat_split(_SPEC, images=flattening.IMAGES_FLATTENED)
    assert split == flattening.FlatSplit(
        features=("joints", "front", "touch", "side", "mask"), images=()
    )


def test_an_unknown_images_choice_is_refused_naming_the_argument():
    with pytest.raises(ValueError, match="images: expected 'apart' or 'flattened', got 'mixed'"):
        flattening.flat_split(_SPEC, images="mixed")


def test_a_nested_observation_cannot_be_split_and_is_named():
    with pytest.raises(TypeError, match="observation 'arm': expected an array spec to flatten"):
        flattening.flat_split({"arm": {"joint": specs.Array((2,), np.float64)}})
