"""Each world's next initial states, waiting on the device; applied to chosen worlds at once.

Every world has `slots_per_world` slots on the device; its episode e starts from slot
e % slots_per_world. A reset of the worlds of a mask is a few kernel launches on the
device: copy each chosen world's slot into its state (`BatchPhysics.set_state` with the mask),
its batched model rows and its episode values, and count the episode. The host never learns
which worlds reset at that step.

Refilling (the one rule for producers): the first reset of every world fills every slot
and waits for it; a later one (`refill(wait=True)`) puts every world's next episode on the
device, waiting for it, and asks for the other slots' states in the background. After
that, every `refill_interval` control steps the host reads how many episodes each world
has started (one (2, num_envs) int32 device-to-host copy) and asks the producers for the
states of the slots freed since. It waits for the producers only when some world's next
episode has no state on the device (the caller waits rather than change the
distribution); at other steps, states the producers have finished are uploaded without
waiting (host to device only). A world that still starts an episode whose state is not
uploaded (it started more than `slots_per_world` episodes between two refills) starts it
from the state in its slot, the one it used `slots_per_world` episodes before: the device
counts each such reuse exactly (`StateSlots.stats`), and the first one is warned about.
"""

import time
import warnings
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from composer.batch import _warp, kernels
from composer.batch.initial_states import Job, ProducedStates, StateProducer

__all__ = ["InitialStateStats", "StateSlots"]

#: How long a refill waits for the producers before it gives up (seconds).
PRODUCER_TIMEOUT = 600.0


class InitialStateStats(NamedTuple):
    """How the producers kept up.

    Attributes:
      started: episodes started, all worlds together.
      reused: episodes that started from a state their world had used before, because the
        producers' states had not been uploaded yet (see the module docstring).
      waits: refills at which the caller waited for the producers.
      wait_seconds: the time the caller spent waiting.
      producer_cpu_seconds: the CPU time the producers spent making the states uploaded
        so far, every worker's together (work beside the caller's, on other cores where
        there are).
    """

    started: int
    reused: int
    waits: int
    wait_seconds: float
    producer_cpu_seconds: float


