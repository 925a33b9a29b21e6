"""Initial states of a batch's episodes, drawn by the CPU task's own initializers off the
caller's thread.

A `StateMaker` runs the CPU task's `initialize_episode_mjcf` hooks and patches their changes
into a host `mjcf.Physics` (`composer.batch.variations`), then its `initialize_episode`
hooks (task and entities) inside its `reset_context`, with one world's random generator, as
a CPU environment's reset does, and records what a world needs to start that episode: the
physics state (`mjSTATE_INTEGRATION`), the rows of the batched model fields, and the
`BatchTask`'s `initial_values`. The distribution of initial states (and of the model's
variations) is therefore the CPU task's by construction.

A `StateProducer` runs makers on worker threads (one maker each) or worker processes (each
builds its own task from a picklable `task_factory`). A job is one world's next episodes,
drawn in order from that world's generator, which travels with the job and comes back
advanced (as its state), so a seed fixes every world's episodes whatever the number of
workers. A worker's share of jobs comes back as one `ProducedStates`, a few stacked arrays:
what the caller's process receives from a worker process is a handful of buffers, whatever
the number of states (unpickling a state and a `RandomState` per episode cost the stepping
process about a third of a millisecond per state, measured on the development machine).
"""

import concurrent.futures
import multiprocessing
import threading
import time
from collections.abc import Callable, Sequence
from typing import NamedTuple

import mujoco
import numpy as np

import composer
import mjcf
from composer.batch.variations import EpisodeModel, model_arrays
from composer.hooks import EnvironmentHooks

__all__ = [
    "InitialState",
    "Job",
    "ProducedStates",
    "StateMaker",
    "StateProducer",
    "Submitted",
    "run_jobs",
]

_STATE_SPEC = mujoco.mjtState.mjSTATE_INTEGRATION


class InitialState(NamedTuple):
    """What one world needs to start one episode.

    Attributes:
      state: the `mj_getState(mjSTATE_INTEGRATION)` vector, float64.
      model_rows: the world's row of each batched model field, by field name.
      values: the `BatchTask.initial_values` of the episode, by name.
      shared: model fields outside the batched ones that the initializers changed the same
        way for every world (such as the flag MuJoCo clears when a site moves off its
        body's frame), with their values.
    """

    state: np.ndarray
    model_rows: dict[str, np.ndarray]
    values: dict[str, np.ndarray]
    shared: dict[str, np.ndarray]


class Job(NamedTuple):
    """Make the initial states of `episodes` of world `world` from `random_state`: the
    world's `np.random.RandomState`, which a worker thread draws from in place, or its
    `get_state()`, from which a worker process draws, sending back the state after
    (`ProducedStates.generators`). A generator's state pickles in about 10 µs, where a
    `RandomState` takes a quarter of a millisecond, and NumPy's `get_state` and `set_state`
    about 0.1 ms each (measured on the development machine), so the stepping process
    converts a world's generator only on its first job, and sets it only when asked
    (`StateSlots.sync_generators`)."""

    world: int
    episodes: tuple[int, ...]
    random_state: np.random.RandomState | tuple


class ProducedStates(NamedTuple):
    """The initial states of some jobs, one row per state, in the jobs' order.

    Attributes:
      worlds: int64 (states,): the world of each state.
      episodes: int64 (states,): the episode of its world each state starts.
      state: float64 (states, state size): the `mj_getState(mjSTATE_INTEGRATION)` vectors.
      model_rows: field name -> (states, *a world's row shape), the field's dtype.
      values: name -> float64 (states, *value shape): the `BatchTask.initial_values`.
      shared: as `InitialState.shared`, the same for every state of one maker.
      generators: per job that came with a generator's state (not a `RandomState`), its
        world and its generator's state after drawing the job's episodes.
      cpu_seconds: the CPU time the worker's thread spent making them.
    """

    worlds: np.ndarray
    episodes: np.ndarray
    state: np.ndarray
    model_rows: dict[str, np.ndarray]
    values: dict[str, np.ndarray]
    shared: dict[str, np.ndarray]
    generators: list[tuple[int, tuple]]
    cpu_seconds: float


