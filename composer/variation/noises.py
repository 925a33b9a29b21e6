"""Variations that perturb an existing value: additive and multiplicative noise."""

from __future__ import annotations

import functools

from composer.variation import base


class _Noise(base.Variation):
    def __init__(self, variation, cumulative: bool = False):
        self._variation = variation
        self._cumulative = cumulative
        # A noise often corrupts an observable, once per sample: decide the call once.
        self._draw = (
            variation.__call__
            if isinstance(variation, base.Variation)
            else functools.partial(base.evaluate, variation)
        )

    def _missing_value(self) -> ValueError:
        """The error for a call without the value this noise perturbs."""
        which = "current_value" if self._cumulative else "initial_value"
        return ValueError(
            f"{type(self).__name__}(cumulative={self._cumulative}) needs a {which} to perturb"
        )

    def __repr__(self):
        return f"{type(self).__name__}({self._variation!r}, cumulative={self._cumulative})"


class Additive(_Noise):
    """Adds the value of `variation` to the initial value (to the current one if `cumulative`)."""

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        value = current_value if self._cumulative else initial_value
        if value is None:
            raise self._missing_value()
        return value + self._draw(initial_value, current_value, random_state)


class Multiplicative(_Noise):
    """Multiplies the initial value (the current one if `cumulative`) by `variation`'s value."""

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        value = current_value if self._cumulative else initial_value
        if value is None:
            raise self._missing_value()
        return value * self._draw(initial_value, current_value, random_state)
