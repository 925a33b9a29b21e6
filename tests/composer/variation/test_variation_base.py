"""Tests for the Variation base class: lazy arithmetic, indexing and `evaluate`."""

import abc
import collections

import numpy as np
import pytest

from composer import variation
from composer.variation import deterministic, distributions


def test_arithmetic_with_numbers_is_evaluated_lazily():
    sequence = deterministic.Sequence([1.0, 2.0, 3.0])
    expression = (sequence + 1) * 2 - 0.5
    assert [expression() for _ in range(3)] == [3.5, 5.5, 7.5]


def test_reflected_arithmetic_puts_the_number_first():
    value = deterministic.Constant(4.0)
    assert (10 - value)() == 6.0
    assert (2 / value)() == 0.5
    assert (2**value)() == 16.0
    assert (9 // value)() == 2.0


def test_arithmetic_between_two_variations():
    a, b = deterministic.Constant(3.0), deterministic.Constant(2.0)
    assert (a + b)() == 5.0
    assert (a - b)() == 1.0
    assert (a * b)() == 6.0
    assert (a / b)() == 1.5
    assert (a // b)() == 1.0
    assert (a**b)() == 9.0


def test_unary_minus_and_indexing():
    vector = deterministic.Constant(np.array([1.0, -2.0, 3.0]))
    assert (-vector[1])() == 2.0
    np.testing.assert_array_equal((-vector)(), [-1.0, 2.0, -3.0])
    np.testing.assert_array_equal(vector[1:]()[::-1], [3.0, -2.0])


def test_arithmetic_draws_each_random_operand_once_per_call():
    uniform = distributions.Uniform(0.0, 1.0)
    difference = uniform - uniform
    # Two separate draws of the same distribution: the difference is not identically zero.
    values = [difference(random_state=np.random.RandomState(seed)) for seed in range(5)]
    assert any(value != 0.0 for value in values)


def test_operations_pass_initial_value_to_operands():
    doubled_initial = deterministic.Identity() * 2
    assert doubled_initial(initial_value=1.0, current_value=5.0) == 10.0


def test_evaluate_replaces_variations_in_nested_structures():
    point = collections.namedtuple("Point", ["x", "y"])
    structure = {
        "a": [deterministic.Constant(1), 2, (deterministic.Constant(3), "text")],
        "b": point(deterministic.Constant(4), np.array([5.0])),
    }
    result = variation.evaluate(structure)
    assert result["a"] == [1, 2, (3, "text")]
    assert isinstance(result["b"], point)
    assert result["b"].x == 4
    np.testing.assert_array_equal(result["b"].y, [5.0])


def test_evaluate_leaves_constants_alone():
    array = np.arange(3)
    assert variation.evaluate(array) is array
    assert variation.evaluate(7) == 7


def test_evaluate_forwards_arguments():
    noise = deterministic.Identity()
    assert variation.evaluate([noise], initial_value=1, current_value=2) == [2]


def test_custom_variation_subclass_works_with_operators():
    class Counter(variation.Variation):
        def __init__(self):
            self.calls = 0

        def __call__(self, initial_value=None, current_value=None, random_state=None):
            self.calls += 1
            return self.calls

    counter = Counter()
    assert (counter + 10)() == 11
    assert (counter + 10)() == 12


def test_variation_base_class_is_abstract():
    with pytest.raises(TypeError):
        variation.Variation()


def test_same_expression_built_twice_compares_equal():
    three, five = deterministic.Constant(3), deterministic.Constant(5)
    assert three + five == deterministic.Constant(3) + deterministic.Constant(5)
    assert -three == -deterministic.Constant(3)
    assert three[0] == deterministic.Constant(3)[0]


def test_expressions_with_different_operands_or_operators_differ():
    three, five = deterministic.Constant(3), deterministic.Constant(5)
    assert three + five != three + three
    assert three + five != three - five
    assert three[0] != three[1]


def test_constants_holding_equal_arrays_compare_equal():
    assert deterministic.Constant(np.array([1, 2])) == deterministic.Constant(np.array([1, 2]))
    assert deterministic.Constant(np.array([1, 2])) != deterministic.Constant(np.array([1, 3]))
    assert deterministic.Constant(np.array([1, 2])) != deterministic.Constant(np.array([1, 2, 3]))


def test_str_shows_values_and_repr_shows_the_expression_tree():
    expression = deterministic.Constant(3) + deterministic.Constant(5)
    assert str(expression) == "add(3, 5)"
    assert repr(expression) == "BinaryOperation(add(Constant(3), Constant(5)))"
    item = deterministic.Constant(7)[2]
    assert str(item) == "7[2]"
    assert repr(item) == "GetItemOperation(Constant(7)[2])"


def test_subclass_listing_abc_abc_before_variation_draws_values():
    class Doubling(abc.ABC, variation.Variation):
        def __call__(self, initial_value=None, current_value=None, random_state=None):
            return 2 * initial_value

    assert (Doubling() + 1)(initial_value=3.0) == 7.0
