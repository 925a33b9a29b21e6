"""BatchPhysics: `num_envs` worlds of one compiled model on a MuJoCo Warp device.

The model is compiled once by `mjcf` (a host `mjcf.Physics`, which also resolves MJCF elements
to MuJoCo ids) and put on the device with `mujoco_warp.put_model` / `put_data(nworld=...)`.
Every field reads as a NumPy array with a leading `num_envs` axis and the trailing shape of the
MjModel/MjData field of the same name (`data.xmat` is (num_envs, nbody, 9), as in C MuJoCo).

Where values live (the one rule for reads and writes): on Warp's CPU device a field is a
NumPy view of the Warp array, so reads cost nothing and writes go straight to the worlds; on
a CUDA device a read is a host copy and a write copies the field back. Writes through
`bind`/`named` arrays touch only the worlds selected by the first index
(`bind(joints).qpos[env_ids] = ...`). Model fields are shared by all worlds unless named in
`batched_model_fields`, which gives each world its own row (MuJoCo Warp's batched model
fields); writing a shared field for some worlds only raises. Derived quantities are not
recomputed after a write: `forward(env_ids)` does that, and the environment calls it after
every reset.
"""

import dataclasses
from collections.abc import Sequence
from typing import Any, NamedTuple

import mujoco
import numpy as np

import mjcf
from composer.batch import _warp, kernels
from mjcf import binding as mjcf_binding
from mujoco_physics import field_layout

__all__ = ["BatchBinding", "BatchPhysics", "Contacts"]

_ACC_STAGE = int(mujoco.mjtStage.mjSTAGE_ACC)


def _spec_shape(field_type) -> tuple:
    return tuple(getattr(field_type, "shape", ()) or ())


