"""`MjModel`/`MjData` with dm_control's interface (`ptr`, `name2id`, `disable`, the
named constructors), the global callbacks, and the visualisation structs with `ptr`.

Served as `dm_control.mujoco.wrapper.core`. Every field of the wrapped MuJoCo struct is a
class attribute of its wrapper (`MjModel.geom_pos`, with MuJoCo's description of the field as
its docstring), made from the installed `mujoco`; other attribute reads are forwarded to the
wrapped object. Arrays whose size cannot change (every MjModel array, and the MjData arrays
sized by model counts) are cached on first read, so later reads are plain
instance-dictionary hits and return the same NumPy view.
"""

import contextlib
import copy
import time
import weakref
from collections.abc import Callable, Iterator

import mujoco
import numpy as np
from mujoco.introspect import structs as _introspect

from mujoco_physics import field_layout

# dm_control's name for the module of MuJoCo's functions, which clients reach through
# `wrapper.core.mjlib` (`core.mjlib.mjv_defaultOption(core.MjvOption().ptr)`).
from mujoco_physics.wrapper.mjbindings import mjlib  # noqa: F401

# The name under which MJB bytes are handed to MuJoCo in a one-file virtual file system.
_MJB_NAME = "model.mjb"


class Error(ValueError):
    """A model MuJoCo could not load, or a bad object type or id (dm_control's
    `wrapper.Error`; a ValueError, as MuJoCo's own loaders raise)."""


# Message formats, under the names dm_control's tests read them from.
_CONTACT_ID_OUT_OF_RANGE = "contact_id {actual} is out of range: expected 0 to {max_valid}"
_NOT_LAST_PARSED_ERROR = (
    "check_model is not the model MuJoCo parsed last: only that one can be saved as XML"
)

# The model MuJoCo parsed from XML last (mj_saveLastXML writes that one), while it lives.
_last_parsed = None


_DISABLE_PREFIX = "mjDSBL_"
_ENABLE_PREFIX = "mjENBL_"


def _object_type(object_type) -> mujoco.mjtObj:
    """`mujoco.mjtObj` for a name such as 'geom' or 'camera', or an mjtObj value."""
    if isinstance(object_type, str):
        member = f"mjOBJ_{object_type.upper()}"
        if member not in mujoco.mjtObj.__members__:
            known = sorted(
                name[len("mjOBJ_") :].lower()
                for name in mujoco.mjtObj.__members__
                if name.startswith("mjOBJ_")
            )
            raise Error(f"unknown object type {object_type!r}; expected one of {known}")
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
            valid = {int(value) for value in enum_type.__members__.values()}
            if int(flag) not in valid:
                raise ValueError(f"unknown flag {flag!r}; expected one of {sorted(valid)}")
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


class _StructField:
    """One field of the wrapped MuJoCo struct, as a class attribute of its wrapper.

    Read on an instance, it forwards to the wrapped struct and keeps a fixed-size array in
    the instance dictionary. It is a non-data descriptor, so the instance dictionary comes
    first: later reads are plain dictionary hits that never reach it, and writes go through
    the wrapper's `__setattr__`. Read on the class, it is the field's documented `property`
    (`help(MjModel.geom_pos)`), as dm_control's wrappers have.
    """

    __slots__ = ("_name", "_cached", "_property")

    def __init__(self, name: str, cached: bool, doc: str, settable: bool):
        self._name = name
        self._cached = cached
        self._property = property(self.__get__, _field_setter(name) if settable else None, doc=doc)

    def __get__(self, instance, owner=None):
        if instance is None:
            return self._property
        value = getattr(instance._ptr, self._name)
        if self._cached:
            instance.__dict__[self._name] = value
        return value


def _field_setter(name: str) -> Callable:
    def set_field(wrapper, value) -> None:
        setattr(wrapper, name, value)

    return set_field


# The array fields' extents, named after model sizes ('ngeom', 3), for the docstrings.
_EXTENTS = {mujoco.MjModel: field_layout.MODEL_EXTENTS, mujoco.MjData: field_layout.DATA_EXTENTS}


