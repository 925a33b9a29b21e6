"""Suite tasks as array code: `SuiteBatchTask` and the registry of their batched versions.

A `SuiteBatchTask` computes, for every world at once, what one dm_control suite task
computes for one physics: its observation, reward and termination, from the batch's
(num_envs, ...) views of MuJoCo's data, float64, operation for operation as the task's own
Python, so that world i equals the CPU task's episode bit for bit. Episode starts are the
CPU task's own `initialize_episode` (see `suite_batch.environment`).
"""

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

__all__ = ["SuiteBatchTask", "batched_domains", "for_task", "register", "registered"]

#: The module of dm_control's suite, whose task classes are registered by full name.
_SUITE_PACKAGE = "dm_control.suite."


class SuiteBatchTask:
    """Every world's observation, reward and termination of one dm_control suite task.

    Args:
      task: the CPU suite task (a `dm_control.suite.base.Task`), whose parameters (sparse
        rewards, swing-up, ...) the array code follows.
      host: the CPU task's physics, for names and model constants, read in `__init__`
        only: a producer thread starts episodes on it (its data, and the model fields the
        episodes vary, change there).
      physics: the `composer.batch.MujocoBatchPhysics` of the worlds; `physics.data.<field>`
        is a (num_envs, ...) view, and so is `physics.model.<field>` for the model fields
        the episodes vary (`physics.batched_model_fields`).

    Attributes:
      episode_values: the current episode's `initial_values` of every world, by name,
        float64 (num_envs, *value shape), set by the environment.
    """

    def __init__(self, task, host, physics):
        self.task = task
        self.host = host
        self.physics = physics
        self.episode_values: dict[str, np.ndarray] = {}

    def initial_values(self) -> dict[str, np.ndarray]:
        """What the CPU task keeps from its `initialize_episode` for the rest of the episode
        (a target drawn there, ...), read from `self.task` right after a start, by name;
        none by default. Each world's values of its current episode are then in
        `episode_values`. Runs on a producer thread: read only `self.task`."""
        return {}

    def get_observation(self) -> dict[str, np.ndarray]:
        """Every world's observation: name -> float64 (num_envs, *the CPU task's shape),
        in the CPU task's key order."""
        raise NotImplementedError(f"{type(self).__name__} must implement get_observation")

    def get_reward(self) -> np.ndarray:
        """Every world's reward, float64 (num_envs,)."""
        raise NotImplementedError(f"{type(self).__name__} must implement get_reward")

    def get_termination(self) -> np.ndarray | None:
        """Every world's discount where the task ends its episode and NaN elsewhere, float64
        (num_envs,); None when the task never ends an episode (`base.Task`'s default)."""
        return None


_REGISTRY: dict[str, type[SuiteBatchTask]] = {}


def _key(task_type: type) -> str:
    return f"{task_type.__module__}.{task_type.__qualname__}"


def register(task_type_name: str, batch_task_type: type[SuiteBatchTask]) -> None:
    """Makes `batch_task_type` the batched version of the suite task class named
    `task_type_name` ("dm_control.suite.cartpole.Balance"), matched by name so that
    registering imports no dm_control."""
    if not (isinstance(batch_task_type, type) and issubclass(batch_task_type, SuiteBatchTask)):
        raise TypeError(
            f"batch_task_type: expected a SuiteBatchTask subclass, got {batch_task_type!r}"
        )
    _REGISTRY[task_type_name] = batch_task_type


def for_task(task: Any) -> type[SuiteBatchTask] | None:
    """The registered batched version of `task`'s class, or None."""
    return _REGISTRY.get(_key(type(task)))


def registered() -> Mapping[str, type[SuiteBatchTask]]:
    """A read-only view of the registry: suite task class name -> its `SuiteBatchTask`."""
    return MappingProxyType(_REGISTRY)


def batched_domains() -> list[str]:
    """The suite domains with a registered task, sorted ("cartpole" for
    "dm_control.suite.cartpole.Balance")."""
    return sorted({name.removeprefix(_SUITE_PACKAGE).split(".")[0] for name in _REGISTRY})
