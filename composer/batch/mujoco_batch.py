"""MujocoBatchPhysics: `num_envs` worlds of one compiled model on `mujoco.batch`, in float64.

MuJoCo 4's `mujoco.batch.Batch` keeps one `MjData` per world and steps them all in one call
on C threads (the GIL released once). This is the batch's CPU device: the interface of
`composer.batch.physics.BatchPhysics` (field views, `bind`, `named`, `forward(mask)`,
`reset(mask)`, `set_state`, contacts), on NumPy float64 arrays, so that a world computes
exactly what a `composer.Environment` computes: a control step is one `Batch.step` of
`n_sub_steps` physics steps that ends with the position and velocity stages computed, which
is the legacy step chain (`mj_step2`, `mj_step` n - 1 times, `mj_step1`) of `mjcf.Physics`.

Where values live: the batch's rows. A state field (`qpos`, `qvel`, `ctrl`, `mocap_pos`, ...,
the parts of `mjSTATE_INTEGRATION`) is a live view of the rows, so writes land in the
worlds; every other data field is an output MuJoCo copies out after each call, read-only. A
model field is the compiled model's, shared by every world (writes refuse), unless named in
`batched_model_fields`, which gives each world its own row (`Batch.expand`). Derived
quantities are not recomputed after a write: `forward(mask)` does that for the worlds of a
mask and no other.
"""

import os
from collections.abc import Sequence
from typing import NamedTuple

import mujoco
import numpy as np

import mjcf
from composer.batch.arrays import ArrayBridge
from composer.batch.bindings import BatchFields, FieldStorage
from mujoco_physics import engine, field_layout

__all__ = [
    "Divergence",
    "MujocoBatchPhysics",
    "batch_model_fields",
    "divergence_report",
    "require_mujoco_batch",
]

_STATE_SPEC = mujoco.mjtState.mjSTATE_INTEGRATION
_VEL_STAGE = int(mujoco.mjtStage.mjSTAGE_VEL)
_NO_STAGE = int(mujoco.mjtStage.mjSTAGE_NONE)
_NO_ACTUATION = int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)


def require_mujoco_batch():
    """Returns the `mujoco.batch` module.

    Raises:
      ImportError: when the installed MuJoCo has no `mujoco.batch` (below 4.0), naming the
        installed version and the device that runs there instead.
    """
    try:
        from mujoco import batch
    except ImportError as error:
        raise ImportError(
            f"device='cpu': the CPU batch runs on mujoco.batch, which MuJoCo "
            f"{mujoco.__version__} does not have (it came with MuJoCo 4.0): pip install "
            "'mujoco>=4', or pass device='warp-cpu' for MuJoCo Warp's CPU device "
            f"(the extra [warp]) ({error})"
        ) from error
    return batch


def batch_model_fields() -> dict[str, bool]:
    """The MjModel fields `mujoco.batch` can give one row per world, each with True.

    Returns:
      Field name (as in `mujoco.MjModel`) -> True, for every array field `Batch.expand`
      takes (its option fields, named `opt.<name>`, are left out).
    """
    batch = require_mujoco_batch()
    return {name: True for name in batch.MODEL_FIELDS if not name.startswith("opt.")}


class Contacts(NamedTuple):
    """The contacts of one world's last collision pass.

    Attributes:
      geom: int (ncon, 2): the two geoms of each contact, as `MjData.contact.geom`.
    """

    geom: np.ndarray


class Divergence(NamedTuple):
    """A world MuJoCo reset in a step because its state became invalid.

    Attributes:
      world: the world's index.
      message: the `PhysicsError` message `mjcf.Physics` gives for it ("Physics state is
        invalid. Warning(s) raised: mjWARN_BADQVEL", ...).
    """

    world: int
    message: str


def divergence_report(divergences: Sequence[Divergence]) -> str:
    """The worlds of `divergences` with their messages, as a `PhysicsError` names them
    ("world 3: Physics state is invalid. ...; world 7: ...")."""
    return "; ".join(f"world {d.world}: {d.message}" for d in divergences)


class ContactWatch:
    """Which worlds have a contact between two sets of geoms.

    Made by `MujocoBatchPhysics.contact_watch`; calling it returns a bool (num_envs,) NumPy
    array, the watch's own, rewritten by every call. Contacts live in each world's MjData
    arena, which `mujoco.batch` does not expose as a view: a call copies the MjData of each
    world that has contacts (`Batch.get_data`), about a microsecond per kilobyte of MjData.
    """

    def __init__(self, physics: "MujocoBatchPhysics", first_geoms, second_geoms):
        self._physics = physics
        self._first = np.asarray(first_geoms, dtype=bool)
        self._second = np.asarray(second_geoms, dtype=bool)
        self.worlds = np.zeros(physics.num_envs, dtype=bool)

    def __call__(self, candidates: np.ndarray | None = None) -> np.ndarray:
        """Which worlds have such a contact; with `candidates` (a bool (num_envs,) mask),
        only those worlds are looked at (the others read False)."""
        physics, first, second = self._physics, self._first, self._second
        self.worlds[...] = False
        counted = physics.contact_counts() > 0
        if candidates is not None:
            counted &= candidates
        for world in np.flatnonzero(counted):
            geoms = physics.contacts(int(world)).geom
            a, b = geoms[:, 0], geoms[:, 1]
            self.worlds[world] = bool(np.any((first[a] & second[b]) | (first[b] & second[a])))
        return self.worlds