class StateSlots:
    """The device slots of `physics`' worlds, filled by `producer`.

    Args:
      physics: the `BatchPhysics` whose worlds start from the slots.
      producer: the `StateProducer` that makes the states.
      random_states: each world's generator (the list is updated in place as jobs return).
      model_fields: the batched model fields that a state sets.
      slots_per_world: states waiting on the device per world (>= 1).
      refill_interval: control steps between two refills (>= 1).

    Attributes:
      values: the current episode's `BatchTask.initial_values` of every world, by name,
        arrays of the batch's namespace of shape (num_envs, *value shape).
    """

    def __init__(
        self,
        physics,
        producer: StateProducer,
        random_states: list,
        *,
        model_fields: Sequence[str],
        slots_per_world: int = 3,
        refill_interval: int = 8,
    ):
        self._on_warp = physics.on_warp
        wp = _warp.load().warp if self._on_warp else None
        self._wp = wp
        self._physics = physics
        self._producer = producer
        self.random_states = random_states
        self._model_fields = tuple(model_fields)
        self.slots_per_world = int(slots_per_world)
        self.refill_interval = int(refill_interval)
        n, k = physics.num_envs, self.slots_per_world
        device = physics.device
        floats = physics.float_dtype
        # Row 0: episodes each world has started; row 1: of those, how many reused a state.
        if self._on_warp:
            self._counters = wp.zeros((2, n), dtype=wp.int32, device=device)
            self._uploaded_on_device = wp.zeros(n, dtype=wp.int32, device=device)
            self._chosen = wp.zeros((n, physics.state_size), dtype=wp.float32, device=device)
        else:
            self._counters = np.zeros((2, n), np.int32)
            self._uploaded_on_device = np.zeros(n, np.int32)
            self._chosen = np.zeros((n, physics.state_size), floats)
        self._slot_states = self._host_backed((n * k, physics.state_size), floats)
        self._slot_rows = {}
        self._row_targets = {}
        for name in self._model_fields:
            field = physics.field("model", name)
            if self._on_warp:
                floating = _scalar(field.device_array.dtype) is wp.float32
            else:
                floating = np.issubdtype(field.view.dtype, np.floating)
            if not floating:
                raise ValueError(
                    f"batched_model_fields: {name!r} is not a float field on the device; an "
                    "initial state can only set float model fields"
                )
            size = int(np.prod(field.c_shape))
            if self._on_warp:
                self._slot_rows[name] = self._host_backed((n * k, size), np.float32)
                self._row_targets[name] = kernels.rows(field.device_array, wp.float32, n)
            else:
                self._slot_rows[name] = self._host_backed((n * k, size), field.view.dtype)
        self._slot_values: dict = {}
        self._value_targets: dict = {}
        self.values: dict = {}
        self._pending = None
        # World -> its generator's state from a worker process, not yet set on its
        # `random_states` entry (see `sync_generators`).
        self._generator_states: dict[int, tuple] = {}
        self._shared_written: dict[str, np.ndarray] | None = None
        self._warned = False
        self._steps = 0
        self._control_steps = 0  # since the last restart, for the warning's rates
        self._clear_bookkeeping()
        self._stats = InitialStateStats(0, 0, 0, 0.0, 0.0)

    def _host_backed(self, shape, dtype):
        """(device array, host array): the same memory on the CPU devices, a mirror on
        CUDA."""
        if not self._on_warp:
            array = np.zeros(shape, dtype)
            return array, array
        wp = self._wp
        array = wp.zeros(shape, dtype=wp.float32, device=self._physics.device)
        host = np.zeros(shape, np.float32) if self._physics.is_cuda else array.numpy()
        return array, host

    def _clear_bookkeeping(self) -> None:
        n = self._physics.num_envs
        self._uploaded = np.zeros(n, np.int64)  # episodes below this are on the device
        self._requested = np.zeros(n, np.int64)  # episodes below this were asked for

    @property
    def stats(self) -> InitialStateStats:
        """The producers' `InitialStateStats` since the last `restart` (reads the device's
        counters: one device-to-host copy)."""
        started, reused = self._counter_values().sum(axis=1)
        return self._stats._replace(started=int(started), reused=int(reused))

    def restart(self, random_states: list) -> None:
        """Drops every prepared state and starts the worlds' streams anew from
        `random_states` (after a reseed)."""
        self._drop_pending()
        self._generator_states.clear()
        self.random_states[:] = random_states
        if self._on_warp:
            self._counters.zero_()
            self._uploaded_on_device.zero_()
        else:
            self._counters[...] = 0
            self._uploaded_on_device[...] = 0
        self._clear_bookkeeping()
        self._control_steps = 0
        self._stats = InitialStateStats(0, 0, 0, 0.0, 0.0)

    def sync_generators(self) -> None:
        """Sets each world's `random_states` entry to the state its worker process left it
        in (process producers send generator states back, not generators), after waiting
        for the jobs in progress, which draw from them (thread workers draw in place)."""
        self._collect()
        for world, state in self._generator_states.items():
            self.random_states[world].set_state(state)
        self._generator_states.clear()

    def _drop_pending(self) -> None:
        if self._pending is not None:
            try:
                self._pending.result(PRODUCER_TIMEOUT)
            finally:
                self._pending = None

    # Applying.

    def _counter_values(self) -> np.ndarray:
        """The counters as int64 NumPy (2, num_envs): one device-to-host copy on CUDA."""
        counters = self._counters.numpy() if self._on_warp else self._counters
        return counters.astype(np.int64)

    def apply(self, mask) -> None:
        """Starts the next episode of the worlds of `mask` (a Warp bool array; NumPy on
        the CPU batch)."""
        if not self._on_warp:
            self._apply_on_host(mask)
            return
        wp, physics = self._wp, self._physics
        k = self.slots_per_world
        take = kernels.kernels().take_slots
        n = physics.num_envs

        def launch(slots, target):
            wp.launch(
                take,
                dim=target.shape,
                inputs=[mask, self._counters, k, slots, target],
                device=physics.device,
            )

        launch(self._slot_states[0], self._chosen)
        physics.set_state(self._chosen, mask)
        for name, target in self._row_targets.items():
            launch(self._slot_rows[name][0], target)
        for name, target in self._value_targets.items():
            launch(self._slot_values[name][0], target)
        wp.launch(
            kernels.kernels().count_episodes,
            dim=n,
            inputs=[mask, self._uploaded_on_device, self._counters],
            device=physics.device,
        )

    def _apply_on_host(self, mask) -> None:
        """`apply` on the CPU batch: the same steps, as NumPy writes into its rows."""
        physics, k = self._physics, self.slots_per_world
        worlds = np.flatnonzero(np.asarray(mask, dtype=bool))
        started = self._counters[0, worlds]
        rows = worlds * k + started % k
        self._chosen[worlds] = self._slot_states[1][rows]
        physics.set_state(self._chosen, mask)
        for name, (_, host) in self._slot_rows.items():
            physics.set_model_rows(name, host[rows], worlds)
        for name, target in self._value_targets.items():
            target[worlds] = self._slot_values[name][1][rows]
        self._counters[1, worlds] += started >= self._uploaded_on_device[worlds]
        self._counters[0, worlds] = started + 1

    # Refilling.

    def after_step(self) -> None:
        """Counts a control step: uploads finished states, and refills every
        `refill_interval` steps."""
        self._steps += 1
        self._control_steps += 1
        if self._steps >= self.refill_interval:
            self.refill(wait=False)
        elif self._pending is not None and self._pending.done():
            self._collect()

    def refill(self, *, wait: bool) -> None:
        """Uploads finished states and asks for the ones freed since the last refill.

        Waits for the producers only where it must: when some world's next episode has no
        state on the device (or with `wait`).

        Args:
          wait: make sure every world's next episode is on the device before returning (a
            reset of every world needs it); the other slots fill in the background.
        """
        self._steps = 0
        started, reused = self._counter_values()
        self._warn_about_reuse(int(reused.sum()), int(started.sum()))
        if self._pending is not None:
            lacking = bool(np.any(self._uploaded <= started))
            if not (wait or lacking or self._pending.done()):
                return  # every world has its next state; the producers are still at work
            self._collect()
        # The first fill fills every slot: a slot must never hold a state no world had.
        first_fill = not self._uploaded.any()
        if wait and not first_fill:
            jobs = self._jobs(started, started + 1)
            if jobs:
                self._pending = self._producer.submit(jobs)
                self._collect()
        jobs = self._jobs(started, started + self.slots_per_world)
        if jobs:
            self._pending = self._producer.submit(jobs)
            if wait and first_fill:
                self._collect()

    def _warn_about_reuse(self, total: int, started: int) -> None:
        if total and not self._warned:
            self._warned = True
            n = self._physics.num_envs
            length = self._control_steps * n / max(started, 1)
            warnings.warn(
                f"{total} episodes started from an initial state their world had used before: "
                f"the worlds reset faster than the states were refilled. {n} worlds whose "
                f"episodes last {length:.1f} control steps on average need {n / length:.1f} "
                "initial states per control step (num_envs / episode control steps); one "
                "producer makes a few hundred to a thousand per second (docs/concepts/batch.md "
                "has measurements). Give more state_workers (with state_processes=True they "
                "scale with the host's cores), more slots_per_world or a smaller "
                "refill_interval (BatchEnvironment.initial_state_stats() counts reuses)",
                RuntimeWarning,
                stacklevel=5,
            )

    def _jobs(self, started: np.ndarray, end: np.ndarray) -> list[Job]:
        jobs = []
        for world in np.flatnonzero(np.maximum(self._requested, started) < end):
            first = max(int(self._requested[world]), int(started[world]))
            episodes = tuple(range(first, int(end[world])))
            jobs.append(Job(int(world), episodes, self._generator(int(world))))
            self._requested[world] = end[world]
        return jobs

    def _generator(self, world: int) -> np.random.RandomState | tuple:
        """What a job of `world` draws from: its generator for thread workers, the
        generator's latest state for worker processes."""
        if not self._producer.in_processes:
            return self.random_states[world]
        state = self._generator_states.get(world)
        return self.random_states[world].get_state() if state is None else state

    def _collect(self) -> None:
        """Waits for the pending jobs and uploads their states."""
        if self._pending is None:
            return
        pending, self._pending = self._pending, None
        begin = time.perf_counter()
        done = pending.done()
        results: list[ProducedStates] = pending.result(PRODUCER_TIMEOUT)
        if not done:
            self._stats = self._stats._replace(
                waits=self._stats.waits + 1,
                wait_seconds=self._stats.wait_seconds + time.perf_counter() - begin,
            )
        if results:
            self._upload(results)

    def _upload(self, results: list[ProducedStates]) -> None:
        k = self.slots_per_world
        first = results[0]
        self._allocate_values(first.values)
        self._write_shared(first.shared)
        for produced in results:
            if produced.shared.keys() != self._shared_written.keys():
                raise RuntimeError(
                    "initialize_episode changed different shared model fields in different "
                    f"workers: {sorted(produced.shared)} and {sorted(self._shared_written)}"
                )
            self._generator_states.update(produced.generators)
            self._stats = self._stats._replace(
                producer_cpu_seconds=self._stats.producer_cpu_seconds + produced.cpu_seconds
            )
            # One write per array for each share's states (rows are distinct: a job asks
            # for at most slots_per_world episodes of a world).
            rows = produced.worlds * k + produced.episodes % k
            self._slot_states[1][rows] = produced.state
            for name, (_, host) in self._slot_rows.items():
                host[rows] = produced.model_rows[name].reshape(rows.size, -1)
            for name, (_, host) in self._slot_values.items():
                host[rows] = produced.values[name].reshape(rows.size, -1)
            np.maximum.at(self._uploaded, produced.worlds, produced.episodes + 1)
        if self._on_warp:
            self._uploaded_on_device.assign(self._uploaded.astype(np.int32))
        else:
            self._uploaded_on_device[...] = self._uploaded
        if self._physics.is_cuda:
            for array, host in (
                self._slot_states,
                *self._slot_rows.values(),
                *self._slot_values.values(),
            ):
                array.assign(host)

    def _allocate_values(self, values: dict[str, np.ndarray]) -> None:
        """Makes the device arrays of the episode values, from the shapes of the first
        states' `values` (name -> (states, *value shape))."""
        if self._slot_values or not values:
            return
        arrays = self._physics.arrays
        n, k = self._physics.num_envs, self.slots_per_world
        for name, stacked in values.items():
            shape = stacked.shape[1:]
            size = int(np.prod(shape))
            floats = self._physics.float_dtype
            self._slot_values[name] = self._host_backed((n * k, size), floats)
            target, view = arrays.empty((n, size), floats)
            self._value_targets[name] = target
            self.values[name] = view.reshape((n, *shape))

    def _write_shared(self, shared: dict[str, np.ndarray]) -> None:
        if self._shared_written is not None:
            return
        self._shared_written = shared
        if not self._on_warp:
            for name, value in shared.items():
                self._physics.set_shared_model_field(name, value)
            return
        for name, value in shared.items():
            try:
                array = getattr(self._physics.warp_model, name)
            except AttributeError:
                continue  # a field MuJoCo Warp does not simulate
            host = array.numpy()
            array.assign(np.asarray(value).astype(host.dtype).reshape(host.shape))

    def close(self) -> None:
        """Stops the producers."""
        self._pending = None
        self._producer.close()


def _scalar(dtype):
    return getattr(dtype, "_wp_scalar_type_", dtype)
