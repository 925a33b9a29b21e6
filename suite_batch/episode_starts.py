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
episodes. A field an episode changes the same way every time (a flag MuJoCo updates) is
written once for every world; one that changes differently later is refused rather than
shared silently.
"""

from collections.abc import Sequence

import mujoco
import numpy as np

from composer.batch.initial_states import InitialState, Job, ProducedStates, run_jobs
from composer.batch.mujoco_batch import batch_model_fields
from composer.batch.variations import PROBE_SEEDS, model_arrays
from suite_batch.tasks import SuiteBatchTask

__all__ = ["SuiteStateMaker", "varied_model_fields"]

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
    expandable = batch_model_fields()
    name = type(task).__qualname__
    for field in varied:
        if field not in expandable:
            raise NotImplementedError(
                f"{name}.initialize_episode changes model field {field!r} per episode, which "
                "mujoco.batch cannot give each world its own row of"
            )
        if not np.issubdtype(compiled[field].dtype, np.floating):
            raise NotImplementedError(
                f"{name}.initialize_episode changes model field {field!r} per episode, but it "
                "holds integers and a world's row can only hold floats"
            )
    return tuple(varied)


class SuiteStateMaker:
    """Makes the episode starts of `task` on its CPU physics `host`.

    Args:
      task: the CPU suite task (a `dm_control.suite.base.Task`).
      host: its physics (dm_control's `Physics`, this project's engine); the maker owns it
        from now on: its model's varied fields and its data change at every start.
      batch_task: the `SuiteBatchTask` whose `initial_values` each start records.
      model_fields: the fields of `varied_model_fields`, restored to their compiled values
        before every start (as a fresh environment has them) and recorded after.

    Raises:
      RuntimeError (from a call): when a start changed a model field outside `model_fields`
        differently from the first start, naming it.
    """

    def __init__(self, task, host, batch_task: SuiteBatchTask, model_fields: Sequence[str] = ()):
        self._task, self._host, self._batch_task = task, host, batch_task
        model = host.model.ptr
        self._model_fields = tuple(model_fields)
        self._compiled_rows = {name: getattr(model, name).copy() for name in self._model_fields}
        self._reference = model_arrays(model)
        self._shared: dict[str, np.ndarray] | None = None
        self._scratch_generator = np.random.RandomState()

    def __call__(self, random_state: np.random.RandomState) -> InitialState:
        """Starts an episode with `random_state` and records what a world needs for it."""
        host = self._host
        model, data = host.model.ptr, host.data.ptr
        for name, value in self._compiled_rows.items():
            getattr(model, name)[...] = value
        _start(self._task, host, random_state)
        state = np.empty(mujoco.mj_stateSize(model, _STATE))
        mujoco.mj_getState(model, data, state, _STATE)
        self._check_shared_fields(model)
        return InitialState(
            state=state,
            model_rows={name: getattr(model, name).copy() for name in self._model_fields},
            values={
                name: np.asarray(value, dtype=np.float64)
                for name, value in self._batch_task.initial_values().items()
            },
            shared=self._shared,
        )

    def _check_shared_fields(self, model: mujoco.MjModel) -> None:
        if self._shared is None:
            # Every model array, compared once (textures make it milliseconds): the fields
            # the first start changed are then every world's, and checked at each start.
            self._shared = {
                name: getattr(model, name).copy()
                for name, value in self._reference.items()
                if name not in self._compiled_rows
                and not np.array_equal(getattr(model, name), value, equal_nan=True)
            }
            self._reference = None
        for name, value in self._shared.items():
            if not np.array_equal(getattr(model, name), value, equal_nan=True):
                raise RuntimeError(
                    f"{type(self._task).__qualname__}.initialize_episode changed model field "
                    f"{name!r} differently from its first episode; every world shares it "
                    "(the probe episodes had not varied it)"
                )

    def run(self, jobs: Sequence[Job]) -> ProducedStates:
        """The starts of every episode of `jobs`, in order, stacked."""
        return run_jobs(self, jobs, self._scratch_generator)
