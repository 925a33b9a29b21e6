"""BatchTask: the per-batch hooks of a `composer.Task`, acting on the worlds they are given.

A `BatchTask` wraps the CPU task it batches (`task`): the scene, observables, timing and
action spec come from there. What a batch needs in array form it defines itself: the reward,
discount and termination of every world, and the controls an action sets. Initialising an
episode defaults to running the CPU task's own `initialize_episode` hooks (task and
entities) for each world being reset, on the host `mjcf.Physics`, with that world's random
generator, and copying the resulting state into the world: the initial-state distribution is
the CPU task's by construction. Subclasses may replace it with array code.

`register(task_type, batch_task_type)` says which `BatchTask` batches a task class;
`for_task(task)` looks it up along the task's class hierarchy.
"""

from collections.abc import Sequence

import mujoco
import numpy as np

import composer
from composer.hooks import EnvironmentHooks

__all__ = ["BatchTask", "for_task", "register"]

_STATE_SPEC = mujoco.mjtState.mjSTATE_INTEGRATION

_REGISTRY: dict[type, type["BatchTask"]] = {}


class BatchTask:
    """The batched hooks of `task`; subclasses implement `get_reward`.

    Every hook gets the `BatchPhysics` of all worlds. Hooks that act on some worlds take
    their ids (`env_ids`, an int array) and one `np.random.RandomState` per id; hooks that
    return per-world values return arrays of shape (num_envs,).

    Attributes:
      batched_model_fields: MjModel fields the task writes per world (for instance
        'site_pos' for a target site placed at every reset); the environment gives each
        world its own row of these.
    """

    batched_model_fields: tuple[str, ...] = ()

    def __init__(self, task: composer.Task):
        if not isinstance(task, composer.Task):
            raise TypeError(f"task: expected a composer.Task, got {type(task).__name__}")
        self.task = task
        self._hooks = EnvironmentHooks(task)
        self._pristine: dict[str, np.ndarray] = {}

    def after_compile(self, physics) -> None:
        """Runs once the worlds exist on the device (nothing by default)."""
        model = physics.mj_model
        self._pristine = {
            name: getattr(model, name).copy() for name in physics.batched_model_fields
        }

    def initialize_episode(
        self, physics, env_ids: np.ndarray, random_states: Sequence[np.random.RandomState]
    ) -> None:
        """Sets the initial state of worlds `env_ids`; the environment then runs forward.

        By default runs the CPU task's `initialize_episode` hooks once per world on the host
        physics (inside its `reset_context`) and copies the state (`mjSTATE_INTEGRATION`)
        and the rows of `physics.batched_model_fields` into that world.

        Raises:
          RuntimeError: if a hook changed the MJCF model (that needs a recompile) or a
            model field not listed in `batched_model_fields`.
        """
        host = physics.host
        model, data = host.model.ptr, host.data.ptr
        root = self.task.root_entity.mjcf_model
        count = root.modification_count
        states = np.empty((len(env_ids), mujoco.mj_stateSize(model, _STATE_SPEC)))
        rows = {name: [] for name in self._pristine}
        reference = _model_arrays(model)
        shared: dict[str, np.ndarray] = {}
        for k, random_state in enumerate(random_states):
            for name, value in self._pristine.items():
                getattr(model, name)[...] = value
            with host.reset_context():
                self._hooks.initialize_episode(host, random_state)
            if root.modification_count != count:
                raise RuntimeError(
                    f"{type(self.task).__name__}.initialize_episode changed the MJCF model; a "
                    "batch compiles its model once (MJCF variations are refused)"
                )
            mujoco.mj_getState(model, data, states[k], _STATE_SPEC)
            for name in rows:
                rows[name].append(getattr(model, name).copy())
            if k == 0:
                # Comparing every model array costs about a millisecond: once per call.
                shared = _changed_shared_fields(model, reference, self._pristine)
            _check_same_for_every_world(model, shared)
        physics.set_state(env_ids, states, _STATE_SPEC)
        for name, values in rows.items():
            physics.field("model", name).write(env_ids, slice(None), np.stack(values))
        for name, value in shared.items():
            physics.field("model", name).write_shared(value)

    def before_step(self, physics, action: np.ndarray) -> None:
        """Applies the actions, shape (num_envs, nu); by default sets every world's controls."""
        physics.field("data", "ctrl").write(np.arange(physics.num_envs), slice(None), action)

    def get_reward(self, physics) -> np.ndarray:
        """Returns every world's reward, shape (num_envs,)."""
        raise NotImplementedError(f"{type(self).__name__} must implement get_reward")

    def get_discount(self, physics) -> np.ndarray:
        """Returns every world's discount, shape (num_envs,) (1.0 by default)."""
        return np.ones(physics.num_envs)

    def should_terminate_episode(self, physics) -> np.ndarray:
        """Returns which worlds' episodes end after this step, bool (num_envs,) (none)."""
        return np.zeros(physics.num_envs, dtype=bool)


def _model_arrays(model: mujoco.MjModel) -> dict[str, np.ndarray]:
    return {
        name: value.copy()
        for name in dir(model)
        if not name.startswith("_") and isinstance(value := getattr(model, name), np.ndarray)
    }


def _changed_shared_fields(model, reference: dict, batched: dict) -> dict[str, np.ndarray]:
    """The model fields outside `batched` that differ from `reference`, with their values."""
    return {
        name: getattr(model, name).copy()
        for name, value in reference.items()
        if name not in batched and not np.array_equal(getattr(model, name), value, equal_nan=True)
    }


def _check_same_for_every_world(model, shared: dict) -> None:
    """Raises if a shared model field got another value than for the first world.

    A shared field written the same way for every world (such as the flag MuJoCo clears
    when a site is moved off its body's frame) is written once for all of them.
    """
    for name, value in shared.items():
        if not np.array_equal(getattr(model, name), value, equal_nan=True):
            raise RuntimeError(
                f"initialize_episode changed model field {name!r} differently per world, but "
                f"all worlds share it; declare it in batched_model_fields=({name!r},) to give "
                "each world its own"
            )


def register(task_type: type, batch_task_type: type[BatchTask]) -> None:
    """Makes `batch_task_type(task)` the batched version of tasks of `task_type`."""
    if not (isinstance(batch_task_type, type) and issubclass(batch_task_type, BatchTask)):
        raise TypeError(f"batch_task_type: expected a BatchTask subclass, got {batch_task_type!r}")
    _REGISTRY[task_type] = batch_task_type


def for_task(task) -> BatchTask:
    """Returns the batched version of `task` (itself when it is a `BatchTask`).

    Raises:
      TypeError: if no `BatchTask` is registered for the task's class or a base class.
    """
    if isinstance(task, BatchTask):
        return task
    for cls in type(task).__mro__:
        batch_task_type = _REGISTRY.get(cls)
        if batch_task_type is not None:
            return batch_task_type(task)
    raise TypeError(
        f"task: no batched version of {type(task).__name__} is registered; subclass "
        "composer.batch.BatchTask and call composer.batch.register (the manipulation tasks "
        "register theirs in manipulation.batch)"
    )
