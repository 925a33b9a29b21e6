"""Views of a batch's MjModel/MjData fields: by field name, by MJCF element, by object name.

Each view reads the batch physics' own memory (MuJoCo Warp's arrays, or `mujoco.batch`'s
rows) through a view made once in the batch's namespace (see `composer.batch.arrays`), with a
leading `num_envs` axis and the trailing shape of the C field of the same name (`data.xmat`
is (num_envs, nbody, 9)), in the physics' float dtype (float32 on MuJoCo Warp, float64 on
`mujoco.batch`). Writes land in the memory of the worlds they select; a model field shared
by every world refuses them (see `composer.batch.physics` and `composer.batch.mujoco_batch`
for where values live).
"""

from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from mjcf import binding as mjcf_binding
from mujoco_physics import field_layout

if TYPE_CHECKING:
    from composer.batch.physics import BatchPhysics

__all__ = [
    "BatchBinding",
    "BatchFields",
    "FieldStorage",
    "FieldView",
    "NamedViews",
    "StructViews",
]


class FieldStorage(NamedTuple):
    """Where a `FieldView` reads a field, as its batch physics reports it.

    Attributes:
      view: the field's memory in the batch's namespace, (num_envs, *C shape) for a
        per-world field, (1, *C shape) for a model field shared by every world.
      per_world: whether each world has its own row.
      gatherable: whether `composer.batch.gather` may read it (a field of the batch's float
        dtype).
      device_array: the Warp array behind `view` (None off MuJoCo Warp).
    """

    view: Any
    per_world: bool
    gatherable: bool
    device_array: Any = None


class FieldView:
    """One MjModel/MjData field of every world, as a view in the batch's namespace.

    Attributes:
      view: the field's memory, shape (num_envs, *C shape) for a per-world field,
        (1, *C shape) for a model field shared by every world.
      per_world: whether each world has its own row.
      gatherable: whether it is a field of the batch's float dtype.
      device_array: the MuJoCo Warp array behind it (None on `mujoco.batch`).
    """

    def __init__(self, physics, struct: str, name: str):
        self.struct = struct
        self.name = name
        self._physics = physics
        host = physics.mj_model if struct == field_layout.MODEL else physics.host.data.ptr
        self.c_shape = np.shape(getattr(host, name))
        storage = physics.field_storage(struct, name)
        self.view = storage.view
        self.per_world = storage.per_world
        self.gatherable = storage.gatherable
        self.device_array = storage.device_array

    def read(self) -> Any:
        """The field of all worlds, (num_envs, *C shape); a shared field is broadcast."""
        if self.per_world:
            return self.view
        xp = self._physics.xp
        return xp.broadcast_to(self.view, (self._physics.num_envs, *self.c_shape))

    def check_writable(self) -> None:
        """Raises ValueError for a model field shared by every world."""
        if not self.per_world:
            raise ValueError(
                f"model field {self.name!r} is shared by all {self._physics.num_envs} worlds; "
                f"pass batched_model_fields=({self.name!r},) to give each world its own"
            )

    def write(self, worlds, index, values) -> None:
        """Writes `values` into rows `index` of `worlds` (an int array, or None for all)."""
        self.check_writable()
        view = self.view
        if _is_host(values):
            values = self._physics.arrays.asarray(values)
        if worlds is None:
            view[:, index] = values
        elif isinstance(index, slice) or np.isscalar(index):
            view[worlds, index] = values
        else:
            view[worlds[:, None], index] = values


def _is_host(values) -> bool:
    return isinstance(values, (np.ndarray, list, tuple, float, int))


