"""Global options that attached models may set differently: how their values combine.

Most global options (`<option>`, `<size>`, `<visual>`, `<compiler>`) must agree between a
model and the models attached to it. For these, as in dm_control, differing values are
combined instead: the smaller tolerance or time step, the larger iteration count, buffer
size or far clipping plane.
"""

from __future__ import annotations

from collections.abc import Callable

_UNITS = "KMGTPE"


def bytes_of(text: str) -> int:
    """The number of bytes a `<size memory>` value ('1048576', '64K', '1M') stands for.

    Raises:
      ValueError: `text` is not digits optionally followed by one of K, M, G, T, P, E.
    """
    text = text.strip()
    if text.isdigit():
        return int(text)
    digits, unit = text[:-1], text[-1:].upper()
    if not digits.isdigit() or unit not in _UNITS:
        raise ValueError(
            f"<size> attribute 'memory': expected a byte count such as '1048576', '64K' or "
            f"'1M' (units {', '.join(_UNITS)}), got {text!r}"
        )
    return int(digits) << (10 * (_UNITS.index(unit) + 1))


def _larger_memory(first: str, second: str) -> str:
    return str(max(bytes_of(first), bytes_of(second)))


#: (section path, attribute) -> function combining two set values into the merged one.
MERGED_OPTIONS: dict[tuple[tuple[str, ...], str], Callable] = {
    **{
        (("option",), name): min
        for name in ("timestep", "tolerance", "ls_tolerance", "noslip_tolerance", "ccd_tolerance")
    },
    **{
        (("option",), name): max
        for name in (
            "iterations",
            "ls_iterations",
            "noslip_iterations",
            "ccd_iterations",
            "sdf_iterations",
            "sdf_initpoints",
        )
    },
    (("size",), "memory"): _larger_memory,
    (("size",), "njmax"): max,
    (("size",), "nconmax"): max,
    (("visual", "map"), "znear"): min,
    (("visual", "map"), "zfar"): max,
}
