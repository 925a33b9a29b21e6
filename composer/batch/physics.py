"""BatchPhysics: `num_envs` worlds of one compiled model on a MuJoCo Warp device.

The model is compiled once by `mjcf` (a host `mjcf.Physics`, which also resolves MJCF elements
to MuJoCo ids) and put on the device with `mujoco_warp.put_model` / `put_data(nworld=...)`.
Every field reads as an array of the batch's namespace `xp` (see `composer.batch.arrays`)
with a leading `num_envs` axis and the trailing shape of the MjModel/MjData field of the
same name (`data.xmat` is (num_envs, nbody, 9), as in C MuJoCo), in float32.

Where values live (the one rule for reads and writes): the device is the source of truth.
A field is a view of MuJoCo Warp's own array, made once, so reads cost no copy and writes
land in the worlds: `bind(joints).qpos[env_ids] = ...` (NumPy) or `bind(joints).set('qpos',
values, env_ids)` (any namespace) touch only the worlds selected. Model fields are shared by
all worlds unless named in `batched_model_fields`, which gives each world its own row
(MuJoCo Warp's batched model fields); writing a shared field raises. Derived quantities are
not recomputed after a write: `forward(mask)` does that for the worlds of a mask, without
touching the others.
"""

import dataclasses
from collections.abc import Callable, Sequence
from typing import Any

import mujoco
import numpy as np

import mjcf
from composer.batch import _warp, kernels
from composer.batch.arrays import ArrayBridge, array_library
from mjcf import binding as mjcf_binding
from mujoco_physics import field_layout

__all__ = ["BatchBinding", "BatchPhysics", "ContactWatch"]

_ACC_STAGE = int(mujoco.mjtStage.mjSTAGE_ACC)
_STATE_SPEC = int(mujoco.mjtState.mjSTATE_INTEGRATION)


def _spec_shape(field_type) -> tuple:
    return tuple(getattr(field_type, "shape", ()) or ())


class _Field:
    """One MjModel/MjData field of every world, as a view in the batch's namespace.

    Attributes:
      view: the field's device memory, shape (num_envs, *C shape) for a per-world field,
        (1, *C shape) for a model field shared by every world.
      per_world: whether each world has its own row.
    """

    def __init__(self, physics: "BatchPhysics", struct: str, name: str):
        self.struct = struct
        self.name = name
        self._physics = physics
        host = physics.mj_model if struct == field_layout.MODEL else physics.host.data.ptr
        self.c_shape = np.shape(getattr(host, name))
        self.per_world = struct == field_layout.DATA or name in physics.batched_model_fields
        owner = physics.warp_model if struct == field_layout.MODEL else physics.warp_data
        try:
            self.device_array = getattr(owner, name)
        except AttributeError:
            raise AttributeError(
                f"MuJoCo Warp has no {struct} field {name!r} (MuJoCo has it; Warp does not "
                "simulate it)"
            ) from None
        rows = physics.num_envs if self.per_world else 1
        self.view = physics.arrays.view(self.device_array, (rows, *self.c_shape))

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


def _bound(field: _Field, index) -> Any:
    """Rows `index` of `field` in every world; in NumPy an array that writes through."""
    values = field.read()[:, index]
    if field._physics.arrays.library != "numpy":
        return values
    array = np.array(values).view(_BatchArray)
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

    def _field_and_index(self, name: str) -> tuple[_Field, Any]:
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
        return _bound(*self._field_and_index(name))

    def set(self, name: str, values, env_ids=None) -> None:
        """Writes `values` into attribute `name` of worlds `env_ids` (every world if None).

        Args:
          name: an attribute, as for reads.
          values: broadcastable to (len(env_ids), *one world's shape).
          env_ids: an int array of the namespace (or NumPy) or None.

        Raises:
          ValueError: for a model field shared by every world.
        """
        field, index = self._field_and_index(name)
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

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return self._physics.field(self._struct, name).read()


