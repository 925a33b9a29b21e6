"""String conversions and the library handle (served as `dm_control.mujoco.wrapper.util`)."""

import sys
from types import ModuleType

import mujoco

DEFAULT_ENCODING = sys.getdefaultencoding()


def to_binary_string(s: str | bytes) -> bytes:
    """`s` as bytes."""
    return s if isinstance(s, bytes) else s.encode(DEFAULT_ENCODING)


def to_native_string(s: str | bytes) -> str:
    """`s` as str."""
    return s.decode(DEFAULT_ENCODING) if isinstance(s, bytes) else s


def get_mjlib() -> ModuleType:
    """The MuJoCo function library: the `mujoco` module."""
    return mujoco
