"""Saves a compiled MjModel's parameters and writes them, or another model's, back in place."""

import copy
import ctypes
import functools
import operator

import mujoco
import numpy as np

from mujoco_physics.field_layout import MODEL_FIELDS

# A model whose first array (qpos0) is not empty, so its address is where the buffer starts.
_PROBE_WITH_JOINT = "<mujoco><worldbody><body><joint/><geom size='1'/></body></worldbody></mujoco>"
# A model without degrees of freedom, to check the layout where qpos0 is empty.
_PROBE_WITHOUT_JOINT = "<mujoco><worldbody><geom size='1'/><site/></worldbody></mujoco>"
_POINTER_SIZE = ctypes.sizeof(ctypes.c_void_p)
# An upper bound on the size of the mjModel struct (its arrays live elsewhere).
_MAX_STRUCT_BYTES = 1 << 16


class _RawBytes:
    """Presents `size` bytes at a raw address to NumPy, without copying them."""

    __slots__ = ("__array_interface__",)

    def __init__(self, address: int, size: int):
        self.__array_interface__ = {
            "data": (address, False),
            "shape": (size,),
            "typestr": "|u1",
            "version": 3,
        }


def _all_arrays_in(model: mujoco.MjModel, start: int, names: tuple[str, ...]) -> bool:
    end = start + model.nbuffer
    for name in names:
        array = getattr(model, name)
        if array.size:
            address = array.ctypes.data
            if address < start or address + array.nbytes > end:
                return False
    return True


@functools.cache
def _buffer_pointer_offset() -> int | None:
    """Where, in the mjModel struct, the pointer to the model's array buffer is stored.

    MuJoCo keeps all of a model's arrays in one block of `nbuffer` bytes, and the
    struct holds a pointer to it just before the arrays' own pointers (the first of
    which, qpos0, points at the start of the block). The offset is found by reading
    the struct of a probe model, then checked against a second probe; None means
    this MuJoCo lays models out differently and snapshots are not supported.
    """
    names = MODEL_FIELDS.arrays
    probe = mujoco.MjModel.from_xml_string(_PROBE_WITH_JOINT)
    start = probe.qpos0.ctypes.data
    # The qpos0 pointer itself holds `start`, so the scan ends inside the struct.
    for offset in range(0, _MAX_STRUCT_BYTES, _POINTER_SIZE):
        if ctypes.c_void_p.from_address(probe._address + offset).value == start:
            break
    else:
        return None
    if not _all_arrays_in(probe, start, names):
        return None
    other = mujoco.MjModel.from_xml_string(_PROBE_WITHOUT_JOINT)
    other_start = ctypes.c_void_p.from_address(other._address + offset).value
    if other_start is None or not _all_arrays_in(other, other_start, names):
        return None
    return offset


def snapshots_supported() -> bool:
    """Whether this MuJoCo's model layout allows `ModelSnapshot`."""
    return _buffer_pointer_offset() is not None


_WORD = np.dtype(np.uint64)
_structure_masks: dict[tuple, np.ndarray] = {}
_MAX_STRUCTURE_MASKS = 16


