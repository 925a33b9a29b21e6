"""Every `mjt*` enum of the installed `mujoco`, as a named tuple of its members' int
values (`enums.mjtObj.mjOBJ_BODY == 1`), the form dm_control's generated module has."""

import collections

import mujoco


def _as_named_tuple(name: str, enum_type) -> tuple:
    members = enum_type.__members__
    return collections.namedtuple(name, list(members))(*(int(v) for v in members.values()))


_ENUMS = {
    name: _as_named_tuple(name, getattr(mujoco, name))
    for name in dir(mujoco)
    if name.startswith("mjt") and hasattr(getattr(mujoco, name), "__members__")
}
globals().update(_ENUMS)

__all__ = sorted(_ENUMS)