class ContactWatch:
    """Which worlds have a contact between two sets of geoms, computed on the device.

    Made by `BatchPhysics.contact_watch`; calling it returns a bool (num_envs,) array of the
    batch's namespace, from the contacts of the last collision pass (the contacts C MuJoCo
    lists in `data.contact`).
    """

    def __init__(self, physics: "BatchPhysics", codes: np.ndarray):
        wp = physics._wp
        self._physics = physics
        self._codes = wp.array(codes.astype(np.int32), dtype=wp.int32, device=physics.device)
        self._out, self._view = physics.arrays.empty((physics.num_envs,), bool)

    def __call__(self) -> Any:
        physics = self._physics
        contact = physics.warp_data.contact
        self._out.zero_()
        physics._wp.launch(
            kernels.kernels().contact_worlds,
            dim=contact.worldid.shape[0],
            inputs=[physics.warp_data.nacon, contact.geom, contact.worldid, self._codes],
            outputs=[self._out],
            device=physics.device,
        )
        return self._view


class BatchPhysics:
    """`num_envs` worlds of the model compiled into `host`, on a Warp device.

    Args:
      host: the `mjcf.Physics` the model was compiled into; its model is put on the device and
        its data is every world's initial state. It also resolves MJCF elements for `bind`.
      num_envs: the number of worlds, >= 1.
      arrays: the `ArrayBridge` (device and namespace) of the batch.
      batched_model_fields: MjModel field names that get one row per world (per-world
        friction, masses, colours, gains, site positions).
      nconmax, njmax: contact and constraint capacity per world, passed to `put_data`
        (None: MuJoCo Warp's defaults).

    Attributes:
      xp: the array namespace of every read (NumPy on Warp's CPU device, torch on CUDA).

    Raises:
      ValueError: for a field in `batched_model_fields` that MuJoCo Warp does not batch.
    """

    def __init__(
        self,
        host: mjcf.Physics,
        num_envs: int,
        *,
        arrays: ArrayBridge,
        batched_model_fields: Sequence[str] = (),
        nconmax: int | None = None,
        njmax: int | None = None,
    ):
        warp, mjw = _warp.load()
        self._wp = warp
        self._mjw = mjw
        self.host = host
        self.num_envs = int(num_envs)
        self.arrays = arrays
        self.xp = arrays.xp
        self.mj_model: mujoco.MjModel = host.model.ptr
        self.layout = field_layout.ModelLayout(self.mj_model)
        self.batched_model_fields = frozenset(batched_model_fields)
        self.device = arrays.device
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
            # Forward for some worlds runs in this copy, whose chosen worlds are copied back.
            self._scratch = mjw.put_data(
                self.mj_model, host.data.ptr, nworld=self.num_envs, nconmax=nconmax, njmax=njmax
            )
            self.state_size = mujoco.mj_stateSize(self.mj_model, _STATE_SPEC)
            self._states = warp.zeros((self.num_envs, self.state_size), dtype=warp.float32)
        self._fields: dict[tuple[str, str], _Field] = {}
        self._world_arrays = list(
            zip(_per_world_arrays(warp, self._scratch), _per_world_arrays(warp, self.warp_data))
        )
        self._acc_sensors = self._acc_sensor_mask()
        self._saved_sensordata = None
        self._graphs: dict[Any, Any] = {}
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
            value = getattr(host, name, None)
            # A per-world scalar such as data.time is a (num_envs,) array.
            scalar = struct == field_layout.DATA and isinstance(value, float)
            if not (isinstance(value, np.ndarray) or scalar):
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

    def contact_watch(self, first_geoms: np.ndarray, second_geoms: np.ndarray) -> ContactWatch:
        """A `ContactWatch` for contacts between a geom of `first_geoms` and one of
        `second_geoms` (two bool masks over the compiled geoms)."""
        codes = np.asarray(first_geoms, dtype=np.int32) | (
            2 * np.asarray(second_geoms, dtype=np.int32)
        )
        return ContactWatch(self, codes)

    # Simulation.

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
        self.run_captured(("step", n_sub_steps), lambda: self._control_step(n_sub_steps))

    def run_captured(self, key, work: Callable[[], None]) -> None:
        """Runs `work` (device work only, on persistent arrays): on CUDA as a graph
        captured at the first call under `key`, elsewhere directly.

        The first call runs `work` once (compiling its kernels) and then records it
        without running it; later calls launch the recording.
        """
        if not self.is_cuda:
            work()
            return
        wp = self._wp
        graph = self._graphs.get(key)
        if graph is not None:
            wp.capture_launch(graph)
            return
        with wp.ScopedDevice(self.device):
            work()
            with wp.ScopedCapture() as capture:
                work()
        self._graphs[key] = capture.graph

    def forward(self, mask=None, *, actuation: bool = True) -> None:
        """Recomputes derived quantities of the worlds of `mask`, as `mj_forward`.

        Other worlds are left exactly as they were: the chosen worlds' states are copied
        into a second MuJoCo Warp data, forward runs there, and only the chosen worlds are
        copied back (one kernel per per-world array, on the device).

        Args:
          mask: a bool (num_envs,) array (of the namespace, NumPy or Warp), or None for
            every world.
          actuation: False runs forward with actuation disabled, as after a reset in
            `mjcf.Physics.reset_context`.
        """
        wp, mjw = self._wp, self._mjw
        model = self.warp_model
        option = model.opt
        flags = option.disableflags
        if not actuation:
            option.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
        try:
            with wp.ScopedDevice(self.device):
                if mask is None:
                    mjw.forward(model, self.warp_data)
                    return
                active = self.warp_mask(mask)
                mjw.get_state(model, self.warp_data, self._states, _STATE_SPEC)
                mjw.set_state(model, self._scratch, self._states, _STATE_SPEC, active)
                mjw.forward(model, self._scratch)
                for source, target in self._world_arrays:
                    _copy_worlds(active, source, target)
        finally:
            option.disableflags = flags

    def reset(self, mask) -> None:
        """Resets the worlds of `mask` to the model's initial state (`mj_resetData`: qpos0,
        zero velocities, time 0), on the device; derived quantities wait for `forward`."""
        with self._wp.ScopedDevice(self.device):
            self._mjw.reset_data(self.warp_model, self.warp_data, reset=self.warp_mask(mask))

    def warp_mask(self, mask):
        """A bool (num_envs,) mask (of the namespace, NumPy, or Warp) as a Warp array."""
        wp = self._wp
        if isinstance(mask, wp.array):
            return mask
        if array_library(mask) == "torch":
            return self.arrays.to_warp(mask, dtype=wp.bool)
        mask = np.ascontiguousarray(mask, dtype=bool)
        return wp.array(mask, dtype=wp.bool, device=self.device, copy=self.is_cuda)


def _per_world_arrays(wp, data) -> list:
    """Every Warp array of `data` with one row per world, from MuJoCo Warp's own specs."""
    arrays = []

    def collect(struct):
        for f in dataclasses.fields(struct):
            value = getattr(struct, f.name, None)
            if dataclasses.is_dataclass(value):
                collect(value)
            elif isinstance(value, wp.array) and _spec_shape(f.type)[:1] == ("nworld",):
                if value.size and value.is_contiguous:
                    arrays.append(value)

    collect(data)
    return arrays


def _copy_worlds(keep, source, target) -> None:
    """Copies the worlds where `keep` is true from `source` to `target` (same shapes)."""
    wp = _warp.load()[0]
    source_bytes = kernels.rows(source, wp.uint8, source.shape[0])
    target_bytes = kernels.rows(target, wp.uint8, target.shape[0])
    wp.launch(
        kernels.kernels().copy_worlds,
        dim=source_bytes.shape,
        inputs=[keep, source_bytes, target_bytes],
        device=target.device,
    )
