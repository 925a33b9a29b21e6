"""Number formatting and small rotations shared by the model builders."""

import math
from collections.abc import Iterable


def vec(values: Iterable[float]) -> str:
    """Formats numbers as a space-separated MJCF attribute value."""
    return " ".join(f"{v:.6g}" for v in values)


def quat_about_axis(
    axis: tuple[float, float, float], angle: float
) -> tuple[float, float, float, float]:
    """Unit quaternion (w, x, y, z) of a rotation by `angle` radians about a unit axis."""
    sin = math.sin(angle / 2)
    return (math.cos(angle / 2), axis[0] * sin, axis[1] * sin, axis[2] * sin)


def check_rgba(rgba: Iterable[float], function: str) -> tuple[float, ...]:
    """Returns `rgba` as a tuple, or raises ValueError unless it is 4 numbers in [0, 1]."""
    values = tuple(rgba)
    if len(values) != 4 or not all(0.0 <= v <= 1.0 for v in values):
        raise ValueError(
            f"{function} argument 'rgba': expected 4 numbers in [0, 1], got {values!r}"
        )
    return values


def check_positive(value: float, argument: str, function: str) -> float:
    """Returns `value`, or raises ValueError unless it is a positive number."""
    if not value > 0:
        raise ValueError(
            f"{function} argument {argument!r}: expected a positive number, got {value!r}"
        )
    return value


def check_name(name: str, function: str) -> str:
    """Returns `name`, or raises ValueError unless it is a non-empty string without '/'."""
    if not isinstance(name, str) or not name or "/" in name:
        raise ValueError(
            f"{function} argument 'name': expected a non-empty string without '/', got {name!r}"
        )
    return name