class _Field:
    """One MjModel/MjData field of every world, as NumPy arrays of shape (num_envs, *C shape)."""

    def __init__(self, physics: "BatchPhysics", struct: str, name: str):
        self.struct = struct
        self.name = name
        self._physics = physics
        host = physics.mj_model if struct == field_layout.MODEL else physics.host.data.ptr
        self.c_shape = np.shape(getattr(host, name))
        self.per_world = struct == field_layout.DATA or name in physics.batched_model_fields

    def _device_array(self):
        owner = (
            self._physics.warp_model
            if self.struct == field_layout.MODEL
            else self._physics.warp_data
        )
        try:
            return getattr(owner, self.name)
        except AttributeError:
            raise AttributeError(
                f"MuJoCo Warp has no {self.struct} field {self.name!r} (MuJoCo has it; Warp "
                "does not simulate it)"
            ) from None

    def read(self) -> np.ndarray:
        """The field of all worlds: a view on the CPU device, a host copy on CUDA."""
        array = self._device_array()
        host = array.numpy()
        num_envs = self._physics.num_envs
        if self.per_world:
            return host.reshape((num_envs,) + self.c_shape)
        # A shared field: one row (or no world axis at all) for every world.
        return np.broadcast_to(host.reshape(self.c_shape), (num_envs,) + self.c_shape)

    def device_rows(self):
        """The field's device memory as a float32 (worlds, entries of one world) Warp array.

        Returns:
          The alias (one row for a model field shared by every world), or None for a field
          that is not float32 or not contiguous on the device.
        """
        array = self._device_array()
        wp = self._physics._wp
        scalar = getattr(array.dtype, "_wp_scalar_type_", array.dtype)
        if scalar is not wp.float32 or not array.is_contiguous:
            return None
        per_world = int(np.prod(self.c_shape))
        return kernels.rows(array, wp.float32, array.capacity // 4 // per_world)

    def write(self, worlds: np.ndarray, index, values: np.ndarray) -> None:
        """Writes `values` (shape (len(worlds), *selected)) into rows `index` of `worlds`."""
        num_envs = self._physics.num_envs
        if not self.per_world:
            raise ValueError(
                f"model field {self.name!r} is shared by all {num_envs} worlds; pass "
                f"batched_model_fields=({self.name!r},) to give each world its own"
            )
        target = self.read()
        if isinstance(index, np.ndarray):
            target[worlds[:, None], index] = values
        else:
            target[worlds, index] = values
        if self._physics.is_cuda:
            array = self._device_array()
            array.assign(target.reshape(array.numpy().shape))

    def write_shared(self, value: np.ndarray) -> None:
        """Writes `value` (the C field's shape) for every world; fields Warp lacks are skipped."""
        try:
            array = self._device_array()
        except AttributeError:
            return
        host = array.numpy()
        array.assign(np.asarray(value).astype(host.dtype).reshape(host.shape))


class _BatchArray(np.ndarray):
    """A bound field of every world; item assignment writes through to the selected worlds."""

    _field: _Field | None = None
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


def _bound(field: _Field, index) -> _BatchArray:
    values = field.read()[:, index]
    array = np.array(values).view(_BatchArray)
    array._field = field
    array._index = index
    return array


class BatchBinding:
    """The fields of one MJCF element, or of a list of same-kind elements, in every world.

    Attribute names are those of `mjcf.Physics.bind` (`xpos`, `qpos`, `pos`, `friction`, ...).
    A read returns a `(num_envs, ...)` array: `bind(site).xpos` is (num_envs, 3) and
    `bind(joints).qpos` (num_envs, n_joints). Item assignment writes only the worlds of the
    first index (`bind(joints).qpos[env_ids] = values`); attribute assignment writes every
    world. Reads are snapshots: read again after stepping.
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
        )

    @property
    def element_id(self):
        """The MuJoCo id of the element (an int) or of each element (an int array)."""
        return self._ids

    def _field_and_index(self, name: str) -> tuple[_Field, Any]:
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
        return self._physics.field(ref.struct, ref.name), index

    def __getattr__(self, name: str) -> np.ndarray:
        if name.startswith("__"):
            raise AttributeError(name)
        return _bound(*self._field_and_index(name))

    def __setattr__(self, name: str, value) -> None:
        field, index = self._field_and_index(name)
        current = field.read()[:, index]
        values = np.broadcast_to(np.asarray(value), current.shape)
        field.write(np.arange(self._physics.num_envs), index, values)

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

    def __getitem__(self, key) -> np.ndarray:
        return _bound(self._field, self._index(key))

    def __setitem__(self, key, value) -> None:
        index = self._index(key)
        current = self._field.read()[:, index]
        values = np.broadcast_to(np.asarray(value), current.shape)
        self._field.write(np.arange(self._physics.num_envs), index, values)


class _NamedStruct:
    def __init__(self, physics: "BatchPhysics", struct: str):
        self._physics = physics
        self._struct = struct

    def __getattr__(self, name: str) -> _NamedField:
        if name.startswith("__"):
            raise AttributeError(name)
        return _NamedField(self._physics, self._struct, name)


class _Named:
    """`physics.named.model` and `physics.named.data`, indexed by object name."""

    def __init__(self, physics: "BatchPhysics"):
        self.model = _NamedStruct(physics, field_layout.MODEL)
        self.data = _NamedStruct(physics, field_layout.DATA)


class _Struct:
    """`physics.data.<field>` / `physics.model.<field>` of all worlds (see the module doc)."""

    def __init__(self, physics: "BatchPhysics", struct: str):
        self._physics = physics
        self._struct = struct

    def __getattr__(self, name: str) -> np.ndarray:
        if name.startswith("__"):
            raise AttributeError(name)
        return self._physics.field(self._struct, name).read()


class Contacts(NamedTuple):
    """The active contacts of all worlds, in one list.

    Attributes:
      geom: int (ncon, 2), the two geoms of each contact.
      worldid: int (ncon,), the world of each contact.
    """

    geom: np.ndarray
    worldid: np.ndarray


class BatchPhysics:
    """`num_envs` worlds of the model compiled into `host`, on a Warp device.

    Args:
      host: the `mjcf.Physics` the model was compiled into; its model is put on the device and
        its data is every world's initial state. It also resolves MJCF elements for `bind`.
      num_envs: the number of worlds, >= 1.
      device: a Warp device name, "cpu" or "cuda:0".
      batched_model_fields: MjModel field names that get one row per world (per-world
        friction, masses, colours, gains, site positions).
      nconmax, njmax: contact and constraint capacity per world, passed to `put_data`
        (None: MuJoCo Warp's defaults).

    Raises:
      ValueError: for a bad `num_envs`, or a field in `batched_model_fields` that MuJoCo Warp
        does not batch.
    """

    def __init__(
        self,
        host: mjcf.Physics,
        num_envs: int,
        *,
        device: str = "cpu",
        batched_model_fields: Sequence[str] = (),
        nconmax: int | None = None,
        njmax: int | None = None,
    ):
        warp, mjw = _warp.load()
        self._wp = warp
        self._mjw = mjw
        self.host = host
        self.num_envs = int(num_envs)
        self.mj_model: mujoco.MjModel = host.model.ptr
        self.layout = field_layout.ModelLayout(self.mj_model)
        self.batched_model_fields = frozenset(batched_model_fields)
        self.device = warp.get_device(device)
        self.is_cuda = self.device.is_cuda
        batchable = {
            f.name for f in dataclasses.fields(mjw.Model) if _spec_shape(f.type)[:1] == ("*",)
        }
        unknown = sorted(self.batched_model_fields - batchable)
        if unknown:
            raise ValueError(
                f"batched_model_fields: {unknown} are not batched model fields of MuJoCo Warp; "
                f"expected names among {len(batchable)} such as 'geom_friction', 'body_mass'"
            )
        with warp.ScopedDevice(self.device):
            self.warp_model = mjw.put_model(
                self.mj_model, batch_sizes={name: self.num_envs for name in batched_model_fields}
            )
            self.warp_data = mjw.put_data(
                self.mj_model, host.data.ptr, nworld=self.num_envs, nconmax=nconmax, njmax=njmax
            )
        self._fields: dict[tuple[str, str], _Field] = {}
        self._world_arrays = self._per_world_arrays()
        self._acc_sensors = self._acc_sensor_mask()
        self._saved_sensordata = None
        self._graphs: dict[int, Any] = {}
        self.data = _Struct(self, field_layout.DATA)
        self.model = _Struct(self, field_layout.MODEL)
        self.named = _Named(self)

    # Fields.

    def field(self, struct: str, name: str) -> _Field:
        """The `_Field` for MjModel (`struct='model'`) or MjData field `name`."""
        key = (struct, name)
        field = self._fields.get(key)
        if field is None:
            host = self.mj_model if struct == field_layout.MODEL else self.host.data.ptr
            if not isinstance(getattr(host, name, None), np.ndarray):
                raise AttributeError(f"MuJoCo has no array {struct} field {name!r}")
            field = self._fields[key] = _Field(self, struct, name)
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

    def contacts(self) -> Contacts:
        """The contacts found by the last collision pass of every world."""
        contact = self.warp_data.contact
        count = int(self.warp_data.nacon.numpy()[0])
        return Contacts(contact.geom.numpy()[:count], contact.worldid.numpy()[:count])

    # Simulation.

    def _per_world_arrays(self) -> list:
        """Every Warp array of the data with one row per world, from MuJoCo Warp's own specs."""
        arrays = []

        def collect(struct):
            for f in dataclasses.fields(struct):
                value = getattr(struct, f.name, None)
                if dataclasses.is_dataclass(value):
                    collect(value)
                elif isinstance(value, self._wp.array) and _spec_shape(f.type)[:1] == ("nworld",):
                    if value.size and value.is_contiguous:
                        arrays.append(value)

        collect(self.warp_data)
        return arrays

    def _acc_sensor_mask(self):
        model = self.mj_model
        mask = np.zeros(model.nsensordata, dtype=bool)
        for i in range(model.nsensor):
            if model.sensor_needstage[i] == _ACC_STAGE:
                adr = model.sensor_adr[i]
                mask[adr : adr + model.sensor_dim[i]] = True
        if not mask.any():
            return None
        return self._wp.array(np.nonzero(mask)[0].astype(np.int32), device=self.device)

    def _control_step(self, n_sub_steps: int) -> None:
        """C MuJoCo's legacy step chain (`mjcf.Physics.step`): step2, n-1 steps, step1.

        MuJoCo Warp's step1 clears all sensor data, C's keeps the acceleration-stage sensors
        of the last step2; they are put back so that observations match.
        """
        mjw, wp = self._mjw, self._wp
        model, data = self.warp_model, self.warp_data
        mjw.step2(model, data)
        for _ in range(n_sub_steps - 1):
            mjw.step(model, data)
        if self._acc_sensors is not None:
            wp.copy(self._saved_sensordata, data.sensordata)
        mjw.step1(model, data)
        if self._acc_sensors is not None:
            wp.launch(
                kernels.kernels().restore_columns,
                dim=(self.num_envs, self._acc_sensors.shape[0]),
                inputs=[self._acc_sensors, self._saved_sensordata, data.sensordata],
                device=self.device,
            )

    def step(self, n_sub_steps: int = 1) -> None:
        """Advances every world by `n_sub_steps` physics steps (a CUDA graph on GPU)."""
        wp = self._wp
        if self._acc_sensors is not None and self._saved_sensordata is None:
            self._saved_sensordata = wp.zeros_like(self.warp_data.sensordata)
        if not self.is_cuda:
            self._control_step(n_sub_steps)
            return
        graph = self._graphs.get(n_sub_steps)
        if graph is None:
            with wp.ScopedDevice(self.device):
                self._control_step(n_sub_steps)  # compiles the kernels outside the capture
                with wp.ScopedCapture() as capture:
                    self._control_step(n_sub_steps)
            graph = self._graphs[n_sub_steps] = capture.graph
        wp.capture_launch(graph)

    def forward(self, env_ids: np.ndarray | None = None, *, actuation: bool = True) -> None:
        """Recomputes derived quantities of worlds `env_ids` (all when None), as `mj_forward`.

        Other worlds are left exactly as they were: MuJoCo Warp computes every world, so their
        per-world arrays are saved before and put back after.

        Args:
          env_ids: world indices, or None for all worlds.
          actuation: False runs forward with actuation disabled, as after a reset in
            `mjcf.Physics.reset_context`.
        """
        wp, mjw = self._wp, self._mjw
        keep = None
        if env_ids is not None:
            mask = np.zeros(self.num_envs, dtype=bool)
            mask[np.asarray(env_ids, dtype=np.intp)] = True
            if not mask.all():
                keep = wp.array(~mask, dtype=wp.bool, device=self.device)
        saved = [wp.clone(array) for array in self._world_arrays] if keep is not None else ()
        option = self.warp_model.opt
        flags = option.disableflags
        if not actuation:
            option.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
        try:
            with wp.ScopedDevice(self.device):
                mjw.forward(self.warp_model, self.warp_data)
        finally:
            option.disableflags = flags
        for source, target in zip(saved, self._world_arrays):
            _copy_worlds(keep, source, target)

    def set_state(self, env_ids: np.ndarray, states: np.ndarray, spec: int) -> None:
        """Writes `mj_getState` vectors `states` (one row per id) into worlds `env_ids`."""
        wp = self._wp
        full = np.zeros((self.num_envs, states.shape[1]), dtype=np.float32)
        full[env_ids] = states
        mask = np.zeros(self.num_envs, dtype=bool)
        mask[env_ids] = True
        with wp.ScopedDevice(self.device):
            self._mjw.set_state(
                self.warp_model,
                self.warp_data,
                wp.array(full, dtype=wp.float32),
                int(spec),
                wp.array(mask, dtype=wp.bool),
            )


def _copy_worlds(keep, source, target) -> None:
    wp = _warp.load()[0]
    source_bytes = kernels.rows(source, wp.uint8, source.shape[0])
    target_bytes = kernels.rows(target, wp.uint8, target.shape[0])
    wp.launch(
        kernels.kernels().copy_worlds,
        dim=source_bytes.shape,
        inputs=[keep, source_bytes, target_bytes],
        device=target.device,
    )
