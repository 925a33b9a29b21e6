"""dm_env specs become Gymnasium spaces with the same bounds, shapes and dtypes."""

import collections

import numpy as np
import pytest
from dm_env import specs
from gymnasium import spaces

from composer.gym import spec_spaces


def test_bounded_array_becomes_box_with_its_bounds_and_dtype():
    spec = specs.BoundedArray((3,), np.float32, minimum=[-1, -2, -3], maximum=[1, 2, 3])
    box = spec_spaces.box_from_spec(spec)
    assert isinstance(box, spaces.Box)
    assert box.dtype == np.float32
    assert box.shape == (3,)
    np.testing.assert_array_equal(box.low, [-1, -2, -3])
    np.testing.assert_array_equal(box.high, [1, 2, 3])


def test_scalar_bounds_are_broadcast_to_the_shape():
    box = spec_spaces.box_from_spec(specs.BoundedArray((2, 2), np.float64, -0.5, 0.5))
    np.testing.assert_array_equal(box.low, np.full((2, 2), -0.5))
    np.testing.assert_array_equal(box.high, np.full((2, 2), 0.5))


def test_unbounded_float_array_becomes_infinite_box():
    box = spec_spaces.box_from_spec(specs.Array((1, 4), np.float64))
    assert box.shape == (1, 4)
    assert box.dtype == np.float64
    assert np.all(box.low == -np.inf) and np.all(box.high == np.inf)


def test_unbounded_integer_array_spans_its_dtype():
    box = spec_spaces.box_from_spec(specs.Array((2,), np.int32))
    assert box.dtype == np.int32
    np.testing.assert_array_equal(box.low, [-(2**31)] * 2)
    np.testing.assert_array_equal(box.high, [2**31 - 1] * 2)


def test_mapping_becomes_dict_space_in_the_same_order():
    spec = collections.OrderedDict(
        [("b", specs.Array((1,), np.float64)), ("a", specs.Array((2,), np.float64))]
    )
    space = spec_spaces.space_from_spec(spec)
    assert isinstance(space, spaces.Dict)
    assert list(space.keys()) == ["b", "a"]
    assert space["a"].shape == (2,)


def test_non_spec_is_rejected_naming_its_type():
    with pytest.raises(TypeError, match="expected a dm_env.specs.Array, got list"):
        spec_spaces.box_from_spec([1, 2])


def test_flat_space_concatenates_feature_bounds_and_keeps_images_apart():
    spec = {
        "joint": specs.BoundedArray((1, 2), np.float64, minimum=[[-1, -2]], maximum=[[1, 2]]),
        "camera": specs.BoundedArray((1, 8, 8, 3), np.uint8, 0, 255),
        "speed": specs.Array((1,), np.float64),
    }
    flat = spec_spaces.FlatObservations(spec)
    assert flat.features == ("joint", "speed")
    assert flat.images == ("camera",)
    assert list(flat.space.keys()) == ["features", "camera"]
    np.testing.assert_array_equal(flat.space["features"].low, [-1, -2, -np.inf])
    np.testing.assert_array_equal(flat.space["features"].high, [1, 2, np.inf])
    assert flat.space["camera"].shape == (1, 8, 8, 3)
    image = np.full((1, 8, 8, 3), 7, np.uint8)
    observation = flat(
        {"joint": np.array([[0.5, -1.5]]), "camera": image, "speed": np.array([3.0])}
    )
    assert list(observation) == ["features", "camera"]
    assert observation["features"].tolist() == [0.5, -1.5, 3.0]
    assert observation["camera"] is image


def test_flattening_into_given_arrays_writes_features_and_images_there():
    spec = {
        "joint": specs.Array((1, 2), np.float64),
        "camera": specs.Array((1, 2, 2, 3), np.uint8),
        "speed": specs.Array((1,), np.float64),
    }
    flat = spec_spaces.FlatObservations(spec)
    out = {"features": np.zeros(3), "camera": np.zeros((1, 2, 2, 3), np.uint8)}
    image = np.full((1, 2, 2, 3), 7, np.uint8)
    returned = flat(
        {"joint": np.array([[0.5, -1.5]]), "camera": image, "speed": np.array([3.0])}, out=out
    )
    assert returned is out
    assert out["features"].tolist() == [0.5, -1.5, 3.0]
    assert out["camera"].tolist() == image.tolist()


def test_flattening_features_only_into_a_given_array_fills_it():
    flat = spec_spaces.FlatObservations({"a": specs.Array((2,), np.float64)})
    out = np.zeros(2)
    assert flat({"a": np.array([4.0, 5.0])}, out=out) is out
    assert out.tolist() == [4.0, 5.0]


def test_flat_space_of_features_only_is_one_box():
    spec = {"a": specs.Array((2,), np.float64), "b": specs.Array((1, 3), np.float64)}
    flat = spec_spaces.FlatObservations(spec)
    assert isinstance(flat.space, spaces.Box)
    assert flat.space.shape == (5,)
    observation = flat({"a": np.array([1.0, 2.0]), "b": np.array([[3.0, 4.0, 5.0]])})
    assert observation.tolist() == [1.0, 2.0, 3.0, 4.0, 5.0]


def test_flat_space_of_images_only_is_a_dict_of_the_images():
    spec = {"left": specs.Array((4, 4, 3), np.uint8), "right": specs.Array((4, 4, 3), np.uint8)}
    flat = spec_spaces.FlatObservations(spec)
    assert isinstance(flat.space, spaces.Dict)
    assert list(flat.space.keys()) == ["left", "right"]
    images = {"left": np.zeros((4, 4, 3), np.uint8), "right": np.ones((4, 4, 3), np.uint8)}
    assert list(flat(images)) == ["left", "right"]


def test_a_nested_observation_cannot_be_flattened_and_is_named():
    spec = {"arm": {"joint": specs.Array((2,), np.float64)}}
    with pytest.raises(TypeError, match="observation 'arm': expected an array spec to flatten"):
        spec_spaces.FlatObservations(spec)
