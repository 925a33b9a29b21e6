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
from composer.batch.arrays import ArrayBridge, array_library, row_items
from composer.batch.bindings import BatchFields, FieldStorage
from mujoco_physics import field_layout

__all__ = ["BatchPhysics", "ContactWatch", "device_model_fields"]

_ACC_STAGE = int(mujoco.mjtStage.mjSTAGE_ACC)
_STATE_SPEC = int(mujoco.mjtState.mjSTATE_INTEGRATION)


def _spec_shape(field_type) -> tuple:
    return tuple(getattr(field_type, "shape", ()) or ())


def device_model_fields() -> dict[str, bool]:
    """MuJoCo Warp's model fields, each with whether it can hold one row per world.

    Returns:
      Field name (as in `mujoco.MjModel`) -> True for a field `put_model` can batch.
    """
    mjw = _warp.load().mujoco_warp
    return {f.name: _spec_shape(f.type)[:1] == ("*",) for f in dataclasses.fields(mjw.Model)}


class ContactWatch:
    """Which worlds have a contact between two sets of geoms, computed on the device.

    Made by `BatchPhysics.contact_watch`; calling it returns a bool (num_envs,) array of the
    batch's namespace, from the contacts of the last collision pass (the contacts C MuJoCo
    lists in `data.contact`). The array is the watch's own, rewritten by every call.

    Attributes:
      worlds: that array as a Warp array, for a task's own kernels.
    """

    def __init__(self, physics: "BatchPhysics", codes: np.ndarray):
        wp = physics._wp
        self._codes = wp.array(codes.astype(np.int32), dtype=wp.int32, device=physics.device)
        self.worlds, self._view = physics.arrays.empty((physics.num_envs,), bool)
        contact = physics.warp_data.contact
        # One thread per contact slot on CUDA; on the CPU device one thread reads them all.
        threads = contact.worldid.shape[0] if physics.is_cuda else 1
        self._launch = wp.launch(
            kernels.kernels().contact_worlds,
            dim=threads,
            inputs=[physics.warp_data.nacon, contact.geom, contact.worldid, self._codes, threads],
            outputs=[self.worlds],
            device=physics.device,
            record_cmd=True,
        )

    def __call__(self) -> Any:
        self.worlds.zero_()
        self._launch.launch()
        return self._view


