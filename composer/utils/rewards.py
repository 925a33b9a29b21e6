"""Shaped rewards: `tolerance` maps a distance from a target interval to a value in [0, 1]."""

from __future__ import annotations

import math

import numpy as np

_DEFAULT_VALUE_AT_MARGIN = 0.1

# Sigmoids whose value reaches exactly zero at some finite distance, so a value of 0 at the
# margin is meaningful; every other sigmoid is strictly positive everywhere.
_BOUNDED_SUPPORT = frozenset({"cosine", "linear", "quadratic"})


def _gaussian(x, value_at_1):
    scale = np.sqrt(-2.0 * np.log(value_at_1))
    return np.exp(-0.5 * (x * scale) ** 2)


def _hyperbolic(x, value_at_1):
    scale = np.arccosh(1.0 / value_at_1)
    return 1.0 / np.cosh(x * scale)


def _long_tail(x, value_at_1):
    scale = np.sqrt(1.0 / value_at_1 - 1.0)
    return 1.0 / ((x * scale) ** 2 + 1.0)


def _reciprocal(x, value_at_1):
    scale = 1.0 / value_at_1 - 1.0
    return 1.0 / (np.abs(x) * scale + 1.0)


def _cosine(x, value_at_1):
    scaled = x * (np.arccos(2.0 * value_at_1 - 1.0) / np.pi)
    # Evaluate the cosine only inside its support; outside it the value is 0.
    inside = np.abs(scaled) < 1.0
    return np.where(inside, (1.0 + np.cos(np.pi * np.where(inside, scaled, 0.0))) / 2.0, 0.0)


def _linear(x, value_at_1):
    scaled = x * (1.0 - value_at_1)
    return np.where(np.abs(scaled) < 1.0, 1.0 - scaled, 0.0)


def _quadratic(x, value_at_1):
    scaled = x * np.sqrt(1.0 - value_at_1)
    return np.where(np.abs(scaled) < 1.0, 1.0 - scaled**2, 0.0)


def _tanh_squared(x, value_at_1):
    scale = np.arctanh(np.sqrt(1.0 - value_at_1))
    return 1.0 - np.tanh(x * scale) ** 2


_SIGMOIDS = {
    "gaussian": _gaussian,
    "hyperbolic": _hyperbolic,
    "long_tail": _long_tail,
    "reciprocal": _reciprocal,
    "cosine": _cosine,
    "linear": _linear,
    "quadratic": _quadratic,
    "tanh_squared": _tanh_squared,
}

SIGMOIDS = tuple(_SIGMOIDS)
_SCALAR_TYPES = (int, float, np.integer, np.floating)


def _scalar_gaussian(x, value_at_1):
    scaled = x * math.sqrt(-2.0 * math.log(value_at_1))
    return math.exp(-0.5 * (scaled * scaled))


def _scalar_long_tail(x, value_at_1):
    scaled = x * math.sqrt(1.0 / value_at_1 - 1.0)
    return 1.0 / (scaled * scaled + 1.0)


def _scalar_reciprocal(x, value_at_1):
    return 1.0 / (abs(x) * (1.0 / value_at_1 - 1.0) + 1.0)


def _scalar_cosine(x, value_at_1):
    scaled = x * (math.acos(2.0 * value_at_1 - 1.0) / math.pi)
    return (1.0 + math.cos(math.pi * scaled)) / 2.0 if abs(scaled) < 1.0 else 0.0


def _scalar_linear(x, value_at_1):
    scaled = x * (1.0 - value_at_1)
    return 1.0 - scaled if abs(scaled) < 1.0 else 0.0


def _scalar_quadratic(x, value_at_1):
    scaled = x * math.sqrt(1.0 - value_at_1)
    return 1.0 - scaled * scaled if abs(scaled) < 1.0 else 0.0


