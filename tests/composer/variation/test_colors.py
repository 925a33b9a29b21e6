"""Tests for composer.variation.colors."""

import numpy as np
import pytest

from composer.variation import colors, deterministic, distributions


def test_rgb_of_constants_is_a_flat_rgba_array():
    rgba = colors.RgbVariation(0.1, 0.2, 0.3)()
    assert rgba.shape == (4,)
    np.testing.assert_array_equal(rgba, [0.1, 0.2, 0.3, 1.0])


def test_rgb_channels_may_be_distributions_with_shape():
    variation = colors.RgbVariation(
        r=distributions.Uniform([0.0], [1.0]),
        g=deterministic.Constant(np.array(0.5)),
        b=distributions.Uniform(),
        alpha=0.25,
    )
    rgba = variation(random_state=np.random.RandomState(0))
    assert rgba.shape == (4,)
    assert rgba[1] == 0.5 and rgba[3] == 0.25


def test_channels_draw_one_sample_each_when_varying_an_rgba_attribute():
    variation = colors.RgbVariation(distributions.Uniform(), 0.0, distributions.Uniform())
    rgba = variation(initial_value=np.ones(4), current_value=np.ones(4))
    assert rgba.shape == (4,)
    assert rgba[1] == 0.0 and rgba[3] == 1.0


def test_channel_with_more_than_one_value_is_rejected_by_name():
    variation = colors.RgbVariation(0.0, distributions.Uniform([0.0, 0.0], 1.0), 0.0)
    with pytest.raises(ValueError, match="channel 'g' must evaluate to a single number"):
        variation()


def test_hsv_converts_to_rgb():
    np.testing.assert_allclose(colors.HsvVariation(h=1 / 3, s=1.0, v=1.0)(), [0, 1, 0, 1])
    np.testing.assert_allclose(
        colors.HsvVariation(h=0.0, s=0.5, v=0.8, alpha=0.5)(), [0.8, 0.4, 0.4, 0.5]
    )


def test_gray_has_equal_rgb_channels():
    rgba = colors.GrayVariation(distributions.Uniform(0.2, 0.8), alpha=0.9)(
        random_state=np.random.RandomState(1)
    )
    assert rgba[0] == rgba[1] == rgba[2]
    assert 0.2 <= rgba[0] < 0.8
    assert rgba[3] == 0.9
