"""Episode starts of the batched suite: the CPU task's own `initialize_episode`, off the
caller's thread.

A `SuiteStateMaker` runs a suite task's `initialize_episode` inside its physics'
`reset_context` with one world's generator, as dm_control's `control.Environment.reset`
does, and records what the world needs to start that episode (an
`composer.batch.initial_states.InitialState`): the integration state (`mj_getState`, warm
start included), the world's row of each model field the task's episodes vary (reacher's
target, finger's target site, ...), and the batched task's `initial_values`. It is the
maker of a `composer.batch.initial_states.StateProducer`, whose worker thread fills the
worlds' `composer.batch.state_slots.StateSlots` ahead of their episodes, as in the batch
of composer tasks.

`varied_model_fields` finds the model fields to give a row per world, once, from two probe
episodes; `seeded_model_fields` those a task draws from its seed when it builds its model
(lqr's), whose worlds then each start on their own CPU model. A field an episode changes
the same way every time (a flag MuJoCo updates) is written once for every world; one that
changes differently later is refused rather than shared silently.
"""

from collections.abc import Sequence
from typing import Any, NamedTuple

import mujoco
import numpy as np

from composer.batch.initial_states import InitialState, Job, ProducedStates, run_jobs
from composer.batch.mujoco_batch import batch_model_fields
from composer.batch.variations import PROBE_SEEDS, model_arrays
from suite_batch.tasks import SuiteBatchTask

__all__ = ["StartHost", "SuiteStateMaker", "seeded_model_fields", "varied_model_fields"]

_STATE = mujoco.mjtState.mjSTATE_INTEGRATION


def _start(task, host, random_state: np.random.RandomState) -> None:
    """dm_control's episode start: the task's `initialize_episode` in `reset_context`."""
    # The suite's tasks draw from the generator they keep as `_random`.
    task._random = random_state
    with host.reset_context():
        task.initialize_episode(host)


def varied_model_fields(task, host) -> tuple[str, ...]:
    """The model fields that `task`'s episode starts set differently per episode.

    Runs two probe episodes (generators seeded `PROBE_SEEDS`, none of a world's) on `host`,
    then puts its model back as compiled (its data is reset by every start).

    Returns:
      The field names, sorted.

    Raises:
      NotImplementedError: for a varied field that `mujoco.batch` cannot give a row per
        world, or that holds integers, naming the task and the field.
    """
    model = host.model.ptr
    compiled = model_arrays(model)
    probes = []
    try:
        for seed in PROBE_SEEDS:
            _start(task, host, np.random.RandomState(seed))
            probes.append({name: getattr(model, name).copy() for name in compiled})
    finally:
        for name, value in compiled.items():
            getattr(model, name)[...] = value
    first, second = probes
    varied = sorted(
        name for name in first if not np.array_equal(first[name], second[name], equal_nan=True)
    )
    _check_rows_possible(
        f"{type(task).__qualname__}.initialize_episode", "changes", varied, compiled
    )
    return tuple(varied)


def seeded_model_fields(model: mujoco.MjModel, probe: mujoco.MjModel, name: str) -> tuple[str, ...]:
    """The model fields that differ between two compilations of one task's model with
    different seeds (`model`, `probe`): the fields a task draws from its seed when it builds
    its model (lqr's joint stiffnesses), sorted; none for most tasks.

    Raises:
      NotImplementedError: when the two differ in structure (an array's shape), or in a
        field the batch cannot give each world, naming the task (`name`) and the field.
    """
    ours, theirs = model_arrays(model), model_arrays(probe)
    differing = []
    for field, value in ours.items():
        other = theirs[field]
        if value.shape != other.shape:
            raise NotImplementedError(
                f"{name}: its model's structure depends on the seed (model field {field!r} "
                f"has shape {value.shape} for one seed and {other.shape} for another); a "
                "batch compiles one model"
            )
        if not np.array_equal(value, other, equal_nan=True):
            differing.append(field)
    _check_rows_possible(name, "builds its model with", differing, ours)
    return tuple(sorted(differing))


