"""Shaped rewards: `tolerance` maps a distance from a target interval to a value in [0, 1].

`tolerance` has three paths, chosen by the type of `x`: plain Python for one Python or
NumPy number, NumPy for NumPy arrays (and lists), and the array's own namespace for any
other array-API array (torch, JAX, CuPy, array_api_strict), found with the optional
`array_api_compat`, imported only when such an array is given. The first two compute the
same float64 operations, so a number's value equals its entry of an array's, bit for bit.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

_DEFAULT_VALUE_AT_MARGIN = 0.1

# Sigmoids whose value reaches exactly zero at some finite distance, so a value of 0 at the
# margin is meaningful; every other sigmoid is strictly positive everywhere.
_BOUNDED_SUPPORT = frozenset({"cosine", "linear", "quadratic"})


# One set of formulas for every path: the constants of a sigmoid are computed with `math`
# from `value_at_1`, the values with the namespace's own functions (NumPy's for Python and
# NumPy numbers too, whose `exp`, `cosh` and `tanh` differ from `math`'s in the last bit for
# some inputs), so that a reward computed for one world on a number equals, bit for bit, the
# same reward computed for many worlds on a NumPy array (the CPU batch). The constants are
# Python floats, so the result keeps the dtype and device of `x`. `x` is the distance in
# units of the margin: non-negative, or NaN.


def _xp_gaussian(xp, x, value_at_1):
    scaled = x * math.sqrt(-2.0 * math.log(value_at_1))
    return xp.exp(-0.5 * (scaled * scaled))


def _xp_hyperbolic(xp, x, value_at_1):
    return 1.0 / xp.cosh(x * math.acosh(1.0 / value_at_1))


def _xp_long_tail(xp, x, value_at_1):
    scaled = x * math.sqrt(1.0 / value_at_1 - 1.0)
    return 1.0 / (scaled * scaled + 1.0)


def _xp_reciprocal(xp, x, value_at_1):
    return 1.0 / (xp.abs(x) * (1.0 / value_at_1 - 1.0) + 1.0)


def _xp_cosine(xp, x, value_at_1):
    scaled = x * (math.acos(2.0 * value_at_1 - 1.0) / math.pi)
    inside = xp.abs(scaled) < 1.0
    zero = xp.zeros_like(scaled)
    # The inner `where` keeps cos(inf) = NaN out of the unused branch and its gradient.
    cosine = (1.0 + xp.cos(math.pi * xp.where(inside, scaled, zero))) / 2.0
    return xp.where(inside, cosine, zero)


def _xp_linear(xp, x, value_at_1):
    scaled = x * (1.0 - value_at_1)
    return xp.where(xp.abs(scaled) < 1.0, 1.0 - scaled, xp.zeros_like(scaled))


def _xp_quadratic(xp, x, value_at_1):
    scaled = x * math.sqrt(1.0 - value_at_1)
    return xp.where(xp.abs(scaled) < 1.0, 1.0 - scaled * scaled, xp.zeros_like(scaled))


def _xp_tanh_squared(xp, x, value_at_1):
    tanh = xp.tanh(x * math.atanh(math.sqrt(1.0 - value_at_1)))
    return 1.0 - tanh * tanh


_XP_SIGMOIDS = {
    "gaussian": _xp_gaussian,
    "hyperbolic": _xp_hyperbolic,
    "long_tail": _xp_long_tail,
    "reciprocal": _xp_reciprocal,
    "cosine": _xp_cosine,
    "linear": _xp_linear,
    "quadratic": _xp_quadratic,
    "tanh_squared": _xp_tanh_squared,
}

SIGMOIDS = tuple(_XP_SIGMOIDS)
_SCALAR_TYPES = (int, float, np.integer, np.floating)

# Inputs that take the scalar or NumPy path without looking for another namespace.
_HOST_INPUTS = (*_SCALAR_TYPES, np.ndarray, np.generic, list, tuple)

_ARRAY_API_INSTALL_HINT = "pip install array-api-compat (or pip install 'mujoco-composer[warp]')"


def _scalar_sigmoid(x: float, value_at_1: float, sigmoid: str) -> float:
    """A sigmoid at one distance: the array formulas on a NumPy number."""
    return float(_XP_SIGMOIDS[sigmoid](np, np.float64(x), value_at_1))


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
    return _XP_SIGMOIDS[sigmoid](np, x, value_at_1)


def _array_namespace(x):
    """Returns the array-API namespace of `x`, or None if `x` is not an array-API array."""
    try:
        import array_api_compat
    except ImportError as error:
        if hasattr(x, "__array_namespace__") or hasattr(x, "__dlpack__"):
            kind = f"{type(x).__module__}.{type(x).__qualname__}"
            raise ImportError(
                f"tolerance: x is a {kind}; computing on it without a copy to NumPy needs "
                f"array-api-compat: {_ARRAY_API_INSTALL_HINT}"
            ) from error
        return None
    if not array_api_compat.is_array_api_obj(x):
        return None
    return array_api_compat.array_namespace(x)


def _host_float(name: str, value) -> float:
    """Returns `value` as a float; refuses a device array, whose value would need a copy."""
    if isinstance(value, numbers.Real) or (isinstance(value, np.ndarray) and value.ndim == 0):
        return float(value)
    raise TypeError(
        f"tolerance: {name} must be a Python or NumPy number when x is a "
        f"non-NumPy array, got {type(value).__module__}.{type(value).__qualname__}"
    )


def _as_real_floating(xp, x):
    """Returns `x` if its dtype is real floating, else `x` cast to the default float dtype."""
    if xp.isdtype(x.dtype, "real floating"):
        return x
    if not xp.isdtype(x.dtype, ("bool", "integral")):
        raise TypeError(f"tolerance: x must have a real dtype, got {x.dtype}")
    import array_api_compat

    default_dtypes = xp.__array_namespace_info__().default_dtypes(device=array_api_compat.device(x))
    return xp.astype(x, default_dtypes["real floating"])


def _xp_tolerance(xp, x, lower: float, upper: float, margin: float, sigmoid: str, value_at_1):
    """`tolerance` on an array of namespace `xp`, computed with `xp` only."""
    x = _as_real_floating(xp, x)
    in_bounds = (lower <= x) & (x <= upper)
    if margin == 0:
        return xp.astype(in_bounds, x.dtype)
    _check_value_at_margin(value_at_1, sigmoid)
    # Distance 0 inside the bounds, where every sigmoid is exactly 1; choosing it before the
    # sigmoid, rather than the result after, keeps an infinite bound's `x - inf` out of the
    # sigmoid and so out of torch's and JAX's gradients. NaN gives what NumPy's path gives.
    outside = xp.where(x < lower, lower - x, x - upper)
    distance = xp.where(in_bounds, xp.zeros_like(x), outside) / margin
    return _XP_SIGMOIDS[sigmoid](xp, distance, value_at_1)


def tolerance(
    x,
    bounds: tuple[float, float] = (0.0, 0.0),
    margin: float = 0.0,
    sigmoid: str = "gaussian",
    value_at_margin: float = _DEFAULT_VALUE_AT_MARGIN,
):
    """Returns 1 where `x` lies within `bounds`, decaying with the distance outside them.

    Works on Python and NumPy numbers, NumPy arrays, and the arrays of any array-API
    namespace that `array_api_compat` knows (torch, JAX, CuPy, array_api_strict, ...).
    A non-NumPy array is computed on with its own namespace's functions, on its own device,
    with no copy to the host and no synchronisation; that needs the optional package
    `array-api-compat`, imported only then.

    Args:
      x: A Python or NumPy number, a NumPy array (or a list), or an array-API array.
      bounds: `(lower, upper)` interval of target values, inclusive; may be infinite.
      margin: Distance outside `bounds` at which the output equals `value_at_margin`.
        With `margin=0` the output is exactly 1 inside the bounds and 0 outside.
      sigmoid: Shape of the decay: one of 'gaussian', 'hyperbolic', 'long_tail',
        'reciprocal', 'cosine', 'linear', 'quadratic', 'tanh_squared'.
      value_at_margin: Output at distance `margin` from the bounds, in (0, 1)
        ([0, 1) for 'cosine', 'linear' and 'quadratic', which reach 0 at a finite distance).

    `bounds`, `margin` and `value_at_margin` are Python or NumPy numbers, checked on the
    host. The values of `x` are not checked on any path (a NaN in `x` raises nothing), and
    must not be for a device array, which would have to be copied to the host.

    Returns:
      A float if `x` is a scalar (`np.isscalar`); a NumPy array of the shape of `x` if `x`
      is a NumPy array or a list; otherwise an array of the namespace, device and shape of
      `x`, of the dtype of `x` if it is real floating (float32 stays float32), else of the
      namespace's default float dtype.

    Raises:
      ValueError: If `lower > upper`, `margin < 0`, `sigmoid` is unknown or
        `value_at_margin` is outside the range the sigmoid accepts.
      TypeError: If `x` is a non-NumPy array and its dtype is not real (complex), or a
        bound, `margin` or `value_at_margin` is itself a non-NumPy array.
      ImportError: If `x` is a non-NumPy array and `array-api-compat` is not installed.
    """
    lower, upper = bounds
    xp = None
    if not isinstance(x, _HOST_INPUTS):
        xp = _array_namespace(x)
    if xp is not None:
        # Comparing device scalars below would copy them to the host.
        lower = _host_float("bounds[0]", lower)
        upper = _host_float("bounds[1]", upper)
        margin = _host_float("margin", margin)
        value_at_margin = _host_float("value_at_margin", value_at_margin)
    if lower > upper:
        raise ValueError(f"tolerance: bounds must satisfy lower <= upper, got {bounds}")
    if margin < 0:
        raise ValueError(f"tolerance: margin must be non-negative, got {margin}")
    if sigmoid not in _XP_SIGMOIDS:
        raise ValueError(f"tolerance: unknown sigmoid {sigmoid!r}; expected one of {SIGMOIDS}")
    if xp is not None:
        return _xp_tolerance(xp, x, lower, upper, margin, sigmoid, value_at_margin)
    if isinstance(x, _SCALAR_TYPES):
        # Plain-Python comparisons: rewards are usually computed from one distance per step.
        if lower <= x <= upper:
            return 1.0
        if margin == 0:
            return 0.0
        _check_value_at_margin(value_at_margin, sigmoid)
        distance = (lower - x if x < lower else x - upper) / margin
        return _scalar_sigmoid(float(distance), float(value_at_margin), sigmoid)
    x_array = np.asarray(x)
    in_bounds = (lower <= x_array) & (x_array <= upper)
    if margin == 0:
        value = np.where(in_bounds, 1.0, 0.0)
    else:
        distance = np.where(x_array < lower, lower - x_array, x_array - upper) / margin
        value = np.where(in_bounds, 1.0, _sigmoids(distance, value_at_margin, sigmoid))
    return float(value) if np.isscalar(x) else value
