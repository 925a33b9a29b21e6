"""Batched composer environments on MuJoCo Warp: thousands of worlds of one task at once.

Needs the extra `[warp]` (`mujoco-warp`, `warp-lang`); importing this package does not
import Warp, building a `BatchEnvironment` does. See docs/batch.md for the limits.
"""

from composer.batch.bindings import BatchBinding
from composer.batch.environment import BatchEnvironment, BatchTimeStep
from composer.batch.observables import BatchObservables, batch_reader
from composer.batch.physics import BatchPhysics
from composer.batch.task import BatchTask, InitialStateSource, for_task, register

__all__ = [
    "BatchBinding",
    "BatchEnvironment",
    "BatchObservables",
    "BatchPhysics",
    "BatchTask",
    "BatchTimeStep",
    "InitialStateSource",
    "batch_reader",
    "for_task",
    "register",
]
