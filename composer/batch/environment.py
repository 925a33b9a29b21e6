"""BatchEnvironment: `num_envs` copies of a composer task stepped together on MuJoCo Warp."""

import logging
import math
import numbers
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import dm_env
import numpy as np
from dm_env import specs

import composer
import mjcf
from composer import episode_end
from composer.batch import _warp, actions, arrays, devices, refusals, variations
from composer.batch import step_clock as clocks
from composer.batch.initial_states import StateMaker, StateProducer
from composer.batch.mujoco_batch import MujocoBatchPhysics, batch_model_fields, divergence_report
from composer.batch.observables import BatchObservables
from composer.batch.physics import BatchPhysics, device_model_fields
from composer.batch.state_slots import InitialStateStats, StateSlots
from composer.batch.task import BatchTask, InitialStateSource, for_task
from composer.batch.time_limit import NO_LIMIT, control_step_limit
from composer.episode_end import Autoreset
from composer.hooks import EnvironmentHooks
from composer.utils import argument_checks

__all__ = ["AUTORESET_MODES", "BatchEnvironment", "BatchTimeStep"]

#: The values of `BatchEnvironment(autoreset_mode=...)`: the `composer.episode_end`
#: modes a batch offers.
AUTORESET_MODES = (Autoreset.NEXT_STEP.value, Autoreset.SAME_STEP.value)

_FIRST, _MID, _LAST = (
    int(t) for t in (dm_env.StepType.FIRST, dm_env.StepType.MID, dm_env.StepType.LAST)
)


class BatchTimeStep(NamedTuple):
    """What `BatchEnvironment.reset` and `step` return, one row per world.

    The arrays are of the environment's `array_type` (NumPy by default; see
    `composer.batch.arrays`), computed on the batch's device in its float dtype: float64 on
    the CPU batch (`mujoco.batch`), float32 on MuJoCo Warp.

    Attributes:
      step_type: int8 (num_envs,), `dm_env.StepType` values: FIRST for a world whose
        episode starts, MID, or LAST for one whose episode ended at this step.
      reward: float (num_envs,); 0 for a FIRST world.
      discount: float (num_envs,); 1 for a FIRST world.
      observation: dict of float arrays (num_envs, *the CPU environment's observation
        shape).
    """

    step_type: Any
    reward: Any
    discount: Any
    observation: dict[str, Any]

    def first(self) -> Any:
        """Which worlds start an episode: a bool array (NumPy for Warp step types)."""
        return _step_types(self.step_type) == _FIRST

    def mid(self) -> Any:
        """Which worlds are mid-episode: a bool array (NumPy for Warp step types)."""
        return _step_types(self.step_type) == _MID

    def last(self) -> Any:
        """Which worlds ended their episode: a bool array (NumPy for Warp step types)."""
        return _step_types(self.step_type) == _LAST


def _step_types(step_type):
    # A Warp array has no elementwise comparison; its values come to the host to compare.
    return step_type.numpy() if arrays.array_library(step_type) == "warp" else step_type


def _check_arguments(
    *, array_type: str, autoreset_mode: str, device, time_limit, **counts: int
) -> None:
    """Raises ValueError naming the first bad one of `BatchEnvironment`'s plain arguments
    (`counts`: arguments that must be integers >= 1)."""
    arrays.check_array_type(array_type)
    if autoreset_mode not in AUTORESET_MODES:
        raise ValueError(
            f"autoreset_mode: expected one of {list(AUTORESET_MODES)}, got {autoreset_mode!r}"
        )
    if not isinstance(time_limit, numbers.Real) or math.isnan(time_limit) or time_limit < 0:
        raise ValueError(f"time_limit: expected a number of seconds >= 0, got {time_limit!r}")
    for name, value in counts.items():
        argument_checks.integer(**{name: value})


