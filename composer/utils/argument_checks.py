"""Checks of public arguments: each takes the argument by keyword and names it in its error.

`integer(num_envs=n)` returns `n` as an int or raises
`ValueError: num_envs: expected an integer >= 1, got 0`. A bool is never accepted where a
number is expected (`True` is an int in Python, never a meaningful count or rate).
"""

import math
import numbers
from typing import Any

import numpy as np

__all__ = ["integer", "number", "writeable_array_problem"]


def _one(argument: dict[str, Any]) -> tuple[str, Any]:
    if len(argument) != 1:
        raise TypeError(f"expected one argument by keyword, got {sorted(argument)}")
    return next(iter(argument.items()))


def _suffix(unit: str | None, or_none: bool) -> str:
    return (f" ({unit})" if unit else "") + (" or None" if or_none else "")


def integer(
    minimum: int = 1, *, or_none: bool = False, unit: str | None = None, **argument: Any
) -> int | None:
    """Returns the one keyword argument as an int if it is an integer >= `minimum`.

    Args:
      minimum: the smallest value accepted.
      or_none: whether None is accepted (and returned).
      unit: what the number counts, for the message ("screen pixels").
      **argument: `name=value`, exactly one.

    Raises:
      ValueError: `"<name>: expected an integer >= <minimum>, got <value>"`.
    """
    name, value = _one(argument)
    if value is None and or_none:
        return None
    if isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= minimum:
        return int(value)
    raise ValueError(
        f"{name}: expected an integer >= {minimum}{_suffix(unit, or_none)}, got {value!r}"
    )


def number(
    *,
    above: float | None = None,
    at_least: float | None = None,
    at_most: float | None = None,
    or_none: bool = False,
    unit: str | None = None,
    **argument: Any,
) -> float | None:
    """Returns the one keyword argument as a float if it is a finite number in range.

    Args:
      above: values must be greater than this (`above=0`: a positive number).
      at_least, at_most: inclusive bounds.
      or_none: whether None is accepted (and returned).
      unit: what the number measures, for the message ("seconds").
      **argument: `name=value`, exactly one.

    Raises:
      ValueError: naming the argument, the range expected and the value got.
    """
    name, value = _one(argument)
    if value is None and or_none:
        return None
    if (
        isinstance(value, numbers.Real)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and (above is None or value > above)
        and (at_least is None or value >= at_least)
        and (at_most is None or value <= at_most)
    ):
        return float(value)
    raise ValueError(
        f"{name}: expected {_range(above, at_least, at_most)}{_suffix(unit, or_none)}, "
        f"got {value!r}"
    )


def _range(above, at_least, at_most) -> str:
    if above == 0 and at_least is None and at_most is None:
        return "a positive number"
    if at_least is not None and at_most is not None:
        return f"a number in [{at_least}, {at_most}]"
    bounds = [
        f"> {above}" if above is not None else "",
        f">= {at_least}" if at_least is not None else "",
        f"<= {at_most}" if at_most is not None else "",
    ]
    return " ".join(["a number", *filter(None, bounds)])


def writeable_array_problem(value: Any, shape: tuple[int, ...], dtype: Any) -> str | None:
    """Why `value` cannot be written into as an array of `shape` and `dtype`, or None.

    Returns:
      None for a writeable NumPy array of exactly that shape and dtype; else
      `"expected a writeable <dtype> array of shape <shape>, got <what value is>"`.
    """
    dtype = np.dtype(dtype)
    if (
        isinstance(value, np.ndarray)
        and value.shape == tuple(shape)
        and value.dtype == dtype
        and value.flags.writeable
    ):
        return None
    if isinstance(value, np.ndarray):
        kind = "" if value.flags.writeable else " read-only"
        got = f"a{kind} {value.dtype} array of shape {value.shape}"
    else:
        got = type(value).__name__
    return f"expected a writeable {dtype} array of shape {tuple(shape)}, got {got}"
