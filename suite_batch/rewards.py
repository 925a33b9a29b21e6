"""dm_control's `rewards.tolerance` for every world at once, bit for bit per world.

The suite's tasks call dm_control's `tolerance` either on one number (a cart's position, a
speed) or on an array (the controls, the joint velocities), and dm_control computes the
two differently: on a number every square is NumPy's scalar power (C `pow`), on an array
it is NumPy's array square (a product), and the two differ in the last bit for some
inputs (167 in 200,000 gaussian ones, measured). `tolerance` therefore takes what the CPU
task passed: `scalar=True` computes each world's value as dm_control's number path does
(squares with `np.float_power`, which is `pow`), `scalar=False` as its array path. The
sigmoids' constants come from NumPy, as dm_control's do.
"""

import numpy as np

__all__ = ["tolerance"]


def _square(x: np.ndarray, scalar: bool) -> np.ndarray:
    return np.float_power(x, 2) if scalar else x**2


def _sigmoid(x: np.ndarray, value_at_1: float, sigmoid: str, scalar: bool) -> np.ndarray:
    """`sigmoid` at the distances `x` (in units of the margin), `value_at_1` at 1."""
    if sigmoid == "gaussian":
        scale = np.sqrt(-2 * np.log(value_at_1))
        return np.exp(-0.5 * _square(x * scale, scalar))
    if sigmoid == "hyperbolic":
        scale = np.arccosh(1 / value_at_1)
        return 1 / np.cosh(x * scale)
    if sigmoid == "long_tail":
        scale = np.sqrt(1 / value_at_1 - 1)
        return 1 / (_square(x * scale, scalar) + 1)
    if sigmoid == "reciprocal":
        scale = 1 / value_at_1 - 1
        return 1 / (abs(x) * scale + 1)
    if sigmoid == "cosine":
        scale = np.arccos(2 * value_at_1 - 1) / np.pi
        scaled = x * scale
        with np.errstate(invalid="ignore"):  # cos(inf) in the branch not taken
            return np.where(abs(scaled) < 1, (1 + np.cos(np.pi * scaled)) / 2, 0.0)
    if sigmoid == "linear":
        scaled = x * (1 - value_at_1)
        return np.where(abs(scaled) < 1, 1 - scaled, 0.0)
    if sigmoid == "quadratic":
        scaled = x * np.sqrt(1 - value_at_1)
        return np.where(abs(scaled) < 1, 1 - _square(scaled, scalar), 0.0)
    if sigmoid == "tanh_squared":
        scale = np.arctanh(np.sqrt(1 - value_at_1))
        return 1 - _square(np.tanh(x * scale), scalar)
    raise ValueError(f"sigmoid: unknown sigmoid type {sigmoid!r}")


def tolerance(
    x: np.ndarray,
    bounds: tuple[float, float] = (0.0, 0.0),
    margin: float = 0.0,
    sigmoid: str = "gaussian",
    value_at_margin: float = 0.1,
    *,
    scalar: bool,
) -> np.ndarray:
    """dm_control's `rewards.tolerance` of every entry of `x`: 1 inside `bounds`, falling
    off with the distance outside them by `sigmoid` (`value_at_margin` at `margin`).

    Args:
      x: float64, any shape (each world's values along the first axis).
      bounds, margin, sigmoid, value_at_margin: as dm_control's.
      scalar: True where the CPU task passes each world's entry as one number (its value
        then equals dm_control's on that number); False where it passes an array.

    Returns:
      float64 of the shape of `x`.

    Raises:
      ValueError: for bounds whose lower exceeds the upper, a negative margin or an
        unknown sigmoid, as dm_control's.
    """
    lower, upper = bounds
    if lower > upper:
        raise ValueError(f"bounds: lower bound {lower} must be <= upper bound {upper}")
    if margin < 0:
        raise ValueError(f"margin: must be non-negative, got {margin}")
    in_bounds = np.logical_and(lower <= x, x <= upper)
    if margin == 0:
        return np.where(in_bounds, 1.0, 0.0)
    distance = np.where(x < lower, lower - x, x - upper) / margin
    return np.where(in_bounds, 1.0, _sigmoid(distance, value_at_margin, sigmoid, scalar))