def _array_bridge(
    device: devices.Device, array_type: str, namespace: str | None
) -> arrays.ArrayBridge:
    """The `ArrayBridge` of the batch's device: NumPy memory on the CPU batch, else Warp's."""
    if not device.on_warp:
        return arrays.ArrayBridge.host(array_type, namespace)
    wp = _warp.load(device.warp_name).warp
    return arrays.ArrayBridge(wp, wp.get_device(device.warp_name), array_type, namespace)


class _HostModel(NamedTuple):
    """The task's model compiled on the host, and what its episodes vary.

    Attributes:
      physics: the host `mjcf.Physics`, on which the `after_compile` hooks have run.
      episode_model: the `variations.EpisodeModel` that patches an episode's MJCF changes
        into `physics`' model.
      varied: model field -> what varies it per world (`variations.measure`); empty for
        `InitialStateSource.ARRAY_CODE`, where no CPU episode hook runs.
    """

    physics: mjcf.Physics
    episode_model: variations.EpisodeModel
    varied: dict[str, str]


def world_random_states(
    num_envs: int,
    random_state: int | np.random.RandomState | None,
    random_states: Sequence[int | np.random.RandomState] | None,
) -> list[np.random.RandomState]:
    """Each world's random generator, by the batch's rule: `random_states` one per world
    (ints seed new generators), else world i's generator is seeded with the i-th of
    `num_envs` draws of `randint(2**31)` from `random_state` (an int seed, a generator or
    None).

    Raises:
      ValueError: for `random_states` of another length than `num_envs`.
    """
    if random_states is not None:
        if len(random_states) != num_envs:
            raise ValueError(
                f"random_states: expected {num_envs} (one per world), got {len(random_states)}"
            )
        return [
            rs if isinstance(rs, np.random.RandomState) else np.random.RandomState(rs)
            for rs in random_states
        ]
    if not isinstance(random_state, np.random.RandomState):
        random_state = np.random.RandomState(random_state)
    seeds = random_state.randint(2**31, size=num_envs)
    return [np.random.RandomState(seed) for seed in seeds]