class BatchPhysics(BatchFields):
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
      float_dtype: float32, the dtype of MuJoCo Warp's float fields.
      state_size: the length of one world's state in `set_state` (`mjSTATE_INTEGRATION`).
      last_divergences: always empty: MuJoCo Warp does not report the worlds whose state
        became invalid (the CPU batch does, `MujocoBatchPhysics.last_divergences`).

    Raises:
      ValueError: for a field in `batched_model_fields` that MuJoCo Warp does not batch.
    """

    float_dtype = np.dtype(np.float32)
    on_warp = True
    last_divergences = ()

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
        modules = _warp.load()
        warp, mjw = modules.warp, modules.mujoco_warp
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
        batchable = {name for name, per_world in device_model_fields().items() if per_world}
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
        # forward(mask) copies the chosen worlds back: on CUDA with these launches, recorded
        # once (and so capturable); on Warp's CPU device, where the arrays are host memory,
        # with NumPy, each world's row one item: reach's 119 arrays (18 kB a world) copy in
        # 3 µs a world when every world starts, 4-10 µs a world otherwise, against 11.5 µs
        # a world for Warp CPU kernels' word-by-word loops (development machine, 2026-11).
        self._forward_mask = warp.zeros(self.num_envs, dtype=warp.bool, device=self.device)
        pairs = list(
            zip(_per_world_arrays(warp, self._scratch), _per_world_arrays(warp, self.warp_data))
        )
        self._copy_back = [
            _copy_worlds_launch(self._forward_mask, source, target)
            for source, target in (pairs if self.is_cuda else [])
        ]
        self._copy_back_rows = [
            (_rows_view(source, self.num_envs), _rows_view(target, self.num_envs))
            for source, target in ([] if self.is_cuda else pairs)
        ]
        self._forward_mask_host = None if self.is_cuda else self._forward_mask.numpy()
        self._acc_sensors = self._acc_sensor_mask()
        self._static_geoms = self._moving_static_geoms()
        self._saved_sensordata = None
        self._graphs: dict[Any, Any] = {}
        self._make_views()

    # Fields.

    def field_storage(self, struct: str, name: str) -> FieldStorage:
        """The `FieldStorage` of field `name`: a view of MuJoCo Warp's own array.

        Raises:
          AttributeError: for a field MuJoCo has but MuJoCo Warp does not simulate.
        """
        host = self.mj_model if struct == field_layout.MODEL else self.host.data.ptr
        per_world = struct == field_layout.DATA or name in self.batched_model_fields
        owner = self.warp_model if struct == field_layout.MODEL else self.warp_data
        try:
            device_array = getattr(owner, name)
        except AttributeError:
            raise AttributeError(
                f"MuJoCo Warp has no {struct} field {name!r} (MuJoCo has it; Warp does not "
                "simulate it)"
            ) from None
        rows = self.num_envs if per_world else 1
        view = self.arrays.view(device_array, (rows, *np.shape(getattr(host, name))))
        scalar = getattr(device_array.dtype, "_wp_scalar_type_", device_array.dtype)
        return FieldStorage(view, per_world, scalar is self._wp.float32, device_array)

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

    def _moving_static_geoms(self):
        """The geoms of bodies welded to the world whose pose a world's model row may set
        (a batched body_pos, body_quat, geom_pos or geom_quat), as a Warp int array, or None.

        MuJoCo Warp computes such geoms' world poses once, when the data is made, and never
        again; `forward` recomputes them for the worlds it runs.
        """
        model = self.mj_model
        if not self.batched_model_fields & {"body_pos", "body_quat", "geom_pos", "geom_quat"}:
            return None
        bodies = model.geom_bodyid
        static = (model.body_weldid[bodies] == 0) & (
            model.body_mocapid[model.body_rootid[bodies]] == -1
        )
        if not static.any():
            return None
        return self._wp.array(np.flatnonzero(static).astype(np.int32), device=self.device)

    def _place_static_geoms(self, data) -> None:
        """Runs kinematics on `data` and recomputes its static geoms' world poses."""
        wp, model = self._wp, self.warp_model
        self._mjw.kinematics(model, data)
        wp.launch(
            kernels.kernels().static_geom_poses,
            dim=(self.num_envs, self._static_geoms.shape[0]),
            inputs=[
                self._static_geoms,
                model.geom_bodyid,
                model.geom_pos,
                model.geom_quat,
                data.xpos,
                data.xquat,
            ],
            outputs=[data.geom_xpos, data.geom_xmat],
            device=self.device,
        )

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
        acc = self._acc_sensors
        if acc is not None:
            wp.launch(
                kernels.kernels().save_columns,
                dim=(self.num_envs, acc.shape[0]),
                inputs=[acc, data.sensordata, self._saved_sensordata],
                device=self.device,
            )
        mjw.step1(model, data)
        if acc is not None:
            wp.launch(
                kernels.kernels().restore_columns,
                dim=(self.num_envs, acc.shape[0]),
                inputs=[acc, self._saved_sensordata, data.sensordata],
                device=self.device,
            )

    def step(self, n_sub_steps: int = 1) -> None:
        """Advances every world by `n_sub_steps` physics steps (a CUDA graph on GPU)."""
        wp = self._wp
        acc = self._acc_sensors
        if acc is not None and self._saved_sensordata is None:
            self._saved_sensordata = wp.zeros(
                (self.num_envs, acc.shape[0]), dtype=wp.float32, device=self.device
            )
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
                    if self._static_geoms is not None:
                        self._place_static_geoms(self.warp_data)
                    mjw.forward(model, self.warp_data)
                    return
                active = self.warp_mask(mask)
                if active.ptr != self._forward_mask.ptr:
                    wp.copy(self._forward_mask, active)
                mjw.get_state(model, self.warp_data, self._states, _STATE_SPEC)
                mjw.set_state(model, self._scratch, self._states, _STATE_SPEC, active)
                if self._static_geoms is not None:
                    self._place_static_geoms(self._scratch)
                mjw.forward(model, self._scratch)
                self._copy_back_worlds()
        finally:
            option.disableflags = flags

    def _copy_back_worlds(self) -> None:
        """Copies the worlds of the forward's mask from its data back."""
        if self.is_cuda:
            for launch in self._copy_back:
                launch.launch()
            return
        chosen = np.flatnonzero(self._forward_mask_host)
        if chosen.size == self.num_envs:
            for source, target in self._copy_back_rows:
                target[...] = source
        else:
            for source, target in self._copy_back_rows:
                target[chosen] = source[chosen]

    def reset(self, mask) -> None:
        """Resets the worlds of `mask` to the model's initial state (`mj_resetData`: qpos0,
        zero velocities, time 0), on the device; derived quantities wait for `forward`."""
        with self._wp.ScopedDevice(self.device):
            self._mjw.reset_data(self.warp_model, self.warp_data, reset=self.warp_mask(mask))

    def set_state(self, states, mask) -> None:
        """Sets the physics state of the worlds of `mask` from `states`, on the device.

        Args:
          states: a float32 Warp array (num_envs, `state_size`): each world's
            `mjSTATE_INTEGRATION` state, as `mujoco.mj_getState` writes it; the rows of
            other worlds are not read.
          mask: a bool (num_envs,) mask (of the namespace, NumPy, or Warp): the worlds to set.
            Derived quantities wait for `forward`.
        """
        with self._wp.ScopedDevice(self.device):
            self._mjw.set_state(
                self.warp_model, self.warp_data, states, _STATE_SPEC, self.warp_mask(mask)
            )

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


def _rows_view(array, nworld: int) -> np.ndarray:
    """A contiguous Warp CPU array's memory as a NumPy (nworld,) view, one item a world's
    row (`composer.batch.arrays.row_items`)."""
    return row_items(array.numpy().reshape(-1).view(np.uint8).reshape(nworld, -1))


def _copy_worlds_launch(keep, source, target):
    """A recorded launch that copies the worlds where `keep` is true from `source` to
    `target` (same shapes), by whole 4-byte words where a world's row allows it."""
    wp = _warp.load().warp
    nworld = source.shape[0]
    word = wp.int32 if (source.capacity // nworld) % 4 == 0 else wp.uint8
    return wp.launch(
        kernels.kernels().copy_worlds,
        dim=nworld,
        inputs=[keep, kernels.rows(source, word, nworld), kernels.rows(target, word, nworld)],
        device=target.device,
        record_cmd=True,
    )
