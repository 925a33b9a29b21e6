"""Color variations: each channel a constant or a variation, the result a flat RGBA array.

Channel variations are evaluated without the color's initial or current value (which is a
whole RGBA vector, not a channel), so a distribution draws one sample per channel whatever
the shape of the attribute being varied.
"""

from __future__ import annotations

import colorsys

import numpy as np

from composer.variation import base


def _evaluated(values: tuple, random_state) -> list:
    """`base.evaluate(values, random_state=random_state)` for a tuple of channels, as a list:
    each variation among them is called with the random state alone."""
    return [
        value(random_state=random_state)
        if isinstance(value, base.Variation)
        else base.evaluate(value, random_state=random_state)
        for value in values
    ]


def _channels(owner: str, names: tuple[str, ...], values) -> list[float]:
    channels = []
    for name, value in zip(names, values):
        if type(value) is float:  # what a distribution draws: a single number already
            channels.append(value)
            continue
        if isinstance(value, float):
            channels.append(float(value))
            continue
        array = np.asarray(value, dtype=np.float64)
        if array.size != 1:
            raise ValueError(
                f"{owner}: channel {name!r} must evaluate to a single number, got shape "
                f"{array.shape}"
            )
        channels.append(float(array.reshape(())))
    return channels


class RgbVariation(base.Variation):
    """A color from red, green, blue and alpha channels in [0, 1]; returns shape (4,)."""

    _NAMES = ("r", "g", "b", "alpha")

    def __init__(self, r, g, b, alpha=1.0):
        self._values = (r, g, b, alpha)

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        values = _evaluated(self._values, random_state)
        return np.array(_channels(type(self).__name__, self._NAMES, values))

    def __repr__(self):
        params = ", ".join(f"{n}={v!r}" for n, v in zip(self._NAMES, self._values))
        return f"{type(self).__name__}({params})"


class HsvVariation(base.Variation):
    """A color from hue, saturation, value and alpha channels in [0, 1]; returns RGBA (4,)."""

    _NAMES = ("h", "s", "v", "alpha")

    def __init__(self, h, s, v, alpha=1.0):
        self._values = (h, s, v, alpha)

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        values = _evaluated(self._values, random_state)
        h, s, v, alpha = _channels(type(self).__name__, self._NAMES, values)
        return np.array([*colorsys.hsv_to_rgb(h, s, v), alpha])

    def __repr__(self):
        params = ", ".join(f"{n}={v!r}" for n, v in zip(self._NAMES, self._values))
        return f"{type(self).__name__}({params})"


class GrayVariation(HsvVariation):
    """A gray with brightness `gray_level` in [0, 1] and the given alpha; returns RGBA (4,)."""

    def __init__(self, gray_level, alpha=1.0):
        super().__init__(h=0.0, s=0.0, v=gray_level, alpha=alpha)

    def __repr__(self):
        return f"GrayVariation(gray_level={self._values[2]!r}, alpha={self._values[3]!r})"