class _BatchArray(np.ndarray):
    """A bound NumPy read of every world; item assignment writes through to those worlds."""

    _field: FieldView | None = None
    _index: Any = None

    def __setitem__(self, key, value):
        np.ndarray.__setitem__(self, key, value)
        field = self._field
        if field is None:
            return
        first = key[0] if isinstance(key, tuple) and key else key
        if key is Ellipsis or (isinstance(key, tuple) and not key):
            first = slice(None)
        worlds = np.atleast_1d(np.arange(self.shape[0])[first])
        field.write(worlds, self._index, np.asarray(self)[worlds])

    def __array_wrap__(self, array, context=None, return_scalar=False):
        # Results of arithmetic are plain arrays, never write-through ones.
        return np.ndarray.__array_wrap__(self, array, context, return_scalar).view(np.ndarray)


def _bound(field: FieldView, index) -> Any:
    """Rows `index` of `field` in every world; in NumPy an array that writes through."""
    values = field.read()[:, index]
    if field._physics.arrays.library != "numpy":
        return values
    # A read is a snapshot: a basic index gives a view of the device memory, to be copied;
    # an index array has gathered a copy already.
    basic = isinstance(index, (int, slice, np.integer))
    array = (np.array(values) if basic else values).view(_BatchArray)
    array._field = field
    array._index = index
    return array


class BatchBinding:
    """The fields of one MJCF element, or of a list of same-kind elements, in every world.

    Attribute names are those of `mjcf.Physics.bind` (`xpos`, `qpos`, `pos`, `friction`, ...).
    A read returns a `(num_envs, ...)` array of the batch's namespace: `bind(site).xpos` is
    (num_envs, 3) and `bind(joints).qpos` (num_envs, n_joints). `set(name, values,
    env_ids)` writes the worlds `env_ids` (all when None) on the device; attribute
    assignment writes every world. In NumPy, item assignment on a read writes through to the
    worlds of its first index (`bind(joints).qpos[env_ids] = values`). Read again after
    stepping: a read is a snapshot.
    """

    def __init__(self, physics: "BatchPhysics", elements):
        host_binding = physics.host.bind(elements)
        single = hasattr(elements, "tag")
        first = elements if single else next(iter(elements), None)
        if first is None:
            raise ValueError("bind: expected an MJCF element or a non-empty list, got []")
        namespace = mjcf_binding.element_namespace(first)
        self.__dict__.update(
            _physics=physics,
            _family=field_layout.FAMILIES[namespace],
            _ids=host_binding.element_id,
            _single=single,
            _label=mjcf_binding.describe(first) if single else f"[{len(elements)} {namespace}]",
            _indices={},
        )

    @property
    def element_id(self):
        """The MuJoCo id of the element (an int) or of each element (an int array)."""
        return self._ids

    def selection(self, name: str) -> tuple[FieldView, Any]:
        """(the field, the index of this binding's rows in one world) for attribute `name`.

        Raises:
          AttributeError: for an attribute the elements' family does not have.
        """
        cached = self._indices.get(name)
        if cached is not None:
            return cached
        ref = self._family.fields.get(name)
        if ref is None:
            raise AttributeError(
                f"{self._label} has no batched attribute {name!r}; expected one of "
                f"{sorted(self._family.fields)}"
            )
        layout = self._physics.layout
        if self._single:
            index = layout.single_index(ref.addressing, int(self._ids))
        else:
            index = field_layout.compress(layout.multi_index(ref.addressing, self._ids))
        field = self._physics.field(ref.struct, ref.name)
        if isinstance(index, np.ndarray) and self._physics.arrays.library != "numpy":
            index = self._physics.arrays.asarray(index)
        self._indices[name] = (field, index)
        return field, index

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return _bound(*self.selection(name))

    def set(self, name: str, values, env_ids=None) -> None:
        """Writes `values` into attribute `name` of worlds `env_ids` (every world if None).

        Args:
          name: an attribute, as for reads.
          values: broadcastable to (len(env_ids), *one world's shape).
          env_ids: an int array of the namespace (or NumPy) or None.

        Raises:
          ValueError: for a model field shared by every world.
        """
        field, index = self.selection(name)
        if env_ids is not None and _is_host(env_ids):
            env_ids = self._physics.arrays.asarray(np.asarray(env_ids, dtype=np.int64))
        field.write(env_ids, index, values)

    def __setattr__(self, name: str, value) -> None:
        self.set(name, value)

    def __repr__(self) -> str:
        return f"BatchBinding({self._label}, num_envs={self._physics.num_envs})"


