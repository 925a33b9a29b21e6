"""BatchTask: the hooks of a `composer.Task` for every world at once, as array code.

A `BatchTask` wraps the CPU task it batches (`task`): the scene, observables, timing and
action spec come from there. What a batch needs for every world it defines itself, as code
on arrays of the batch's namespace `physics.xp` (NumPy on Warp's CPU device, torch on CUDA;
see `composer.batch.arrays`), written once against the Python array API standard: the
reward, discount and termination of every world, and the controls an action sets. Such code
runs where the worlds are, without a copy to the host.

Initial states come one of two ways, named by `InitialStateSource` and read from
`BatchTask.initial_state_source`:
- **`CPU_TASK` (the default).** The CPU task's own `initialize_episode` hooks (task and
  entities) run for each world on host physics, off the caller's thread, with that world's
  random generator (`composer.batch.initial_states`); a reset applies the prepared state
  to the worlds being reset on the device. The distribution is the CPU task's by
  construction. What the hooks draw besides the physics state (a desired order, a target
  id) reaches the batched hooks through `episode_values`.
- **`ARRAY_CODE`.** A subclass that overrides `initialize_episode(physics, mask)` sets the
  state of the worlds of `mask` itself, on the device; no CPU initializer runs.

The source follows from the class (an override of `initialize_episode` is array code), so
that the two can never disagree: a flag set apart from the method could name array code
with no method to run, or a method that would never be called.

`register(task_type, batch_task_type)` says which `BatchTask` batches a task class;
`for_task(task)` looks it up along the task's class hierarchy.
"""

import enum
from collections.abc import Callable
from typing import Any

import numpy as np

import composer

__all__ = ["BatchTask", "InitialStateSource", "for_task", "register"]

_REGISTRY: dict[type, type["BatchTask"]] = {}


class InitialStateSource(enum.Enum):
    """Where a `BatchTask`'s worlds get the initial state of each episode (see the module
    docstring)."""

    #: The CPU task's initializers, run on host physics by the initial-state producers.
    CPU_TASK = "cpu_task"
    #: The `BatchTask`'s own `initialize_episode(physics, mask)`, array code on the device.
    ARRAY_CODE = "array_code"


class BatchTask:
    """The batched hooks of `task`; subclasses implement `get_reward`.

    Every hook gets the `BatchPhysics` of all worlds and returns arrays of its namespace
    `physics.xp` with a leading num_envs axis; none may copy to the host (no `float()`,
    `.item()`, `bool()` or NumPy conversion of a device array).

    Initial states come from the CPU task's initializers unless the subclass overrides
    `initialize_episode`; `initial_state_source` says which.

    Attributes:
      batched_model_fields: MjModel fields the task's initializers write per world (for
        instance 'site_pos' for a target site placed at every reset); the environment gives
        each world its own row of these, and of the fields it finds the task's episodes
        vary (`composer.batch.variations`).
      episode_values: the current episode's values of every world (see
        `episode_values`), by name, arrays of shape (num_envs, *value shape), set by the
        environment; empty until the first reset.
    """

    batched_model_fields: tuple[str, ...] = ()

    def __init__(self, task: composer.Task):
        if not isinstance(task, composer.Task):
            raise TypeError(f"task: expected a composer.Task, got {type(task).__name__}")
        self.task = task
        self.episode_values: dict[str, Any] = {}

    @property
    def initial_state_source(self) -> InitialStateSource:
        """Where this task's worlds get their initial states: `ARRAY_CODE` when its class
        overrides `initialize_episode`, else `CPU_TASK`.

        Returns:
          An `InitialStateSource`.
        """
        if type(self).initialize_episode is BatchTask.initialize_episode:
            return InitialStateSource.CPU_TASK
        return InitialStateSource.ARRAY_CODE

    def after_compile(self, physics) -> None:
        """Runs once the worlds exist on the device (nothing by default): bind here."""

    def initial_values(self) -> dict[str, np.ndarray]:
        """Values of the CPU task's current episode that the batched hooks read, by name.

        Called on a state producer right after the CPU task's `initialize_episode` hooks;
        each world's values for its current episode are then in `self.episode_values`
        (in the batch's float dtype). None by default.

        Returns:
          A dict of arrays of a fixed shape each (one episode of one world).
        """
        return {}

    def initialize_episode(self, physics, mask) -> None:
        """Sets the initial state of the worlds of `mask`, bool (num_envs,), on the device.

        Called only for `InitialStateSource.ARRAY_CODE`, which overriding this method
        chooses: the environment first resets those worlds to the model's initial state
        (`mj_resetData`: qpos0, zero velocities, time 0), calls this, and runs forward on
        them after. Not overridden, the method is never called: each world starts from a
        state its CPU task's initializers prepared (`InitialStateSource.CPU_TASK`).
        """

    def observable_readers(self, physics) -> dict[str, Callable[[], Any]]:
        """Batched readers for the task's observables that have no generic one, by key.

        Each reader returns the observable's value in every world, (num_envs, *shape).
        None by default.
        """
        return {}

    def before_step(self, physics, action) -> None:
        """Applies the actions, shape (num_envs, nu), of the batch's float dtype (float64
        on the CPU batch, float32 on MuJoCo Warp); by default sets every world's
        controls."""
        physics.data.ctrl[...] = action

    def get_reward(self, physics) -> Any:
        """Returns every world's reward, shape (num_envs,)."""
        raise NotImplementedError(f"{type(self).__name__} must implement get_reward")

    def get_discount(self, physics) -> Any:
        """Returns every world's discount, shape (num_envs,) (1.0 by default)."""
        xp = physics.xp
        floats = getattr(xp, physics.float_dtype.name)
        return xp.ones(physics.num_envs, dtype=floats, device=physics.arrays.xp_device)

    def should_terminate_episode(self, physics) -> Any:
        """Returns which worlds' episodes end after this step, bool (num_envs,) (none)."""
        xp = physics.xp
        return xp.zeros(physics.num_envs, dtype=xp.bool, device=physics.arrays.xp_device)


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