class StateMaker:
    """Makes initial states with the CPU task of `batch_task` on the host `physics`.

    Args:
      batch_task: the `BatchTask`; its `task` is the CPU task whose hooks run, and its
        `episode_values` are recorded.
      physics: the host `mjcf.Physics` of that task, after its `after_compile` hooks ran.
      model_fields: the batched model fields whose rows are recorded (and restored to the
        compiled values before every episode, as a fresh world has them).
      host_fields: model fields that vary per world but that the device does not have:
        restored before every episode like `model_fields`, not recorded.
      episode_model: the `EpisodeModel` of `physics` (made here, counting MJCF changes from
        now, if None).

    Raises:
      NotImplementedError (from a call): for an MJCF change that needs a recompile (see
        `composer.batch.variations`).
      RuntimeError (from a call): if `initialize_episode` changed the MJCF model, or changed
        a model field outside `model_fields` differently from the first episode.
    """

    def __init__(
        self,
        batch_task,
        physics: mjcf.Physics,
        model_fields: Sequence[str],
        *,
        host_fields: Sequence[str] = (),
        episode_model: EpisodeModel | None = None,
    ):
        self._batch_task = batch_task
        self._hooks = EnvironmentHooks(batch_task.task)
        self._physics = physics
        root = batch_task.task.root_entity.mjcf_model
        self._episode_model = episode_model or EpisodeModel(self._hooks, physics, root)
        model = physics.model.ptr
        self._model_fields = tuple(model_fields)
        self._pristine = {
            name: getattr(model, name).copy() for name in (*model_fields, *host_fields)
        }
        self._reference = model_arrays(model)
        self._shared: dict[str, np.ndarray] | None = None
        self._scratch_generator: np.random.RandomState | None = None

    def __call__(self, random_state: np.random.RandomState) -> InitialState:
        """Runs the initializers with `random_state` and records the state they set."""
        physics = self._physics
        model, data = physics.model.ptr, physics.data.ptr
        task = self._batch_task.task
        root = task.root_entity.mjcf_model
        for name, value in self._pristine.items():
            getattr(model, name)[...] = value
        self._episode_model(random_state)
        count = root.modification_count
        with physics.reset_context():
            self._hooks.initialize_episode(physics, random_state)
        if root.modification_count != count:
            raise RuntimeError(
                f"{type(task).__name__}.initialize_episode changed the MJCF model, which a "
                "CPU environment compiles at the next reset; a batch does not (change it in "
                "initialize_episode_mjcf)"
            )
        state = np.empty(mujoco.mj_stateSize(model, _STATE_SPEC))
        mujoco.mj_getState(model, data, state, _STATE_SPEC)
        if self._shared is None:
            # Comparing every model array costs about a millisecond: once per maker.
            self._shared = {
                name: getattr(model, name).copy()
                for name, value in self._reference.items()
                if name not in self._pristine
                and not np.array_equal(getattr(model, name), value, equal_nan=True)
            }
        for name, value in self._shared.items():
            if not np.array_equal(getattr(model, name), value, equal_nan=True):
                raise RuntimeError(
                    f"the episode's initializers changed model field {name!r} differently per "
                    f"world, but all worlds share it; declare it in batched_model_fields="
                    f"({name!r},) to give each world its own"
                )
        return InitialState(
            state=state,
            model_rows={name: getattr(model, name).copy() for name in self._model_fields},
            values={
                name: np.asarray(value, dtype=np.float64)
                for name, value in self._batch_task.initial_values().items()
            },
            shared=self._shared,
        )

    def run(self, jobs: Sequence[Job]) -> ProducedStates:
        """The states of every episode of `jobs`, in order, stacked (at least one state)."""
        if self._scratch_generator is None:
            self._scratch_generator = np.random.RandomState()
        return run_jobs(self._make, jobs, self._scratch_generator)

    def _make(self, world: int, random_state: np.random.RandomState) -> InitialState:
        # One maker serves every world: they share its task and model.
        return self(random_state)


def run_jobs(
    make_state: Callable[[int, np.random.RandomState], InitialState],
    jobs: Sequence[Job],
    scratch_generator: np.random.RandomState,
) -> ProducedStates:
    """The states `make_state(world, random_state)` makes for every episode of `jobs`, in
    order, stacked (at least one state): what a producer's worker runs, whatever makes one
    state.

    A job that carries a generator's state (from a worker process) is drawn from
    `scratch_generator`, set to it, and its state after comes back in `generators`.
    """
    begin = time.thread_time()
    worlds, episodes, states, generators = [], [], [], []
    for job in jobs:
        random_state = job.random_state
        if not isinstance(random_state, np.random.RandomState):
            random_state = scratch_generator
            random_state.set_state(job.random_state)
        for episode in job.episodes:
            states.append(make_state(job.world, random_state))
            worlds.append(job.world)
            episodes.append(episode)
        if random_state is not job.random_state:
            generators.append((job.world, random_state.get_state()))
    return ProducedStates(
        worlds=np.asarray(worlds, np.int64),
        episodes=np.asarray(episodes, np.int64),
        state=np.stack([state.state for state in states]),
        model_rows=_stacked([state.model_rows for state in states]),
        values=_stacked([state.values for state in states]),
        shared=states[0].shared,
        generators=generators,
        cpu_seconds=time.thread_time() - begin,
    )