# The same sigmoids on one Python float, with the `math` module: a reward computed from one
# distance per step would spend most of its time in NumPy's per-call overhead. The
# hyperbolic and tanh-squared ones keep NumPy's functions, whose tails libm's do not match.
_SCALAR_SIGMOIDS = {
    "gaussian": _scalar_gaussian,
    "hyperbolic": _hyperbolic,
    "long_tail": _scalar_long_tail,
    "reciprocal": _scalar_reciprocal,
    "cosine": _scalar_cosine,
    "linear": _scalar_linear,
    "quadratic": _scalar_quadratic,
    "tanh_squared": _tanh_squared,
}


def _check_value_at_margin(value_at_1: float, sigmoid: str) -> None:
    if sigmoid in _BOUNDED_SUPPORT:
        if not 0.0 <= value_at_1 < 1.0:
            raise ValueError(
                f"tolerance: value_at_margin for sigmoid {sigmoid!r} must be in [0, 1), "
                f"got {value_at_1}"
            )
    elif not 0.0 < value_at_1 < 1.0:
        raise ValueError(
            f"tolerance: value_at_margin for sigmoid {sigmoid!r} must be in (0, 1), "
            f"got {value_at_1}"
        )


def _sigmoids(x, value_at_1: float, sigmoid: str):
    """Evaluates `sigmoid` at `x` (distance in units of the margin), equal to `value_at_1` at 1.

    Every sigmoid equals 1 at x=0, decreases with |x|, and equals `value_at_1` at |x|=1.
    """
    _check_value_at_margin(value_at_1, sigmoid)
    return _SIGMOIDS[sigmoid](x, value_at_1)


def tolerance(
    x,
    bounds: tuple[float, float] = (0.0, 0.0),
    margin: float = 0.0,
    sigmoid: str = "gaussian",
    value_at_margin: float = _DEFAULT_VALUE_AT_MARGIN,
):
    """Returns 1 where `x` lies within `bounds`, decaying with the distance outside them.

    Args:
      x: A scalar or NumPy array.
      bounds: `(lower, upper)` interval of target values, inclusive; may be infinite.
      margin: Distance outside `bounds` at which the output equals `value_at_margin`.
        With `margin=0` the output is exactly 1 inside the bounds and 0 outside.
      sigmoid: Shape of the decay: one of 'gaussian', 'hyperbolic', 'long_tail',
        'reciprocal', 'cosine', 'linear', 'quadratic', 'tanh_squared'.
      value_at_margin: Output at distance `margin` from the bounds, in (0, 1)
        ([0, 1) for 'cosine', 'linear' and 'quadratic', which reach 0 at a finite distance).

    Returns:
      A float if `x` is a scalar (`np.isscalar`), else an array of the shape of `x`.

    Raises:
      ValueError: If `lower > upper`, `margin < 0`, `sigmoid` is unknown or
        `value_at_margin` is outside the range the sigmoid accepts.
    """
    lower, upper = bounds
    if lower > upper:
        raise ValueError(f"tolerance: bounds must satisfy lower <= upper, got {bounds}")
    if margin < 0:
        raise ValueError(f"tolerance: margin must be non-negative, got {margin}")
    if sigmoid not in _SIGMOIDS:
        raise ValueError(f"tolerance: unknown sigmoid {sigmoid!r}; expected one of {SIGMOIDS}")
    if isinstance(x, _SCALAR_TYPES):
        # Plain-Python comparisons: rewards are usually computed from one distance per step.
        if lower <= x <= upper:
            return 1.0
        if margin == 0:
            return 0.0
        _check_value_at_margin(value_at_margin, sigmoid)
        distance = (lower - x if x < lower else x - upper) / margin
        return float(_SCALAR_SIGMOIDS[sigmoid](float(distance), float(value_at_margin)))
    x_array = np.asarray(x)
    in_bounds = (lower <= x_array) & (x_array <= upper)
    if margin == 0:
        value = np.where(in_bounds, 1.0, 0.0)
    else:
        distance = np.where(x_array < lower, lower - x_array, x_array - upper) / margin
        value = np.where(in_bounds, 1.0, _sigmoids(distance, value_at_margin, sigmoid))
    return float(value) if np.isscalar(x) else value