def _struct_fields(wrapper: type, struct: type) -> dict[str, _StructField]:
    """A `_StructField` for each field of `struct` (`mujoco.MjModel`) that `wrapper` and its
    bases do not define themselves, documented from `mujoco.introspect`."""
    # mujoco.MjModel is MuJoCo's mjModel.
    declared = _introspect.STRUCTS.get("mj" + struct.__name__[len("Mj") :])
    docs = {field.name: field.doc for field in declared.fields} if declared else {}
    extents = _EXTENTS.get(struct, {})
    fields = {}
    for name, descriptor in vars(struct).items():
        if name.startswith("_") or not isinstance(descriptor, property):
            continue
        if any(name in vars(base) for base in wrapper.__mro__):
            continue
        settable = descriptor.fset is not None
        notes = (
            f"Forwarded to `mujoco.{struct.__name__}.{name}`{'' if settable else ', read-only'}."
        )
        if name in extents:
            notes = f"Shape ({', '.join(str(extent) for extent in extents[name])}). {notes}"
        doc = docs.get(name) or (descriptor.__doc__ or "").strip()
        if doc:
            notes = f"{doc}\n\n{notes}"
        fields[name] = _StructField(name, name in wrapper._cacheable, notes, settable)
    return fields


class _StructWrapper:
    """Forwards attribute access to a MuJoCo struct and caches its fixed-size arrays.

    A subclass names the struct it wraps (`class MjModel(_StructWrapper,
    struct=mujoco.MjModel)`) and gets each of its fields as a class attribute.
    """

    _cacheable: frozenset = frozenset()

    def __init_subclass__(cls, *, struct: type | None = None, **kwargs):
        super().__init_subclass__(**kwargs)
        if struct is not None:
            for name, field in _struct_fields(cls, struct).items():
                setattr(cls, name, field)

    def __init__(self, ptr):
        object.__setattr__(self, "_ptr", ptr)

    @property
    def ptr(self):
        """The wrapped `mujoco` object, for passing to `mujoco.mj_*` functions."""
        return self._ptr

    def __getattr__(self, name):
        # Only what is not a struct field gets here (`model.geom('name')`, `bind`).
        if name == "_ptr":
            raise AttributeError(name)
        return getattr(self._ptr, name)

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


class MjModel(_StructWrapper, struct=mujoco.MjModel):
    """A `mujoco.MjModel` with dm_control's helpers: `ptr`, `name2id`, `disable`.

    `MjModel(model)` wraps a `mujoco.MjModel`; the `from_*` constructors load one.
    """

    _cacheable = frozenset(field_layout.MODEL_EXTENTS) | {"opt", "vis", "stat"}

    @classmethod
    def from_xml_string(cls, xml_string: str, assets: dict | None = None) -> "MjModel":
        """Compiles MJCF (or URDF) text; `assets` maps file names used in it to bytes.

        Raises:
          Error: when MuJoCo cannot compile it (MuJoCo's message).
        """
        return cls(_parse(mujoco.MjModel.from_xml_string, xml_string, assets=assets))

    @classmethod
    def from_xml_path(cls, xml_path: str) -> "MjModel":
        """Compiles the MJCF or URDF file at `xml_path`."""
        return cls(_parse(mujoco.MjModel.from_xml_path, str(xml_path)))

    @classmethod
    def from_binary_path(cls, binary_path: str) -> "MjModel":
        """Loads the MJB model file at `binary_path`."""
        return cls(_load(mujoco.MjModel.from_binary_path, str(binary_path)))

    @classmethod
    def from_byte_string(cls, byte_string: bytes) -> "MjModel":
        """Loads a model from MJB bytes (what `to_bytes` returns).

        Raises:
          Error: if `byte_string` is not a model binary this MuJoCo can load.
        """
        try:
            model = mujoco.MjModel.from_binary_path(_MJB_NAME, {_MJB_NAME: bytes(byte_string)})
        except ValueError as error:
            raise Error(
                f"byte_string ({len(byte_string)} bytes) is not a MuJoCo model binary (MJB) "
                f"that this MuJoCo can load: {error}"
            ) from None
        return cls(model)

    @property
    def _model(self) -> mujoco.MjModel:
        # dm_control's attribute name for the wrapped struct, which code reaches for.
        return self._ptr

    def to_bytes(self) -> bytes:
        """The model as MJB bytes."""
        buffer = np.empty(mujoco.mj_sizeModel(self._ptr), dtype=np.uint8)
        mujoco.mj_saveModel(self._ptr, None, buffer)
        return buffer.tobytes()

    def save_binary(self, binary_path: str) -> None:
        """Writes the model as an MJB file."""
        mujoco.mj_saveModel(self._ptr, str(binary_path), None)

    def copy(self) -> "MjModel":
        """A deep copy of the model."""
        return self.__copy__()

    def __copy__(self) -> "MjModel":
        return type(self)(copy.copy(self._ptr))

    def __getstate__(self):
        return self._ptr

    def __setstate__(self, state) -> None:
        object.__setattr__(self, "_ptr", state)

    def free(self) -> None:
        """Drops the reference to the MuJoCo model (freed once nothing else holds it)."""
        self.__dict__.clear()
        object.__setattr__(self, "_ptr", None)

    @property
    def name(self) -> str:
        """The model's name (`<mujoco model=...>`): the first string in `names`."""
        names = bytes(self._ptr.names)
        return names[: names.index(b"\0")].decode()

    def name2id(self, name: str, object_type) -> int:
        """The id of the object of `object_type` ('geom', 'body', ...) called `name`.

        Raises:
          ValueError: if there is no such object.
        """
        obj_type = _object_type(object_type)
        object_id = mujoco.mj_name2id(self._ptr, obj_type, name)
        if object_id == -1:
            type_name = obj_type.name[len("mjOBJ_") :].lower()
            raise Error(f"Object of type {type_name!r} with name {name!r} does not exist.")
        return object_id

    def id2name(self, object_id: int, object_type) -> str:
        """The name of object `object_id` of `object_type`; '' when it has none."""
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
        return f"MjModel(nbody={self._ptr.nbody}, ngeom={self._ptr.ngeom}, nq={self._ptr.nq})"