def _structure_mask(model: mujoco.MjModel, start: int, layout: tuple) -> np.ndarray:
    """Per 8-byte word of the buffer: True unless it holds a free float parameter.

    Float arrays (masses, sizes, colours, gains, mesh vertices, height field
    elevations, ...) are parameters that a recompile may change without invalidating
    anything built on the model (render contexts refresh what they copied of them:
    `mujoco_physics.render_inputs`); every other byte (ids, addresses, types, names,
    texture pixels, padding) is structure. Arrays are 8-byte aligned, so no word mixes
    the two. Cached per `layout` key.
    """
    mask = _structure_masks.get(layout)
    if mask is not None:
        return mask
    mask = np.ones(model.nbuffer // _WORD.itemsize, dtype=bool)
    for name in MODEL_FIELDS.arrays:
        array = getattr(model, name)
        if array.size and array.dtype.kind == "f":
            offset = array.ctypes.data - start
            first = offset // _WORD.itemsize
            last = -(-(offset + array.nbytes) // _WORD.itemsize)
            mask[first:last] = False
    if len(_structure_masks) >= _MAX_STRUCTURE_MASKS:
        _structure_masks.clear()
    _structure_masks[layout] = mask
    return mask


def _buffer_start(model: mujoco.MjModel) -> int:
    return ctypes.c_void_p.from_address(model._address + _buffer_pointer_offset()).value


# Reads every single-number field of a model: the sizes of model and data, its flags and
# its signature. The flags are not in the buffer, so models whose flags differ must not be
# loaded into each other.
_scalars = operator.attrgetter(*MODEL_FIELDS.scalars)


def _layout(model: mujoco.MjModel) -> tuple:
    """Equal for models whose arrays lie at the same places, whose data sizes agree and
    whose flags are the same."""
    return _scalars(model)


# The MjModel structs a snapshot saves besides the buffer. Bindings before mujoco 3.16 give
# them no setter: they are then copied field by field (about 100 µs instead of 0.2 µs).
_STRUCTS = ("opt", "vis", "stat")
_STRUCTS_ASSIGNABLE = all(getattr(mujoco.MjModel, name).fset is not None for name in _STRUCTS)


def _copy_struct(target, source) -> None:
    """Copies every field of MuJoCo struct `source` into `target` in place, nested ones too."""
    for name in dir(source):
        if name.startswith("_"):
            continue
        value = getattr(source, name)
        if isinstance(value, type):
            continue
        if isinstance(value, np.ndarray):
            getattr(target, name)[...] = value
        elif isinstance(value, (int, float)):
            setattr(target, name, value)
        else:
            _copy_struct(getattr(target, name), value)


class ModelSnapshot:
    """The parameters of one compiled `mujoco.MjModel`, restorable in place.

    `restore()` writes every array of the model and its `opt`, `vis` and `stat`
    structs back to their values when the snapshot was taken, without allocating:
    NumPy views of the model's fields, and bindings built on them, stay valid. The
    model's sizes cannot change, so nothing else can differ.

    `load(other)` does the same with the parameters of another compiled model of the
    same structure, so a recompile that only changed parameters (colours, sizes,
    masses, ...) can reuse everything built on this model. `save()` takes the model's
    current parameters instead, once they were patched in place.
    `mjcf.patching.compiled_model.CompiledModel` decides when a reset restores, patches,
    loads or compiles afresh.

    Raises (on construction):
      RuntimeError: if `snapshots_supported()` is False.
    """

    __slots__ = ("_model", "_start", "_layout", "_buffer", "_saved_buffer", "_opt", "_vis", "_stat")

    def __init__(self, model: mujoco.MjModel):
        if not snapshots_supported():
            raise RuntimeError(
                f"mujoco {mujoco.__version__} lays out MjModel in a way ModelSnapshot does "
                "not recognise"
            )
        self._model = model
        self._start = _buffer_start(model)
        self._layout = _layout(model)
        # The view does not own the memory: holding `model` keeps the buffer alive.
        self._buffer = np.asarray(_RawBytes(self._start, model.nbuffer))
        self._saved_buffer = self._buffer.copy()
        self._save_structs(model)

    def _save_structs(self, model: mujoco.MjModel) -> None:
        self._opt = copy.copy(model.opt)
        self._vis = copy.copy(model.vis)
        self._stat = copy.copy(model.stat)

    def save(self) -> None:
        """Takes the model's current arrays and `stat` as the ones to restore, after a patch
        of the compiled model (`mjcf.patching.model_patch`: it writes arrays, and
        `mj_setConst` updates `stat`) made them those of a fresh compile."""
        np.copyto(self._saved_buffer, self._buffer)
        self._stat = copy.copy(self._model.stat)

    def restore(self) -> None:
        """Writes the saved parameters back into the model."""
        np.copyto(self._buffer, self._saved_buffer)
        model = self._model
        if _STRUCTS_ASSIGNABLE:
            model.opt = self._opt
            model.vis = self._vis
            model.stat = self._stat
        else:
            _copy_struct(model.opt, self._opt)
            _copy_struct(model.vis, self._vis)
            _copy_struct(model.stat, self._stat)

    def load(self, other: mujoco.MjModel) -> bool:
        """Takes `other`'s parameters as this snapshot's, and restores them into the model.

        Returns False, changing nothing, unless `other` has the same structure as the
        model: the same sizes, and the same bytes everywhere except in float
        parameter arrays (so the same names, ids, addresses, types and assets).
        """
        if _layout(other) != self._layout:
            return False
        other_start = _buffer_start(other)
        other_buffer = np.asarray(_RawBytes(other_start, other.nbuffer))
        words = self._model.nbuffer // _WORD.itemsize
        end = words * _WORD.itemsize
        mask = _structure_mask(other, other_start, self._layout)
        saved_words = self._saved_buffer[:end].view(_WORD)
        other_words = other_buffer[:end].view(_WORD)
        if np.any((saved_words != other_words) & mask) or not np.array_equal(
            self._saved_buffer[end:], other_buffer[end:]
        ):
            return False
        np.copyto(self._saved_buffer, other_buffer)
        self._save_structs(other)
        self.restore()
        return True
