"""Variations without randomness: constants, fixed cyclic sequences, identity."""

from __future__ import annotations

from composer.variation import base


class Constant(base.Variation):
    """Always returns `value`; equal to another constant of an equal value."""

    def __init__(self, value):
        self._value = value

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        return self._value

    def __eq__(self, other):
        if not isinstance(other, Constant):
            return NotImplemented
        return base.same_value(self._value, other._value)

    __hash__ = None

    def __str__(self):
        return f"{self._value}"

    def __repr__(self):
        return f"Constant({self._value!r})"


class Sequence(base.Variation):
    """Returns the elements of `values` one per call, starting over after the last."""

    def __init__(self, values):
        self._values = tuple(values)
        if not self._values:
            raise ValueError("Sequence: values must not be empty")
        self._next = 0

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        value = self._values[self._next]
        self._next = (self._next + 1) % len(self._values)
        return value

    def __repr__(self):
        return f"Sequence({list(self._values)!r})"


class Identity(base.Variation):
    """Returns the current value unchanged; all identities are equal."""

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        return current_value

    def __eq__(self, other):
        return isinstance(other, Identity) or NotImplemented

    __hash__ = None

    def __repr__(self):
        return "Identity()"
