"""Tests for the options of composer.observation.observable.Observable (no physics needed)."""

import numpy as np
import pytest

from composer.observation import observable


def _generic(**options):
    return observable.Generic(lambda physics: physics * 2.0, **options)


def test_observables_start_disabled():
    assert not _generic().enabled


def test_call_evaluates_the_raw_callable_on_physics():
    assert _generic()(3.0) == 6.0


def test_observation_callable_returns_a_zero_argument_function():
    assert _generic().observation_callable(4.0)() == 8.0


def test_corruptor_applies_to_calls_with_the_given_random_state():
    random_state = np.random.RandomState(0)
    seen = []

    def corruptor(value, random_state):
        seen.append(random_state)
        return -value

    assert _generic(corruptor=corruptor)(1.0, random_state) == -2.0
    assert seen == [random_state]


@pytest.mark.parametrize(
    "option, value",
    [("update_interval", 0), ("buffer_size", 0), ("delay", -1), ("update_interval", 1.5)],
)
def test_invalid_option_value_is_a_value_error_naming_the_option(option, value):
    with pytest.raises(ValueError, match=option):
        _generic(**{option: value})


def test_invalid_option_set_later_is_a_value_error_naming_the_option():
    obs = _generic()
    with pytest.raises(ValueError, match="delay"):
        obs.delay = -3


def test_callable_buffer_size_is_rejected():
    with pytest.raises(ValueError, match="buffer_size"):
        _generic(buffer_size=lambda: 2)


def test_unknown_aggregator_name_lists_the_valid_ones():
    with pytest.raises(KeyError, match="'avg'.*'max'.*'mean'.*'median'.*'min'.*'sum'"):
        _generic(aggregator="avg")


def test_aggregator_name_resolves_to_a_reduction_over_the_first_axis():
    obs = _generic(aggregator="max")
    np.testing.assert_array_equal(obs.aggregator(np.array([[1, 5], [3, 2]])), [3, 5])


def test_configure_sets_several_options():
    obs = _generic()
    obs.configure(update_interval=4, buffer_size=2, enabled=True)
    assert (obs.update_interval, obs.buffer_size, obs.enabled) == (4, 2, True)


def test_configure_with_unknown_option_raises_attribute_error():
    with pytest.raises(AttributeError, match="sample_rate"):
        _generic().configure(sample_rate=3)


def test_generic_requires_a_callable():
    with pytest.raises(TypeError, match="raw_observation_callable"):
        observable.Generic(3.0)


def test_camera_spec_is_uint8_rgb_from_0_to_255_by_default():
    spec = observable.MujocoCamera("front", height=48, width=64).array_spec
    assert (spec.shape, spec.dtype) == ((48, 64, 3), np.uint8)
    assert (spec.minimum, spec.maximum) == (0, 255)


def test_camera_spec_is_non_negative_float_single_channel_for_depth():
    spec = observable.MujocoCamera("front", height=48, width=64, depth=True).array_spec
    assert (spec.shape, spec.dtype) == ((48, 64, 1), np.float32)
    assert (spec.minimum, spec.maximum) == (0.0, np.inf)


def test_camera_spec_is_two_int_channels_from_minus_one_for_segmentation():
    spec = observable.MujocoCamera("front", height=48, width=64, segmentation=True).array_spec
    assert (spec.shape, spec.dtype) == ((48, 64, 2), np.int32)
    assert (spec.minimum, spec.maximum) == (-1, 2**31 - 1)


def test_camera_spec_follows_size_changes():
    camera = observable.MujocoCamera("front")
    camera.height, camera.width = 10, 20
    assert camera.array_spec.shape == (10, 20, 3)


def test_camera_with_depth_and_segmentation_is_rejected():
    with pytest.raises(ValueError, match="depth.*segmentation"):
        observable.MujocoCamera("front", depth=True, segmentation=True)


def test_camera_with_non_positive_height_is_rejected():
    with pytest.raises(ValueError, match="height"):
        observable.MujocoCamera("front", height=0)