class MjData(_StructWrapper, struct=mujoco.MjData):
    """A `mujoco.MjData` with dm_control's `ptr`, a wrapped `model` and helpers.

    `MjData(model)` allocates data for a wrapped `MjModel`; `MjData(data)` wraps a
    `mujoco.MjData`.
    """

    _cacheable = _static_data_fields()

    def __init__(self, model_or_data: "MjModel | mujoco.MjData"):
        if isinstance(model_or_data, MjModel):
            model, data = model_or_data, mujoco.MjData(model_or_data.ptr)
        elif isinstance(model_or_data, mujoco.MjData):
            model, data = MjModel(model_or_data.model), model_or_data
        else:
            raise TypeError(
                "MjData expects a wrapper.MjModel or a mujoco.MjData, got "
                f"{type(model_or_data).__name__}"
            )
        super().__init__(data)
        object.__setattr__(self, "_model", model)

    @property
    def model(self) -> MjModel:
        """The wrapped model this data belongs to."""
        return self._model

    @property
    def _data(self) -> mujoco.MjData:
        # dm_control's attribute name for the wrapped struct, which code reaches for.
        return self._ptr

    def copy(self) -> "MjData":
        """A copy of the data sharing this model."""
        return self.__copy__()

    def __copy__(self) -> "MjData":
        return self._make_copy(share_model=True)

    def _make_copy(self, share_model: bool) -> "MjData":
        return type(self)((copy.copy if share_model else copy.deepcopy)(self._ptr))

    def __getstate__(self):
        return self._ptr

    def __setstate__(self, state) -> None:
        object.__setattr__(self, "_ptr", state)
        object.__setattr__(self, "_model", MjModel(state.model))

    def object_velocity(self, object_id, object_type, local_frame: bool = False) -> np.ndarray:
        """The (linear, angular) velocity of an object, as a (2, 3) array.

        Args:
          object_id: the object's id or name.
          object_type: 'body', 'geom', 'site', ... or an `mjtObj` value.
          local_frame: whether to express it in the object's frame instead of the world's.
        """
        obj_type = _object_type(object_type)
        if isinstance(object_id, str):
            object_id = self._model.name2id(object_id, obj_type)
        velocity = np.empty(6)
        mujoco.mj_objectVelocity(
            self._model.ptr, self._ptr, obj_type, object_id, velocity, int(local_frame)
        )
        # MuJoCo gives (angular, linear).
        return velocity.reshape(2, 3)[::-1]

    def contact_force(self, contact_id: int) -> np.ndarray:
        """The wrench of contact `contact_id` in its frame: (force, torque) as (2, 3).

        Raises:
          ValueError: if `contact_id` is not in [0, ncon).
        """
        ncon = self._ptr.ncon
        if not 0 <= contact_id < ncon:
            raise ValueError(_CONTACT_ID_OUT_OF_RANGE.format(actual=contact_id, max_valid=ncon - 1))
        # The parts of mj_step2 that the constraint forces depend on.
        mujoco.mj_fwdActuation(self._model.ptr, self._ptr)
        mujoco.mj_fwdAcceleration(self._model.ptr, self._ptr)
        mujoco.mj_fwdConstraint(self._model.ptr, self._ptr)
        wrench = np.empty(6)
        mujoco.mj_contactForce(self._model.ptr, self._ptr, contact_id, wrench)
        return wrench.reshape(2, 3)

    @property
    def contact(self):
        """The active contacts (the first `ncon` of the contact buffer)."""
        return self._ptr.contact[: self._ptr.ncon]

    def __repr__(self):
        return f"MjData(time={self._ptr.time}, ncon={self._ptr.ncon})"


