"""Thin wrappers that give ``mujoco.MjModel``/``MjData`` the dm_control ``.ptr`` interface.

Attribute reads are forwarded to the wrapped MuJoCo object; arrays whose size cannot change
(every MjModel array, and the MjData arrays sized by model counts) are cached on first read,
so later reads are plain instance-dictionary hits and return the same NumPy view.
"""

import contextlib
from collections.abc import Iterator

import mujoco

from mjcf import field_layout

_DISABLE_PREFIX = "mjDSBL_"
_ENABLE_PREFIX = "mjENBL_"


def _object_type(object_type) -> mujoco.mjtObj:
    """``mujoco.mjtObj`` for a name such as 'geom' or 'camera', or an mjtObj value."""
    if isinstance(object_type, str):
        member = f"mjOBJ_{object_type.upper()}"
        if member not in mujoco.mjtObj.__members__:
            known = sorted(
                name[len("mjOBJ_") :].lower()
                for name in mujoco.mjtObj.__members__
                if name.startswith("mjOBJ_")
            )
            raise ValueError(f"unknown object type {object_type!r}; expected one of {known}")
        return mujoco.mjtObj.__members__[member]
    return mujoco.mjtObj(int(object_type))


def _flag_bits(flags, enum_type, prefix: str) -> int:
    """OR of option flags given as lowercase names ('gravity') or enum values."""
    bits = 0
    for flag in flags:
        if isinstance(flag, str):
            member = f"{prefix}{flag.upper()}"
            if member not in enum_type.__members__:
                known = sorted(
                    name[len(prefix) :].lower()
                    for name in enum_type.__members__
                    if name.startswith(prefix) and not name.endswith("NDISABLE")
                )
                raise ValueError(f"unknown flag {flag!r}; expected one of {known}")
            bits |= int(enum_type.__members__[member])
        else:
            bits |= int(flag)
    return bits


@contextlib.contextmanager
def flags_set(opt, field: str, bits: int) -> Iterator[None]:
    """Sets `bits` in option field `field` ('disableflags' or 'enableflags') while active."""
    previous = getattr(opt, field)
    setattr(opt, field, previous | bits)
    try:
        yield
    finally:
        setattr(opt, field, previous)


class _StructWrapper:
    """Forwards attribute access to a MuJoCo struct and caches its fixed-size arrays."""

    _cacheable: frozenset = frozenset()

    def __init__(self, ptr):
        object.__setattr__(self, "_ptr", ptr)

    @property
    def ptr(self):
        """The wrapped ``mujoco`` object, for passing to ``mujoco.mj_*`` functions."""
        return self._ptr

    def __getattr__(self, name):
        if name == "_ptr":
            raise AttributeError(name)
        value = getattr(self._ptr, name)
        if name in self._cacheable:
            self.__dict__[name] = value
        return value

    def __setattr__(self, name, value):
        self.__dict__.pop(name, None)
        setattr(self._ptr, name, value)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(dir(self._ptr)))


def _static_data_fields() -> frozenset:
    """MjData arrays whose size is fixed by model counts (not by contacts or constraints)."""
    return frozenset(
        name
        for name, extent in field_layout.DATA_EXTENTS.items()
        if hasattr(mujoco.MjModel, extent[0])
    )


class ModelWrapper(_StructWrapper):
    """A ``mujoco.MjModel`` with dm_control's helpers: ``ptr``, ``name2id``, ``disable``."""

    _cacheable = frozenset(field_layout.MODEL_EXTENTS) | {"opt", "vis", "stat"}

    def name2id(self, name: str, object_type) -> int:
        """The id of the object of ``object_type`` ('geom', 'body', ...) called ``name``.

        Raises:
          ValueError: if there is no such object.
        """
        obj_type = _object_type(object_type)
        object_id = mujoco.mj_name2id(self._ptr, obj_type, name)
        if object_id == -1:
            type_name = obj_type.name[len("mjOBJ_") :].lower()
            raise ValueError(f"Object of type {type_name!r} with name {name!r} does not exist.")
        return object_id

    def id2name(self, object_id: int, object_type) -> str:
        """The name of object ``object_id`` of ``object_type``; '' when it has none."""
        return mujoco.mj_id2name(self._ptr, _object_type(object_type), object_id) or ""

    def disable(self, *flags) -> contextlib.AbstractContextManager[None]:
        """Temporarily sets MuJoCo disable flags ('gravity', 'contact', 'actuation', ...)."""
        bits = _flag_bits(flags, mujoco.mjtDisableBit, _DISABLE_PREFIX)
        return flags_set(self._ptr.opt, "disableflags", bits)

    def enable(self, *flags) -> contextlib.AbstractContextManager[None]:
        """Temporarily sets MuJoCo enable flags ('energy', 'multiccd', ...)."""
        bits = _flag_bits(flags, mujoco.mjtEnableBit, _ENABLE_PREFIX)
        return flags_set(self._ptr.opt, "enableflags", bits)

    def __repr__(self):
        return f"ModelWrapper(nbody={self._ptr.nbody}, ngeom={self._ptr.ngeom}, nq={self._ptr.nq})"


class DataWrapper(_StructWrapper):
    """A ``mujoco.MjData`` with dm_control's ``ptr`` and a wrapped ``model``."""

    _cacheable = _static_data_fields()

    def __init__(self, ptr: mujoco.MjData, model: ModelWrapper):
        super().__init__(ptr)
        object.__setattr__(self, "_model", model)

    @property
    def model(self) -> ModelWrapper:
        return self._model

    def __repr__(self):
        return f"DataWrapper(time={self._ptr.time}, ncon={self._ptr.ncon})"
