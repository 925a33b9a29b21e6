"""The `Variation` protocol: lazily evaluated values, their arithmetic, and `evaluate`."""

from __future__ import annotations

import abc
import operator

import numpy as np


class Variation(metaclass=abc.ABCMeta):
    """A value that is re-sampled or recomputed each time it is called.

    Calling a variation returns a new value. Arithmetic (`+ - * / // **`, unary minus) with
    numbers, arrays or other variations, and indexing, return new variations that evaluate
    their operands (with the same arguments) each time they are called.
    """

    @abc.abstractmethod
    def __call__(self, initial_value=None, current_value=None, random_state=None):
        """Returns the next value.

        Args:
          initial_value: The original value of the quantity being varied; relative
            variations (noises) apply to it, absolute ones may ignore it. Distributions draw
            samples of its shape.
          current_value: The value the quantity has now (used by cumulative variations).
          random_state: A `np.random.RandomState`; None means NumPy's global random state.
        """

    def __add__(self, other):
        return _BinaryOperation(operator.add, self, other)

    def __radd__(self, other):
        return _BinaryOperation(operator.add, other, self)

    def __sub__(self, other):
        return _BinaryOperation(operator.sub, self, other)

    def __rsub__(self, other):
        return _BinaryOperation(operator.sub, other, self)

    def __mul__(self, other):
        return _BinaryOperation(operator.mul, self, other)

    def __rmul__(self, other):
        return _BinaryOperation(operator.mul, other, self)

    def __truediv__(self, other):
        return _BinaryOperation(operator.truediv, self, other)

    def __rtruediv__(self, other):
        return _BinaryOperation(operator.truediv, other, self)

    def __floordiv__(self, other):
        return _BinaryOperation(operator.floordiv, self, other)

    def __rfloordiv__(self, other):
        return _BinaryOperation(operator.floordiv, other, self)

    def __pow__(self, other):
        return _BinaryOperation(operator.pow, self, other)

    def __rpow__(self, other):
        return _BinaryOperation(operator.pow, other, self)

    def __neg__(self):
        return _UnaryOperation(operator.neg, self)

    def __getitem__(self, index):
        return _GetItemOperation(self, index)


# Types whose values `evaluate` returns as they are, found without the (slower) abstract
# `isinstance` check: the constants that variations are mixed with.
_CONSTANTS = frozenset([float, int, bool, str, type(None), np.ndarray, np.float64])


def evaluate(structure, *args, **kwargs):
    """Returns `structure` with every `Variation` inside it replaced by its value.

    Lists, tuples (including namedtuples) and dicts are traversed recursively; everything else
    (numbers, arrays, strings, ...) is returned unchanged. `args` and `kwargs` are passed to
    each variation: `(initial_value, current_value, random_state)`.
    """
    kind = type(structure)
    if kind in _CONSTANTS:
        return structure
    # The exact container types first: none of them is a Variation, and they skip the
    # (slower) abstract `isinstance` check.
    if kind is tuple:
        return tuple([evaluate(item, *args, **kwargs) for item in structure])
    if kind is list:
        return [evaluate(item, *args, **kwargs) for item in structure]
    if kind is dict:
        return {key: evaluate(value, *args, **kwargs) for key, value in structure.items()}
    if isinstance(structure, Variation):
        return structure(*args, **kwargs)
    if isinstance(structure, tuple) and hasattr(structure, "_fields"):
        return kind(*(evaluate(item, *args, **kwargs) for item in structure))
    if isinstance(structure, (list, tuple)):
        return kind(evaluate(item, *args, **kwargs) for item in structure)
    if isinstance(structure, dict):
        return kind((key, evaluate(value, *args, **kwargs)) for key, value in structure.items())
    return structure


def same_value(first, second) -> bool:
    """Returns whether two variation parameters are equal, comparing arrays element-wise.

    Lists, tuples and dicts are compared item by item, so that parameters holding NumPy
    arrays compare as a whole instead of raising on an ambiguous truth value.
    """
    if isinstance(first, np.ndarray) or isinstance(second, np.ndarray):
        first, second = np.asarray(first), np.asarray(second)
        return first.shape == second.shape and bool(np.all(first == second))
    if isinstance(first, (list, tuple)) and isinstance(second, (list, tuple)):
        return (
            type(first) is type(second)
            and len(first) == len(second)
            and all(same_value(a, b) for a, b in zip(first, second))
        )
    if isinstance(first, dict) and isinstance(second, dict):
        return first.keys() == second.keys() and all(
            same_value(first[key], second[key]) for key in first
        )
    return bool(first == second)


class _UnaryOperation(Variation):
    """`op(variation)`, evaluated lazily; equal to another with the same op and operand."""

    def __init__(self, op, variation):
        self._op = op
        self._variation = variation

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        return self._op(evaluate(self._variation, initial_value, current_value, random_state))

    def __eq__(self, other):
        if not isinstance(other, _UnaryOperation):
            return NotImplemented
        return self._op == other._op and same_value(self._variation, other._variation)

    __hash__ = None

    def __str__(self):
        return f"{self._op.__name__}({self._variation})"

    def __repr__(self):
        return f"UnaryOperation({self._op.__name__}({self._variation!r}))"


class _BinaryOperation(Variation):
    """`op(first, second)` where either operand may be a variation, evaluated lazily.

    Equal to another binary operation with the same op and equal operands, so the same
    expression built twice compares equal.
    """

    def __init__(self, op, first, second):
        self._op = op
        self._first = first
        self._second = second

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        first = evaluate(self._first, initial_value, current_value, random_state)
        second = evaluate(self._second, initial_value, current_value, random_state)
        return self._op(first, second)

    def __eq__(self, other):
        if not isinstance(other, _BinaryOperation):
            return NotImplemented
        return (
            self._op == other._op
            and same_value(self._first, other._first)
            and same_value(self._second, other._second)
        )

    __hash__ = None

    def __str__(self):
        return f"{self._op.__name__}({self._first}, {self._second})"

    def __repr__(self):
        return f"BinaryOperation({self._op.__name__}({self._first!r}, {self._second!r}))"


class _GetItemOperation(Variation):
    """`variation[index]`, evaluated lazily; equal to another with the same operand and index."""

    def __init__(self, variation, index):
        self._variation = variation
        self._index = index

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        value = evaluate(self._variation, initial_value, current_value, random_state)
        return np.asarray(value)[self._index]

    def __eq__(self, other):
        if not isinstance(other, _GetItemOperation):
            return NotImplemented
        return same_value(self._variation, other._variation) and same_value(
            self._index, other._index
        )

    __hash__ = None

    def __str__(self):
        return f"{self._variation}[{self._index}]"

    def __repr__(self):
        return f"GetItemOperation({self._variation!r}[{self._index}])"
