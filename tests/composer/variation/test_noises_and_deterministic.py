"""Tests for composer.variation.noises and composer.variation.deterministic."""

import numpy as np
import pytest

from composer.variation import deterministic, noises


def test_additive_adds_to_the_initial_value_each_time():
    noise = noises.Additive(deterministic.Constant(0.5))
    assert noise(initial_value=1.0, current_value=4.0) == 1.5
    assert noise(initial_value=1.0, current_value=1.5) == 1.5


def test_cumulative_additive_accumulates_on_the_current_value():
    noise = noises.Additive(deterministic.Constant(0.5), cumulative=True)
    value = 1.0
    for _ in range(3):
        value = noise(initial_value=1.0, current_value=value)
    assert value == 2.5


def test_multiplicative_scales_the_initial_value():
    noise = noises.Multiplicative(deterministic.Constant(np.array([2.0, 3.0])))
    np.testing.assert_array_equal(noise(initial_value=np.array([1.0, 2.0])), [2.0, 6.0])


def test_cumulative_multiplicative_compounds():
    noise = noises.Multiplicative(deterministic.Constant(2.0), cumulative=True)
    assert (
        noise(initial_value=1.0, current_value=noise(initial_value=1.0, current_value=3.0)) == 12.0
    )


def test_noise_accepts_a_constant_instead_of_a_variation():
    assert noises.Additive(2.0)(initial_value=1.0) == 3.0


def test_noise_without_a_value_to_perturb_is_a_clear_error():
    with pytest.raises(ValueError, match="Additive\\(cumulative=False\\) needs a initial_value"):
        noises.Additive(1.0)()


def test_constant_returns_its_value():
    assert deterministic.Constant("x")(initial_value=3) == "x"


def test_sequence_cycles_through_its_values():
    sequence = deterministic.Sequence([1, 2, 3])
    assert [sequence() for _ in range(7)] == [1, 2, 3, 1, 2, 3, 1]


def test_sequence_accepts_a_generator_and_cycles_it():
    sequence = deterministic.Sequence(value for value in "ab")
    assert [sequence() for _ in range(4)] == ["a", "b", "a", "b"]


def test_empty_sequence_is_rejected():
    with pytest.raises(ValueError, match="Sequence: values must not be empty"):
        deterministic.Sequence([])


def test_identity_returns_the_current_value():
    assert deterministic.Identity()(initial_value=1, current_value=2) == 2