def _load(loader: Callable, *args, **kwargs) -> mujoco.MjModel:
    try:
        return loader(*args, **kwargs)
    except ValueError as error:
        raise Error(str(error)) from None


def _parse(loader: Callable, *args, **kwargs) -> mujoco.MjModel:
    global _last_parsed
    model = _load(loader, *args, **kwargs)
    _last_parsed = weakref.ref(model)
    return model


def set_callback(name: str, new_callback=None) -> None:
    """Sets MuJoCo's global callback `name` ('mjcb_passive', 'mjcb_control', ...);
    None removes it."""
    setter = getattr(mujoco, f"set_{name}", None)
    if setter is None:
        known = sorted(n[len("set_") :] for n in dir(mujoco) if n.startswith("set_mjcb_"))
        raise ValueError(f"unknown MuJoCo callback {name!r}; expected one of {known}")
    setter(new_callback)


@contextlib.contextmanager
def callback_context(name: str, new_callback=None) -> Iterator[None]:
    """Sets callback `name` inside the block and restores the previous one after."""
    previous = getattr(mujoco, f"get_{name}")()
    set_callback(name, new_callback)
    try:
        yield
    finally:
        set_callback(name, previous)


def enable_timer(enabled: bool = True) -> None:
    """Turns MuJoCo's profiling timers (`data.timer`) on or off."""
    set_callback("mjcb_time", time.time if enabled else None)


def get_schema() -> str:
    """MuJoCo's MJCF schema as text (`mj_printSchema`)."""
    return mujoco.mj_printSchema(False, False)


def save_last_parsed_model_to_xml(xml_path: str, check_model: MjModel | None = None) -> None:
    """Writes the model MuJoCo parsed last (from XML), with `check_model`'s current
    values where given, to `xml_path`.

    Raises:
      ValueError: if `check_model` is not the model parsed last.
    """
    last = _last_parsed() if _last_parsed is not None else None
    if check_model is not None and getattr(check_model, "ptr", check_model) is not last:
        raise ValueError(_NOT_LAST_PARSED_ERROR)
    mujoco.mj_saveLastXML(str(xml_path), last)


class _OwnPointer:
    """dm_control's `ptr` on a struct that is itself the `mujoco` object."""

    @property
    def ptr(self):
        return self


class MjvCamera(_OwnPointer, mujoco.MjvCamera):
    """`mujoco.MjvCamera` with dm_control's `ptr`."""


class MjvOption(_OwnPointer, mujoco.MjvOption):
    """`mujoco.MjvOption` with dm_control's `ptr`."""


class MjvPerturb(_OwnPointer, mujoco.MjvPerturb):
    """`mujoco.MjvPerturb` with dm_control's `ptr`."""


class MjvFigure(_OwnPointer, mujoco.MjvFigure):
    """`mujoco.MjvFigure` with dm_control's `ptr`."""


class MjvScene(_OwnPointer, mujoco.MjvScene):
    """`mujoco.MjvScene` for a wrapped model, with dm_control's `ptr`, `free` and
    `geoms` (the `ngeom` geoms in use, not the whole buffer)."""

    def __init__(self, model: MjModel | None = None, max_geom: int = 1000):
        if model is None:
            super().__init__()
        else:
            super().__init__(getattr(model, "ptr", model), max_geom)

    @property
    def geoms(self):
        return super().geoms[: self.ngeom]

    def free(self) -> None:
        """Nothing to do: the scene's memory goes with the object."""


class MjrContext(_OwnPointer, mujoco.MjrContext):
    """`mujoco.MjrContext` with dm_control's `ptr` and `free`, made in `gl_context`
    (an object whose `make_current()` context manager yields a caller with
    `call(function, *args)`, as dm_control's renderers have), or in the current one.

    Raises:
      ValueError: for a `font_scale` that is not an `mjtFontScale` value.
    """

    def __init__(
        self, model: MjModel, gl_context=None, font_scale=mujoco.mjtFontScale.mjFONTSCALE_150
    ):
        scales = {int(value) for value in mujoco.mjtFontScale.__members__.values()}
        if int(font_scale) not in scales:
            raise ValueError(f"font_scale: expected one of {sorted(scales)}, got {font_scale!r}")
        self._gl_context = gl_context
        model = getattr(model, "ptr", model)
        if gl_context is None:
            super().__init__(model, int(font_scale))
        else:
            with gl_context.make_current() as caller:
                caller.call(super().__init__, model, int(font_scale))

    def free(self) -> None:
        """Frees the context's OpenGL resources now (in its OpenGL context)."""
        if self._gl_context is None:
            mujoco.MjrContext.free(self)
        else:
            with self._gl_context.make_current() as caller:
                caller.call(mujoco.MjrContext.free, self)
