"""Batched composer environments: many worlds of one task stepped at once.

On the CPU (`device="cpu"`, the default without a GPU) the worlds run on MuJoCo's own
`mujoco.batch` (MuJoCo >= 4, no extra), each bit for bit its `composer.Environment`; on a
GPU, and on Warp's CPU device (`device="warp-cpu"`), on MuJoCo Warp (the extra `[warp]`).
Importing this package imports neither; see `composer.batch.devices` and
docs/concepts/batch.md.
"""

from composer.batch.bindings import BatchBinding
from composer.batch.environment import BatchEnvironment, BatchTimeStep
from composer.batch.mujoco_batch import MujocoBatchPhysics
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
    "MujocoBatchPhysics",
    "batch_reader",
    "for_task",
    "register",
]
