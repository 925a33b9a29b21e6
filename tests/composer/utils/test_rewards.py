"""Tests for composer.utils.rewards.tolerance."""

import numpy as np
import pytest

from composer.utils import rewards

ALL_SIGMOIDS = (
    "gaussian",
    "hyperbolic",
    "long_tail",
    "reciprocal",
    "cosine",
    "linear",
    "quadratic",
    "tanh_squared",
)


@pytest.mark.parametrize("sigmoid", ALL_SIGMOIDS)
@pytest.mark.parametrize("value_at_margin", [0.1, 0.5, 0.9])
def test_value_at_margin_is_hit_exactly_on_both_sides(sigmoid, value_at_margin):
    bounds, margin = (-1.0, 2.0), 0.7
    below = rewards.tolerance(-1.7, bounds, margin, sigmoid, value_at_margin)
    above = rewards.tolerance(2.7, bounds, margin, sigmoid, value_at_margin)
    assert below == pytest.approx(value_at_margin, rel=1e-12)
    assert above == pytest.approx(value_at_margin, rel=1e-12)


@pytest.mark.parametrize("sigmoid", ALL_SIGMOIDS)
def test_inside_bounds_is_one_and_value_decreases_with_distance(sigmoid):
    x = np.array([0.0, 0.5, 1.0, 1.2, 1.5, 1.9])
    values = rewards.tolerance(x, bounds=(0.0, 1.0), margin=1.0, sigmoid=sigmoid)
    np.testing.assert_array_equal(values[:3], 1.0)
    assert np.all(np.diff(values[2:]) < 0)


def test_gaussian_follows_its_closed_form_between_bounds_and_margin():
    # For the gaussian sigmoid the value at a fraction f of the margin is value_at_margin**(f**2).
    value = rewards.tolerance(0.5, bounds=(0, 0), margin=1.0, value_at_margin=0.1)
    assert value == pytest.approx(0.1**0.25, rel=1e-12)


def test_long_tail_follows_its_closed_form():
    value = rewards.tolerance(
        3.0, bounds=(0, 1), margin=1.0, sigmoid="long_tail", value_at_margin=0.2
    )
    assert value == pytest.approx(1.0 / (4.0 * (1 / 0.2 - 1) + 1.0), rel=1e-12)


def test_linear_reaches_zero_at_margin_over_one_minus_value():
    at_zero = rewards.tolerance(
        2.0, bounds=(0, 0), margin=1.0, sigmoid="linear", value_at_margin=0.5
    )
    before_zero = rewards.tolerance(
        1.9, bounds=(0, 0), margin=1.0, sigmoid="linear", value_at_margin=0.5
    )
    assert at_zero == 0.0
    assert before_zero == pytest.approx(0.05)


@pytest.mark.parametrize("sigmoid", ["cosine", "linear", "quadratic"])
def test_bounded_sigmoids_accept_zero_value_at_margin(sigmoid):
    assert rewards.tolerance(
        1.0, margin=1.0, sigmoid=sigmoid, value_at_margin=0.0
    ) == pytest.approx(0)
    assert rewards.tolerance(5.0, margin=1.0, sigmoid=sigmoid, value_at_margin=0.0) == 0.0


@pytest.mark.parametrize(
    "sigmoid", ["gaussian", "hyperbolic", "long_tail", "reciprocal", "tanh_squared"]
)
def test_unbounded_sigmoids_reject_zero_value_at_margin(sigmoid):
    with pytest.raises(ValueError, match="value_at_margin"):
        rewards.tolerance(1.0, margin=1.0, sigmoid=sigmoid, value_at_margin=0.0)


def test_zero_margin_is_an_indicator_of_the_bounds():
    values = rewards.tolerance(np.array([-0.1, 0.0, 0.5, 1.0, 1.1]), bounds=(0.0, 1.0))
    np.testing.assert_array_equal(values, [0.0, 1.0, 1.0, 1.0, 0.0])


def test_infinite_bound_is_one_sided():
    values = rewards.tolerance(np.array([-1e9, 0.0, 1.0]), bounds=(-np.inf, 0.0), margin=1.0)
    np.testing.assert_allclose(values, [1.0, 1.0, 0.1])


def test_scalar_input_gives_float_and_array_input_keeps_shape():
    assert isinstance(rewards.tolerance(0.3, margin=1.0), float)
    assert rewards.tolerance(np.zeros((2, 3)), margin=1.0).shape == (2, 3)


def test_lower_bound_above_upper_is_rejected():
    with pytest.raises(ValueError, match="lower <= upper"):
        rewards.tolerance(0.0, bounds=(1.0, 0.0))


def test_negative_margin_is_rejected():
    with pytest.raises(ValueError, match="margin must be non-negative, got -1"):
        rewards.tolerance(0.0, margin=-1.0)


def test_unknown_sigmoid_is_rejected_with_the_valid_names():
    with pytest.raises(ValueError, match="unknown sigmoid 'sigmund'.*gaussian"):
        rewards.tolerance(0.0, margin=1.0, sigmoid="sigmund")


@pytest.mark.parametrize("sigmoid", ALL_SIGMOIDS)
def test_scalar_and_array_inputs_give_the_same_values(sigmoid):
    points = np.linspace(-3.0, 4.0, 29)
    as_array = rewards.tolerance(points, bounds=(-1.0, 2.0), margin=0.7, sigmoid=sigmoid)
    one_by_one = [
        rewards.tolerance(float(p), bounds=(-1.0, 2.0), margin=0.7, sigmoid=sigmoid) for p in points
    ]
    np.testing.assert_allclose(one_by_one, as_array, rtol=1e-14, atol=0)