class BatchEnvironment:
    """Runs `num_envs` worlds of a composer task as one batch, on the CPU or a GPU.

    The task's MJCF is compiled once through `mjcf` (the host `mjcf.Physics`, on which the
    `after_compile` hooks run once), then put on `device` with `num_envs` worlds. Each world
    is an episode of its own, with its own random generator, step count and time limit.
    Everything per world lives on the device: the physics, the step counters, the rewards,
    discounts and step types (the `BatchTask`'s array code), and the episode ends. A step
    launches work and copies nothing back to the host (see `composer.batch.state_slots`
    for the one read every `refill_interval` steps).

    Autoreset follows `composer.episode_end`: under "next_step" (the default) the `step`
    after a world's LAST resets it, ignores its action and returns FIRST with reward 0 and
    discount 1; under "same_step" (rsl_rl's and mjlab's) the `step` that ends an episode
    returns LAST with that episode's reward and discount and the next episode's first
    observation, the ended episode's last observation being `final_observation`.

    Args:
      task: a `composer.Task` with a registered batched version, or a `BatchTask`.
      num_envs: the number of worlds.
      device: "cpu" (`mujoco.batch` on C threads, float64, each world bit for bit the CPU
        environment's), "warp-cpu" (MuJoCo Warp's CPU device) or a CUDA device such as
        "cuda:0" (MuJoCo Warp); None picks "cuda:0" when MuJoCo Warp sees a GPU, else "cpu"
        (`composer.batch.devices`).
      time_limit: seconds of simulated time after which a world's episode ends (LAST).
      random_state: an int seed or `np.random.RandomState` from which each world's random
        generator is seeded (ignored when `random_states` is given).
      random_states: one int seed or `np.random.RandomState` per world.
      n_sub_steps: physics steps per control step (default: the task's).
      strip_singleton_obs_buffer_dim: as in `composer.Environment`.
      batched_model_fields: MjModel fields to give one row per world, in addition to the
        task's own and those its episodes vary (`composer.batch.variations`; see
        `BatchPhysics`).
      nconmax, njmax: per-world contact and constraint capacity for MuJoCo Warp.
      threads: the C threads that step the worlds on the CPU batch (None: the cores this
        process may use); MuJoCo Warp's devices take None only.
      array_type: what `reset` and `step` hand out: "numpy", "warp", "torch" or "jax" (see
        `composer.batch.arrays`). Actions may be NumPy, Warp, torch or JAX arrays whatever
        the array type.
      autoreset_mode: "next_step" or "same_step" (above).
      task_factory: a picklable callable returning a new CPU task like `task`, with which
        each initial-state producer builds its own task (needed for more than one).
      state_workers: the number of initial-state producers.
      state_processes: run the producers in processes instead of threads.
      slots_per_world, refill_interval: see `composer.batch.state_slots`.
      check_action_values: check device actions for NaN and infinity (one integer read
        per step); default: on Warp's CPU device only, where the read costs no copy.
      namespace: the array namespace of task code, "numpy" or "torch" (default: see
        `composer.batch.arrays`).
      raise_exception_on_physics_error: on the CPU batch, a world whose state becomes
        invalid in a step (NaN, infinite or huge qpos, qvel or qacc, which MuJoCo answers
        by resetting it) makes `step` raise `mjcf.PhysicsError` naming the world when True,
        as `composer.Environment` does; when False that world's episode ends there, as
        `composer.Environment`'s does (LAST, reward 0, discount 0, a logged warning naming
        the world) and every other world goes on. MuJoCo Warp does not report such worlds.

    Raises:
      ValueError: for a bad argument, named in the message.
      TypeError: for a task with no batched version, or an observable without a batched
        reader.
      NotImplementedError: for an MJCF variation that needs a recompile or a per-world field
        MuJoCo Warp shares (see `composer.batch.variations`), for a task or entity with
        sub-step or `after_step` hooks, or with a `before_step` that the `BatchTask` does
        not override.
    """

    def __init__(
        self,
        task: composer.Task | BatchTask,
        num_envs: int,
        *,
        device: str | None = None,
        time_limit: float = float("inf"),
        random_state: int | np.random.RandomState | None = None,
        random_states: Sequence[int | np.random.RandomState] | None = None,
        n_sub_steps: int | None = None,
        strip_singleton_obs_buffer_dim: bool = False,
        batched_model_fields: Sequence[str] = (),
        nconmax: int | None = None,
        njmax: int | None = None,
        array_type: str = "numpy",
        autoreset_mode: str = "next_step",
        task_factory: Callable[[], composer.Task] | None = None,
        state_workers: int = 1,
        state_processes: bool = False,
        slots_per_world: int = 3,
        refill_interval: int = 8,
        check_action_values: bool | None = None,
        namespace: str | None = None,
        threads: int | None = None,
        raise_exception_on_physics_error: bool = True,
    ):
        self.num_envs = argument_checks.integer(num_envs=num_envs)
        _check_arguments(
            array_type=array_type,
            autoreset_mode=autoreset_mode,
            device=device,
            time_limit=time_limit,
            state_workers=state_workers,
            slots_per_world=slots_per_world,
            refill_interval=refill_interval,
        )
        self._batch_task = for_task(task)
        hooks = EnvironmentHooks(self._batch_task.task)
        self._refuse_what_a_batch_cannot_run(hooks)
        self._n_sub_steps = self._sub_steps_per_control_step(n_sub_steps)
        self._random_states = world_random_states(self.num_envs, random_state, random_states)
        host = self._compile_on_host(hooks)
        self._device = devices.resolve(device)
        if threads is not None and self._device.on_warp:
            raise ValueError(
                f"threads: {threads!r} sets the CPU batch's C threads; device "
                f"{self._device.name!r} (MuJoCo Warp) takes threads=None"
            )
        self._arrays = _array_bridge(self._device, array_type, namespace)
        fields = self._per_world_fields(host, batched_model_fields)
        self._physics = self._put_worlds_on_device(
            host, fields, nconmax=nconmax, njmax=njmax, threads=threads
        )
        self._set_step_rules(host.physics, autoreset_mode, check_action_values)
        self._raise_exception_on_physics_error = bool(raise_exception_on_physics_error)
        self._observables = self._batch_observables(strip_singleton_obs_buffer_dim)
        self._step_limit = control_step_limit(
            float(time_limit), self._batch_task.task.physics_timestep, self._n_sub_steps
        )
        self._slots = self._initial_state_slots(
            host,
            fields,
            state_workers=state_workers,
            state_processes=state_processes,
            task_factory=task_factory,
            slots_per_world=slots_per_world,
            refill_interval=refill_interval,
        )
        self._make_episode_arrays()

    # The steps of __init__, in order.

    def _refuse_what_a_batch_cannot_run(self, hooks: EnvironmentHooks) -> None:
        """Raises NotImplementedError, naming the hook, for CPU hooks a batch cannot run
        (see `composer.batch.refusals`)."""
        if self._batch_task.initial_state_source is InitialStateSource.ARRAY_CODE:
            refusals.refuse_mjcf_variations(self._batch_task)
        refusals.refuse_unbatched_hooks(hooks, self._batch_task)

    def _sub_steps_per_control_step(self, n_sub_steps: int | None) -> int:
        """`n_sub_steps` checked, or the CPU task's when None."""
        if n_sub_steps is None:
            return self._batch_task.task.physics_steps_per_control_step
        return argument_checks.integer(n_sub_steps=n_sub_steps)

    def _compile_on_host(self, hooks: EnvironmentHooks) -> "_HostModel":
        """Compiles the task's MJCF into a host `mjcf.Physics`, runs the `after_compile`
        hooks on it once, and measures what the CPU task's episodes vary."""
        root = self._batch_task.task.root_entity.mjcf_model
        physics = mjcf.Physics.from_mjcf_model(root)
        with physics.reset_context():
            hooks.after_compile(physics, np.random.RandomState(0))
        episode_model = variations.EpisodeModel(hooks, physics, root)
        from_cpu_task = self._batch_task.initial_state_source is InitialStateSource.CPU_TASK
        varied = variations.measure(hooks, physics, episode_model) if from_cpu_task else {}
        return _HostModel(physics, episode_model, varied)

    def _per_world_fields(
        self, host: "_HostModel", batched_model_fields: Sequence[str]
    ) -> variations.PerWorldFields:
        """The model fields with one row per world.

        Returns:
          `device`: the task's `batched_model_fields`, the caller's, then the fields the
          episodes vary that MuJoCo Warp batches, each once; `host`: the varied fields that
          MuJoCo Warp does not have (see `variations.per_world_fields`).
        """
        batchable = device_model_fields() if self._device.on_warp else batch_model_fields()
        varied = variations.per_world_fields(host.varied, batchable, host.physics.model.ptr)
        device = (*self._batch_task.batched_model_fields, *batched_model_fields, *varied.device)
        return variations.PerWorldFields(device=tuple(dict.fromkeys(device)), host=varied.host)

    def _put_worlds_on_device(
        self,
        host: "_HostModel",
        fields: variations.PerWorldFields,
        *,
        nconmax: int | None,
        njmax: int | None,
        threads: int | None,
    ) -> "BatchPhysics | MujocoBatchPhysics":
        """The physics of `num_envs` worlds of the host model (`MujocoBatchPhysics` on the
        CPU batch, `BatchPhysics` on MuJoCo Warp), on which the `BatchTask`'s
        `after_compile` has run."""
        if self._device.on_warp:
            physics_type, options = BatchPhysics, {"nconmax": nconmax, "njmax": njmax}
        else:
            physics_type, options = MujocoBatchPhysics, {"threads": threads}
        physics = physics_type(
            host.physics,
            self.num_envs,
            arrays=self._arrays,
            batched_model_fields=fields.device,
            **options,
        )
        self._batch_task.after_compile(physics)
        return physics

    def _set_step_rules(
        self, host_physics: mjcf.Physics, autoreset_mode: str, check_action_values: bool | None
    ) -> None:
        """Sets what `step` follows: the autoreset mode, the action spec and whether action
        values are checked, and which of the task's hooks it calls (BatchTask's own discount,
        1, and termination, never, need no arrays of their own)."""
        self.autoreset_mode = autoreset_mode
        self._autoreset = Autoreset.of(autoreset_mode)
        self._check_action_values = (
            not self._physics.is_cuda if check_action_values is None else check_action_values
        )
        self._action_spec = self._batch_task.task.action_spec(host_physics)
        self._action_shape = (self.num_envs, *self._action_spec.shape)
        self._float_type = getattr(self._physics.xp, self._physics.float_dtype.name)
        task_type = type(self._batch_task)
        self._default_discount = task_type.get_discount is BatchTask.get_discount
        self._default_termination = (
            task_type.should_terminate_episode is BatchTask.should_terminate_episode
        )

    def _batch_observables(self, strip_singleton_obs_buffer_dim: bool) -> BatchObservables:
        """The batched readers of the CPU task's observables."""
        return BatchObservables(
            self._batch_task.task.observables,
            self._physics,
            strip_singleton_obs_buffer_dim,
            self._batch_task.observable_readers(self._physics),
        )

    def _initial_state_slots(
        self,
        host: "_HostModel",
        fields: variations.PerWorldFields,
        *,
        state_workers: int,
        state_processes: bool,
        task_factory: Callable[[], composer.Task] | None,
        slots_per_world: int,
        refill_interval: int,
    ) -> StateSlots | None:
        """The `StateSlots` that producers running the CPU task's initializers fill, and
        from which worlds start their episodes; None for `InitialStateSource.ARRAY_CODE`,
        where `BatchTask.initialize_episode` sets the initial states instead."""
        if self._batch_task.initial_state_source is InitialStateSource.ARRAY_CODE:
            return None
        maker = StateMaker(
            self._batch_task,
            host.physics,
            fields.device,
            host_fields=fields.host,
            episode_model=host.episode_model,
        )
        producer = StateProducer(
            maker,
            workers=state_workers,
            processes=state_processes,
            task_factory=task_factory,
            batch_task_type=type(self._batch_task),
            model_fields=fields.device,
            host_fields=fields.host,
        )
        slots = StateSlots(
            self._physics,
            producer,
            self._random_states,
            model_fields=fields.device,
            slots_per_world=slots_per_world,
            refill_interval=refill_interval,
        )
        self._batch_task.episode_values = slots.values
        return slots

    def _make_episode_arrays(self) -> None:
        """Makes what `step` keeps per world on the device (step counts, episode ends,
        discounts) and the constants it selects from; no episode has started yet."""
        xp, n = self._physics.xp, self.num_envs
        self._mask, self._mask_view = self._arrays.empty((n,), bool)
        self._steps = self._arrays.asarray(np.zeros(n, np.int32))
        self._ended = self._arrays.asarray(np.zeros(n, bool))
        self._discount = self._arrays.asarray(np.ones(n, self._physics.float_dtype))
        self._zero = xp.zeros_like(self._discount)
        self._one = xp.ones_like(self._discount)
        self._step_types = {
            kind: self._arrays.asarray(np.full(n, kind, np.int8)) for kind in (_FIRST, _MID, _LAST)
        }
        self._final_observation: dict[str, Any] = {}
        self._started = False
        self._clock = clocks.STOPPED

    @property
    def step_clock(self) -> clocks.StepClock | None:
        """The `composer.batch.step_clock.StepClock` timing each part of `step`, or None
        (the default: no timing, no synchronisation).

        Set it to a new `StepClock(env.synchronize)` to time the steps that follow; each
        part then ends with a wait for the device.
        """
        return None if self._clock is clocks.STOPPED else self._clock

    @step_clock.setter
    def step_clock(self, clock: clocks.StepClock | None) -> None:
        if clock is not None and not isinstance(clock, clocks.StepClock):
            raise ValueError(f"step_clock: expected a StepClock or None, got {clock!r}")
        self._clock = clocks.STOPPED if clock is None else clock

    def synchronize(self) -> None:
        """Waits until every launch on the batch's device has finished (the CPU batch's
        calls return when their work is done)."""
        if self._device.on_warp:
            _warp.load().warp.synchronize_device(self._physics.device)

    @property
    def cameras(self):
        """What renders the camera observables for every world: a
        `composer.batch.gl_cameras.GLBatchCameras` (OpenGL) on the CPU batch, a
        `composer.batch.cameras.BatchCameras` (MuJoCo Warp's ray tracer) on Warp; None when
        no enabled observable is a camera."""
        return self._observables.cameras

    @property
    def physics(self) -> "BatchPhysics | MujocoBatchPhysics":
        """The physics of all worlds: `MujocoBatchPhysics` on the CPU batch, `BatchPhysics`
        on MuJoCo Warp."""
        return self._physics

    @property
    def task(self) -> BatchTask:
        """The `BatchTask`; its `task` is the CPU task."""
        return self._batch_task

    @property
    def xp(self):
        """The array namespace of the batch's device arrays (see `composer.batch.arrays`)."""
        return self._physics.xp

    @property
    def random_states(self) -> list[np.random.RandomState]:
        """Each world's random generator (drawn from by the initial-state producers)."""
        if self._slots is not None:
            self._slots.sync_generators()
        return self._random_states

    @property
    def final_observation(self) -> dict[str, Any]:
        """With autoreset "same_step": the last observation of the episodes that ended at
        the last step (rows of other worlds are that step's observation), as `array_type`."""
        return {key: self.hand_out(value) for key, value in self._final_observation.items()}

    @property
    def array_type(self) -> str:
        """What `reset` and `step` hand out: "numpy", "warp", "torch" or "jax"."""
        return self._arrays.array_type

    @property
    def max_episode_steps(self) -> int | None:
        """The control steps after which the time limit ends an episode; None without one."""
        return None if self._step_limit == NO_LIMIT else self._step_limit

    @property
    def episode_steps(self) -> Any:
        """The control steps each world's episode has taken, int32 (num_envs,), handed out
        as `array_type` (a copy).

        Setting it (an integer array of shape (num_envs,), values from 0 to 2**31 - 2, as
        the device counts in int32) moves each world's count, and so when its time limit
        ends it: rsl_rl starts training from random episode lengths this way.
        """
        return self.hand_out(self.xp.asarray(self._steps, copy=True))

    @episode_steps.setter
    def episode_steps(self, steps) -> None:
        values = self._arrays.to_host(steps)
        if values.shape != (self.num_envs,) or not np.issubdtype(values.dtype, np.integer):
            raise ValueError(
                f"episode_steps: expected integers of shape ({self.num_envs},), got "
                f"{values.dtype} of shape {values.shape}"
            )
        if values.size and not 0 <= values.min() <= values.max() < NO_LIMIT:
            bad = values.min() if values.min() < 0 else values.max()
            raise ValueError(f"episode_steps: expected counts from 0 to {NO_LIMIT - 1}, got {bad}")
        self._steps = self._arrays.asarray(values.astype(np.int32))

    def initial_state_stats(self) -> InitialStateStats | None:
        """How the initial-state producers kept up (None for array-code initial states)."""
        return None if self._slots is None else self._slots.stats

    def reseed(
        self,
        seed: int | np.random.RandomState | None = None,
        *,
        random_states: Sequence[int | np.random.RandomState] | None = None,
    ) -> None:
        """Reseeds every world's random generator, as the constructor does: from `seed`, or
        world i from `random_states[i]` when given; the next `step` or `reset` starts every
        world's episode anew.

        Raises:
          ValueError: for `random_states` of other than `num_envs` entries.
        """
        self._random_states[:] = world_random_states(self.num_envs, seed, random_states)
        if self._slots is not None:
            self._slots.restart(self._random_states)
        self._started = False

    def action_spec(self) -> specs.BoundedArray:
        """One world's action spec (the CPU task's); actions have a leading num_envs axis."""
        return self._action_spec

    def observation_spec(self) -> dict[str, specs.Array]:
        """One world's observation specs by key: the shapes of one world; features are
        float32, camera images have their CPU observable's dtype (uint8 RGB)."""
        return {
            name: specs.Array(tuple(value.shape[1:]), self._observables.dtype(name), name)
            for name, value in self._observables.read().items()
        }

    def _start_episodes(self, mask) -> None:
        """Starts a new episode in the worlds of `mask` (an array of the namespace)."""
        physics = self._physics
        if physics.arrays.library == "numpy" and not mask.any():
            return  # free to know in NumPy; elsewhere the masked work runs for no world
        self._mask_view[...] = mask
        if self._slots is None:
            physics.reset(self._mask)
            self._batch_task.initialize_episode(physics, self._mask_view)
            physics.forward(self._mask, actuation=False)
        else:
            physics.run_captured("start_episodes", self._apply_prepared_states)

    def _apply_prepared_states(self) -> None:
        self._slots.apply(self._mask)
        self._physics.forward(self._mask, actuation=False)

    def reset(self) -> BatchTimeStep:
        """Starts a new episode in every world.

        Returns:
          A `BatchTimeStep` with every step type FIRST, rewards 0 and discounts 1.
        """
        self._arrays.use_stream()
        if self._slots is not None:
            self._slots.refill(wait=True)
        xp = self.xp
        every = xp.ones(self.num_envs, dtype=xp.bool, device=self._arrays.xp_device)
        self._start_episodes(every)
        self._started = True
        self._steps = xp.zeros_like(self._steps)
        self._ended = xp.zeros_like(self._ended)
        self._discount = self._one
        # New arrays, as every step's: the caller may keep or change them.
        return self._time_step(
            xp.asarray(self._step_types[_FIRST], copy=True),
            xp.zeros_like(self._zero),
            xp.ones_like(self._one),
            self._observables.read(),
        )

    def _time_step(self, step_type, reward, discount, observation) -> BatchTimeStep:
        hand_out = self._arrays.hand_out
        return BatchTimeStep(
            hand_out(step_type),
            hand_out(reward),
            hand_out(discount),
            {name: hand_out(value) for name, value in observation.items()},
        )

    def hand_out(self, values) -> Any:
        """An array of the namespace (or host values) as this environment's `array_type`."""
        if not arrays.array_library(values) and isinstance(values, np.ndarray):
            values = self._arrays.asarray(values)
        return self._arrays.hand_out(values)

    def episode_ends(self) -> episode_end.EpisodeEnds:
        """How the episodes that ended at the last `step` ended, as arrays of the namespace.

        Returns:
          A `composer.episode_end.EpisodeEnds` of bool (num_envs,) arrays: `terminated`
          where the task ended an episode (discount 0), `truncated` where the time limit did.
        """
        return episode_end.episode_ends(self._ended, self._discount)

    def step(self, action) -> BatchTimeStep:
        """Steps every world by one control step; see the class docstring for autoreset.

        Args:
          action: shape (num_envs, *action_spec().shape): a NumPy array (or anything
            NumPy reads), or a Warp, torch or JAX array on the batch's device (used there
            without a copy).

        Returns:
          A `BatchTimeStep`: LAST for worlds whose episode ended (the task terminated it or
          the time limit passed), FIRST (reward 0, discount 1) for worlds reset at this step
          under "next_step", MID for the others.

        Raises:
          ValueError: for an action of the wrong shape or with NaN or infinity; nothing is
            stepped.
          mjcf.PhysicsError: on the CPU batch, when a world's state became invalid and
            `raise_exception_on_physics_error` is True; every world has been stepped (the
            invalid one reset by MuJoCo), and the step is not counted: call `reset`.
        """
        self._arrays.use_stream()
        clock = self._clock
        clock.start()
        checked = actions.check_action(
            action,
            self._action_shape,
            self._arrays,
            check_values=self._check_action_values,
            dtype=self._physics.float_dtype,
        )
        clock.lap("action")
        if not self._started:
            return self.reset()
        xp, physics, task = self.xp, self._physics, self._batch_task
        task.before_step(physics, checked)
        clock.lap("task")
        physics.step(self._n_sub_steps)
        clock.lap("physics")
        autoreset = self._autoreset
        restarting = autoreset.resets_before_step(self._ended)
        diverged = self._diverged_worlds(restarting) if physics.last_divergences else None
        if autoreset is Autoreset.NEXT_STEP:
            # These worlds were stepped with the others; their reset overwrites that step.
            self._start_episodes(restarting)
            clock.lap("start_episodes")
        floats = self._float_type
        reward = xp.astype(task.get_reward(physics), floats, copy=False)
        # BatchTask's own discount (1) and termination (never) need no arrays of their own.
        discount = (
            self._one
            if self._default_discount
            else xp.astype(task.get_discount(physics), floats, copy=False)
        )
        terminated = (
            None
            if self._default_termination
            else xp.astype(task.should_terminate_episode(physics), xp.bool, copy=False)
        )
        if diverged is not None:
            reward = xp.where(diverged, self._zero, reward)
            discount = xp.where(diverged, self._zero, discount)
            terminated = diverged if terminated is None else terminated | diverged
        clock.lap("task")
        steps = xp.where(restarting, 0, self._steps + 1)
        ended = steps >= self._step_limit
        if terminated is not None:
            ended = ended | terminated
        ended = ended & ~restarting
        step_type = xp.where(
            restarting,
            self._step_types[_FIRST],
            xp.where(ended, self._step_types[_LAST], self._step_types[_MID]),
        )
        reward = xp.where(restarting, self._zero, reward)
        discount = xp.where(restarting, self._one, discount)
        clock.lap("counters")
        observation = self._observables.read()
        clock.lap("observations")
        if autoreset is Autoreset.SAME_STEP:
            self._final_observation = observation
            self._start_episodes(ended)
            steps = xp.where(ended, 0, steps)
            clock.lap("start_episodes")
            fresh = self._observables.read()
            observation = {
                key: xp.where(_rows(xp, ended, value), fresh[key], value)
                for key, value in observation.items()
            }
            clock.lap("observations")
        self._steps, self._ended, self._discount = steps, ended, discount
        if self._slots is not None:
            self._slots.after_step()
        clock.lap("refill")
        time_step = self._time_step(step_type, reward, discount, observation)
        clock.lap("hand_out")
        return time_step

    def _diverged_worlds(self, restarting) -> np.ndarray | None:
        """The worlds whose state became invalid in the last physics step and whose episode
        it ends (a world restarting at this step is overwritten by its reset), as a bool
        (num_envs,) mask, or None for none.

        Raises:
          mjcf.PhysicsError: naming those worlds, with `raise_exception_on_physics_error`.
        """
        restarting = np.asarray(restarting, dtype=bool)
        found = [d for d in self._physics.last_divergences if not restarting[d.world]]
        if not found:
            return None
        report = divergence_report(found)
        if self._raise_exception_on_physics_error:
            raise mjcf.PhysicsError(report)
        logging.warning("Physics error, ending the episode of %s", report)
        diverged = np.zeros(self.num_envs, dtype=bool)
        diverged[[d.world for d in found]] = True
        return diverged

    def close(self) -> None:
        """Stops the initial-state producers and releases the cameras' renderers (on the
        CPU batch, their OpenGL contexts and worker threads)."""
        try:
            if self._slots is not None:
                self._slots.close()
        finally:
            self._observables.close()


def _rows(xp, mask, like):
    """`mask` (num_envs,) shaped to broadcast over the rows of `like`."""
    return xp.reshape(mask, (mask.shape[0],) + (1,) * (like.ndim - 1))