def _stacked(rows: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """name -> (len(rows), *shape): each row's arrays stacked."""
    return {name: np.stack([row[name] for row in rows]) for name in rows[0]}


def build_maker(
    task_factory: Callable[[], composer.Task],
    batch_task_type: type,
    model_fields: Sequence[str],
    host_fields: Sequence[str] = (),
) -> StateMaker:
    """A `StateMaker` over a new task from `task_factory`, compiled on its own physics."""
    task = task_factory()
    physics = mjcf.Physics.from_mjcf_model(task.root_entity.mjcf_model)
    with physics.reset_context():
        EnvironmentHooks(task).after_compile(physics, np.random.RandomState(0))
    return StateMaker(batch_task_type(task), physics, model_fields, host_fields=host_fields)


# The maker of a worker process (one per process).
_process_maker: StateMaker | None = None


def _start_process(task_factory, batch_task_type, model_fields, host_fields) -> None:
    global _process_maker
    _process_maker = build_maker(task_factory, batch_task_type, model_fields, host_fields)


def _run_in_process(jobs: list[Job]) -> ProducedStates:
    return _process_maker.run(jobs)


class StateProducer:
    """Runs jobs on `workers` threads or processes, off the caller's thread.

    Args:
      maker: the `StateMaker` of the batch's own task; used by a single thread worker when
        there is no `task_factory`.
      workers: the number of workers (>= 1).
      processes: run workers in processes (each builds its task with `task_factory`; their
        throughput scales with the host's cores) instead of threads.
      task_factory: a picklable callable returning a new CPU task of the same kind; needed
        for more than one worker or for processes.
      batch_task_type, model_fields, host_fields: what each worker's `StateMaker` is built
        with.

    Raises:
      ValueError: for more than one worker, or processes, without a `task_factory`.
    """

    def __init__(
        self,
        maker: StateMaker,
        *,
        workers: int = 1,
        processes: bool = False,
        task_factory: Callable[[], composer.Task] | None = None,
        batch_task_type: type | None = None,
        model_fields: Sequence[str] = (),
        host_fields: Sequence[str] = (),
    ):
        if task_factory is None and (workers > 1 or processes):
            raise ValueError(
                f"state_workers={workers}, processes={processes}: more than one producer, or "
                "producers in processes, need task_factory (a picklable callable returning "
                "the CPU task) to build their own task"
            )
        self.workers = workers
        #: Whether the workers are processes (jobs then carry generator states).
        self.in_processes = processes
        if processes:
            self._pool = concurrent.futures.ProcessPoolExecutor(
                workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_start_process,
                initargs=(task_factory, batch_task_type, tuple(model_fields), tuple(host_fields)),
            )
            self._run = _run_in_process
        else:
            makers = [maker]
            if task_factory is not None:
                makers = [
                    build_maker(task_factory, batch_task_type, model_fields, host_fields)
                    for _ in range(workers)
                ]
            free = list(makers)
            lock = threading.Lock()

            def run(jobs: list[Job]) -> ProducedStates:
                with lock:
                    own = free.pop()
                try:
                    return own.run(jobs)
                finally:
                    with lock:
                        free.append(own)

            self._pool = concurrent.futures.ThreadPoolExecutor(
                workers, thread_name_prefix="composer-initial-states"
            )
            self._run = run

    def submit(self, jobs: Sequence[Job]) -> "Submitted":
        """Starts `jobs` on the workers; the `Submitted`'s result is one `ProducedStates`
        per worker's share.

        Jobs are split into one share per worker; a world's episodes stay in one job.
        """
        shares = [list(jobs[i :: self.workers]) for i in range(self.workers)]
        futures = [self._pool.submit(self._run, share) for share in shares if share]
        return Submitted(futures)

    def close(self) -> None:
        """Stops the workers (pending jobs are cancelled)."""
        self._pool.shutdown(wait=True, cancel_futures=True)


class Submitted:
    """The shares of one `StateProducer.submit`, in flight on the workers."""

    def __init__(self, futures: list):
        self._futures = futures

    def done(self) -> bool:
        """Whether every share has finished."""
        return all(future.done() for future in self._futures)

    def result(self, timeout: float) -> list[ProducedStates]:
        """Every share's states, waiting at most `timeout` seconds in all.

        Raises:
          TimeoutError: when the workers are not done by then; a worker's own error.
        """
        concurrent.futures.wait(self._futures, timeout)
        return [future.result(timeout=0) for future in self._futures]