class MujocoBatchPhysics(BatchFields):
    """`num_envs` worlds of the model compiled into `host`, on `mujoco.batch` C threads.

    Args:
      host: the `mjcf.Physics` the model was compiled into; every world starts from its
        data's state. It also resolves MJCF elements for `bind`.
      num_envs: the number of worlds, >= 1.
      arrays: the batch's host `ArrayBridge` (`ArrayBridge.host`).
      batched_model_fields: MjModel field names that get one row per world.
      threads: the C threads that step the worlds (None: the cores this process may use).

    Attributes:
      xp: the array namespace of every read (NumPy).
      float_dtype: float64: the dtype of every float field, as in C MuJoCo.
      state_size: the length of one world's state in `set_state` (`mjSTATE_INTEGRATION`).
      batch: the `mujoco.batch.Batch` (persistent) that holds and steps the worlds.
      last_divergences: a `Divergence` for each world whose state became invalid in the
        last `step` (MuJoCo reset it and stepped on, as `mj_step` does). Not seen: a world
        with `mjDSBL_AUTORESET`, and one whose very first step of an episode, from time 0,
        diverges in its first sub-step.

    Raises:
      ImportError: without `mujoco.batch` (MuJoCo below 4.0).
      ValueError: for a field in `batched_model_fields` that `mujoco.batch` cannot expand,
        or a bad `threads`.
    """

    is_cuda = False
    device = "cpu"
    float_dtype = np.dtype(np.float64)
    on_warp = False

    def __init__(
        self,
        host: mjcf.Physics,
        num_envs: int,
        *,
        arrays: ArrayBridge,
        batched_model_fields: Sequence[str] = (),
        threads: int | None = None,
    ):
        batch_module = require_mujoco_batch()
        self.host = host
        self.num_envs = int(num_envs)
        self.arrays = arrays
        self.xp = arrays.xp
        self.mj_model: mujoco.MjModel = host.model.ptr
        self.layout = field_layout.ModelLayout(self.mj_model)
        self.batched_model_fields = frozenset(batched_model_fields)
        unknown = sorted(self.batched_model_fields - set(batch_model_fields()))
        if unknown:
            raise ValueError(
                f"batched_model_fields: {unknown} are not MjModel array fields mujoco.batch "
                "can expand; expected names such as 'geom_friction', 'body_mass'"
            )
        self.threads = _thread_count(threads)
        self.batch = batch_module.Batch(
            self.mj_model, self.num_envs, nthread=self.threads, persistent=True
        )
        self.state_size = mujoco.mj_stateSize(self.mj_model, _STATE_SPEC)
        if self.batch.nstate != self.state_size:
            raise RuntimeError(
                f"mujoco.batch holds {self.batch.nstate} state numbers per world where "
                f"mjSTATE_INTEGRATION has {self.state_size}: this MuJoCo's batch rows are not "
                "the integration state the initial states are written as"
            )
        for name in sorted(self.batched_model_fields):
            self.batch.expand(name)
        self._disable_flags = None  # expanded at the first forward without actuation
        self._one_world: mujoco.MjData | None = None  # one world's copy, to read
        self.last_divergences: tuple[Divergence, ...] = ()
        initial = np.empty(self.state_size)
        mujoco.mj_getState(self.mj_model, host.data.ptr, initial, _STATE_SPEC)
        self.batch.reset(stage=_NO_STAGE)
        self.batch.state[...] = initial
        self.batch.forward()
        self._times = self.batch.bind("time")
        self._timesteps = (
            self.batch.expand("opt.timestep")
            if "opt.timestep" in self.batched_model_fields
            else self.mj_model.opt.timestep
        )
        self._make_views()

    # Fields.

    def field_storage(self, struct: str, name: str) -> FieldStorage:
        """The `FieldStorage` of field `name`: the batch's rows of it, or for a shared
        model field the compiled model's array.

        Raises:
          AttributeError: for a data field `mujoco.batch` cannot bind (the arena's contacts
            and constraints).
        """
        if struct == field_layout.MODEL:
            if name in self.batched_model_fields:
                rows, per_world = self.batch.expand(name), True
            else:
                value = getattr(self.mj_model, name)
                rows, per_world = value.reshape((1, *value.shape)), False
        else:
            try:
                rows, per_world = self.batch.bind(name), True
            except ValueError as error:
                raise AttributeError(f"data field {name!r}: {error}") from None
        return FieldStorage(rows, per_world, rows.dtype == self.float_dtype)

    def contact_counts(self) -> np.ndarray:
        """int (num_envs,): each world's number of contacts in its last collision pass."""
        return self.batch.bind("ncon")

    def contacts(self, world: int) -> Contacts:
        """The `Contacts` of world `world` (a copy of its MjData's; see `ContactWatch`)."""
        return Contacts(geom=self._world_data(world).contact.geom.copy())

    def _world_data(self, world: int) -> mujoco.MjData:
        """World `world`'s MjData, copied into one MjData kept for such reads."""
        if self._one_world is None:
            self._one_world = mujoco.MjData(self.mj_model)
        return self.batch.get_data(world, self._one_world)

    def contact_watch(self, first_geoms: np.ndarray, second_geoms: np.ndarray) -> ContactWatch:
        """A `ContactWatch` for contacts between a geom of `first_geoms` and one of
        `second_geoms` (two bool masks over the compiled geoms)."""
        return ContactWatch(self, first_geoms, second_geoms)

    # Simulation.

    def step(self, n_sub_steps: int = 1) -> None:
        """Advances every world by `n_sub_steps` physics steps, ending with the position
        and velocity stages of the new state computed (the legacy step chain).

        A world that diverged in the call is in `last_divergences` afterwards.
        """
        n = int(n_sub_steps)
        before = self._times.copy()
        self.batch.step(nstep=n, stage=_VEL_STAGE)
        # MuJoCo resets a world whose qpos, qvel or qacc became NaN, infinite or huge
        # (mj_resetData: time 0), and carries on from there: its clock is then behind
        # where n steps take it. One comparison of num_envs times finds such worlds.
        behind = self._times < before + (n - 0.5) * self._timesteps
        self.last_divergences = (
            tuple(self._divergence(int(world)) for world in np.flatnonzero(behind))
            if behind.any()
            else ()
        )

    def _divergence(self, world: int) -> Divergence:
        """The `Divergence` of `world`, naming the warnings it raised: MuJoCo's reset
        zeroed its counters before counting the warning that caused it."""
        counts = self._world_data(world).warning.number
        message = engine.invalid_state_message(np.zeros_like(counts), counts)
        return Divergence(world, message or "Physics state is invalid (MuJoCo reset it)")

    def run_captured(self, key, work) -> None:
        """Runs `work` (nothing is captured off a GPU)."""
        work()

    def forward(self, mask=None, *, actuation: bool = True) -> None:
        """Recomputes derived quantities of the worlds of `mask`, as `mj_forward`; other
        worlds are left exactly as they were.

        Args:
          mask: a bool (num_envs,) array, or None for every world.
          actuation: False runs forward with actuation disabled, as after a reset in
            `mjcf.Physics.reset_context`.
        """
        ids = _ids(mask)
        if ids is not None and ids.size == 0:
            return
        if actuation:
            self.batch.forward(ids)
            return
        if self._disable_flags is None:
            self._disable_flags = self.batch.expand("opt.disableflags")
        flags = self._disable_flags
        chosen = slice(None) if ids is None else ids
        saved = flags[chosen].copy()
        flags[chosen] = saved | _NO_ACTUATION
        try:
            self.batch.forward(ids)
        finally:
            flags[chosen] = saved

    def reset(self, mask) -> None:
        """Resets the worlds of `mask` to the model's initial state (`mj_resetData`);
        derived quantities wait for `forward`."""
        ids = _ids(mask)
        if ids is None or ids.size:
            self.batch.reset(ids, stage=_NO_STAGE)

    def set_state(self, states: np.ndarray, mask) -> None:
        """Sets the physics state of the worlds of `mask` from the rows of `states`
        (num_envs, `state_size`) float64, each an `mj_getState(mjSTATE_INTEGRATION)`
        vector; derived quantities wait for `forward`."""
        ids = _ids(mask)
        if ids is None:
            self.batch.state[...] = states
        else:
            self.batch.state[ids] = states[ids]

    def set_model_rows(self, name: str, rows: np.ndarray, ids: np.ndarray) -> None:
        """Writes `rows` (len(ids), *a row's shape) into the worlds `ids` of batched model
        field `name`."""
        field = self.batch.expand(name)
        field[ids] = rows.reshape((ids.size, *field.shape[1:]))

    def set_shared_model_field(self, name: str, value: np.ndarray) -> None:
        """Sets model field `name` of every world (a field the initializers change the same
        way in each)."""
        field = self.batch.expand(name)
        field[...] = np.asarray(value).reshape(field.shape[1:])


def _ids(mask) -> np.ndarray | None:
    """The worlds of a bool mask, or None (every world) for None."""
    if mask is None:
        return None
    return np.flatnonzero(np.asarray(mask, dtype=bool)).astype(np.int32)


def _thread_count(threads: int | None) -> int:
    if threads is None:
        try:
            return max(1, len(os.sched_getaffinity(0)))
        except AttributeError:  # not on Linux
            return max(1, os.cpu_count() or 1)
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
        raise ValueError(f"threads: expected an integer >= 1, got {threads!r}")
    return int(threads)
