"""MuJoCo's `mj*` constants (`mjMAXVAL`, `mjNGROUP`, `mjDISABLESTRING`, ...), read from
the installed `mujoco`."""

import re

import mujoco

_CONSTANT = re.compile(r"^mj[A-Z][A-Z0-9_]*$")

_CONSTANTS = {
    name: getattr(mujoco, name)
    for name in dir(mujoco)
    if _CONSTANT.match(name) and isinstance(getattr(mujoco, name), (int, float, str, tuple))
}
globals().update(_CONSTANTS)

__all__ = sorted(_CONSTANTS)
