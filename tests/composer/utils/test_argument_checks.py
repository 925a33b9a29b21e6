"""Argument checks: what they accept, and errors that name the argument, range and value."""

import numpy as np
import pytest

from composer.utils import argument_checks


@pytest.mark.parametrize("value", [1, 7, np.int64(3)])
def test_integer_returns_a_python_int(value):
    result = argument_checks.integer(num_envs=value)
    assert result == int(value) and type(result) is int


@pytest.mark.parametrize("value", [0, -2, True, 2.0, "3", None])
def test_integer_refuses_values_that_are_not_counts(value):
    with pytest.raises(ValueError, match=rf"^num_envs: expected an integer >= 1, got {value!r}$"):
        argument_checks.integer(num_envs=value)


def test_integer_minimum_unit_and_none_appear_in_the_message():
    assert argument_checks.integer(0, max_restarts=0) == 0
    assert argument_checks.integer(or_none=True, max_steps=None) is None
    with pytest.raises(
        ValueError, match=r"^width: expected an integer >= 1 \(screen pixels\) or None, got -1$"
    ):
        argument_checks.integer(or_none=True, unit="screen pixels", width=-1)


@pytest.mark.parametrize("value", [0, -1.0, float("inf"), float("nan"), True, "2"])
def test_positive_number_refuses_zero_negatives_non_finite_and_non_numbers(value):
    with pytest.raises(ValueError, match=rf"^fps: expected a positive number, got {value!r}$"):
        argument_checks.number(above=0, fps=value)


def test_number_in_a_closed_range_accepts_its_bounds():
    assert argument_checks.number(at_least=0.5, at_most=2, speed=2) == 2.0
    assert argument_checks.number(at_least=0.5, at_most=2, speed=0.5) == 0.5
    with pytest.raises(ValueError, match=r"^speed: expected a number in \[0.5, 2\], got 2.5$"):
        argument_checks.number(at_least=0.5, at_most=2, speed=2.5)


def test_a_lower_bound_alone_is_stated():
    with pytest.raises(ValueError, match=r"^cpus: expected a number >= 0 or None, got -1$"):
        argument_checks.number(at_least=0, or_none=True, cpus=-1)