def _check_rows_possible(
    name: str, what: str, fields: Sequence[str], values: dict[str, np.ndarray]
) -> None:
    """Refuses fields that `mujoco.batch` cannot give a row per world, or that hold
    integers (a world's row holds floats), naming the task and the field."""
    expandable = batch_model_fields()
    for field in fields:
        if field not in expandable:
            raise NotImplementedError(
                f"{name} {what} model field {field!r} per episode or seed, which "
                "mujoco.batch cannot give each world its own row of"
            )
        if not np.issubdtype(values[field].dtype, np.floating):
            raise NotImplementedError(
                f"{name} {what} model field {field!r} per episode or seed, but it holds "
                "integers and a world's row can only hold floats"
            )


class StartHost(NamedTuple):
    """A CPU suite task and its physics, on which episode starts run."""

    task: Any
    physics: Any


class _Starts:
    """The starts of one `StartHost`: its compiled varied rows and shared fields."""

    def __init__(self, host: StartHost, model_fields: Sequence[str]):
        self.host = host
        model = host.physics.model.ptr
        self.compiled_rows = {name: getattr(model, name).copy() for name in model_fields}
        self.reference: dict[str, np.ndarray] | None = model_arrays(model)
        self.shared: dict[str, np.ndarray] | None = None


class SuiteStateMaker:
    """Makes the episode starts of a suite task on CPU physics.

    Args:
      hosts: one `StartHost` for every world, or one per world (the suite tasks whose model
        is drawn from the seed, such as lqr's: world i's starts then run on its own model).
        The maker owns them from now on: their varied model fields and their data change
        at every start.
      batch_task: the `SuiteBatchTask` whose `initial_values` each start records.
      model_fields: the model fields that get a row per world (those of
        `varied_model_fields`, and those drawn from the seed), restored to the host's
        compiled values before every start (as a fresh environment has them) and recorded
        after.

    Raises:
      RuntimeError (from a call): when a start changed a model field outside `model_fields`
        differently from the host's first start, naming it.
    """

    def __init__(
        self,
        hosts: Sequence[StartHost],
        batch_task: SuiteBatchTask,
        model_fields: Sequence[str] = (),
    ):
        self._model_fields = tuple(model_fields)
        self._starts = [_Starts(host, self._model_fields) for host in hosts]
        self._batch_task = batch_task
        self._scratch_generator = np.random.RandomState()

    def __call__(self, world: int, random_state: np.random.RandomState) -> InitialState:
        """Starts an episode of `world` with `random_state` and records what the world
        needs for it."""
        starts = self._starts[world if len(self._starts) > 1 else 0]
        task, physics = starts.host
        model, data = physics.model.ptr, physics.data.ptr
        for name, value in starts.compiled_rows.items():
            getattr(model, name)[...] = value
        _start(task, physics, random_state)
        state = np.empty(mujoco.mj_stateSize(model, _STATE))
        mujoco.mj_getState(model, data, state, _STATE)
        _check_shared_fields(starts)
        return InitialState(
            state=state,
            model_rows={name: getattr(model, name).copy() for name in self._model_fields},
            values={
                name: np.asarray(value, dtype=np.float64)
                for name, value in self._batch_task.initial_values().items()
            },
            shared=starts.shared,
        )

    def run(self, jobs: Sequence[Job]) -> ProducedStates:
        """The starts of every episode of `jobs`, in order, stacked."""
        return run_jobs(self, jobs, self._scratch_generator)


def _check_shared_fields(starts: _Starts) -> None:
    model = starts.host.physics.model.ptr
    if starts.shared is None:
        # Every model array, compared once per host (textures make it milliseconds): the
        # fields the first start changed are then every world's, and checked at each start.
        starts.shared = {
            name: getattr(model, name).copy()
            for name, value in starts.reference.items()
            if name not in starts.compiled_rows
            and not np.array_equal(getattr(model, name), value, equal_nan=True)
        }
        starts.reference = None
    for name, value in starts.shared.items():
        if not np.array_equal(getattr(model, name), value, equal_nan=True):
            raise RuntimeError(
                f"{type(starts.host.task).__qualname__}.initialize_episode changed model "
                f"field {name!r} differently from its first episode; every world shares it "
                "(the probe episodes had not varied it)"
            )