class _NamedField:
    """`physics.named.data.qpos['arm/joint_1']`: rows of one field by object name."""

    def __init__(self, physics: "BatchPhysics", struct: str, name: str):
        owner = field_layout.ROW_OWNERS.get((struct, name))
        if owner is None:
            raise AttributeError(f"{struct} field {name!r} has no rows addressed by object names")
        self._family, self._rule = owner
        self._physics = physics
        self._field = physics.field(struct, name)

    def _index(self, key):
        layout = self._physics.layout
        names = [key] if isinstance(key, str) else list(key)
        ids = []
        for name in names:
            object_id = layout.object_id(self._family, name)
            if object_id < 0:
                raise KeyError(
                    f"named: no {self._family.namespace} named {name!r} in the compiled model"
                )
            ids.append(object_id)
        if isinstance(key, str):
            return layout.single_index(self._rule, ids[0])
        return field_layout.compress(layout.multi_index(self._rule, ids))

    def __getitem__(self, key) -> Any:
        return _bound(self._field, self._index(key))

    def __setitem__(self, key, value) -> None:
        self._field.write(None, self._index(key), value)


class _NamedStruct:
    def __init__(self, physics: "BatchPhysics", struct: str):
        self._physics = physics
        self._struct = struct

    def __getattr__(self, name: str) -> _NamedField:
        if name.startswith("__"):
            raise AttributeError(name)
        return _NamedField(self._physics, self._struct, name)


class NamedViews:
    """`physics.named.model` and `physics.named.data`, indexed by object name."""

    def __init__(self, physics: "BatchPhysics"):
        self.model = _NamedStruct(physics, field_layout.MODEL)
        self.data = _NamedStruct(physics, field_layout.DATA)


class StructViews:
    """`physics.data.<field>` / `physics.model.<field>` of all worlds (see the module doc)."""

    def __init__(self, physics: "BatchPhysics", struct: str):
        self._physics = physics
        self._struct = struct

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return self._physics.field(self._struct, name).read()


class BatchFields:
    """What every batch physics gives alike: `field`, `bind`, and the `data`, `model` and
    `named` views, all over the subclass's `field_storage(struct, name)`.

    A subclass sets `mj_model`, `host` and `num_envs` and calls `_make_views()`.
    """

    def _make_views(self) -> None:
        self._fields: dict[tuple[str, str], FieldView] = {}
        self.data = StructViews(self, field_layout.DATA)
        self.model = StructViews(self, field_layout.MODEL)
        self.named = NamedViews(self)

    def field(self, struct: str, name: str) -> FieldView:
        """The `FieldView` for MjModel (`struct='model'`) or MjData field `name`.

        Raises:
          AttributeError: for a name that is not an MjModel/MjData array field.
        """
        key = (struct, name)
        field = self._fields.get(key)
        if field is None:
            host = self.mj_model if struct == field_layout.MODEL else self.host.data.ptr
            value = getattr(host, name, None)
            # A per-world scalar such as data.time is a (num_envs,) array.
            scalar = struct == field_layout.DATA and isinstance(value, float)
            if not (isinstance(value, np.ndarray) or scalar):
                raise AttributeError(f"MuJoCo has no array {struct} field {name!r}")
            field = self._fields[key] = FieldView(self, struct, name)
        return field

    def bind(self, elements) -> BatchBinding:
        """The batched fields of an MJCF element or a list of them (see `BatchBinding`).

        Returns:
          A `BatchBinding` whose reads have a leading `num_envs` axis.

        Raises:
          ValueError: for elements that are not part of the compiled model, as
            `mjcf.Physics.bind` raises.
        """
        return BatchBinding(self, elements)
