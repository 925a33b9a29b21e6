"""Pendulum's `SwingUp` batched: its swing-up task."""

import sys

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# Entries of a row-major 3x3 orientation matrix, as dm_control names its xmat columns.
_ZZ, _XZ = 8, 2


class BatchSwingUp(tasks.SuiteBatchTask):
    """`pendulum.SwingUp` for every world: 1 while the pole is within the domain's angle of
    upright (its z-axis' vertical component at or above the bound's cosine), else 0."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        self._pole = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "pole")
        hinge = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "hinge")
        self._hinge = [int(model.jnt_dofadr[hinge])]
        self._cosine_bound = float(sys.modules[type(task).__module__]._COSINE_BOUND)
        data = physics.data
        self._qvel, self._xmat = data.qvel, data.xmat

    def get_observation(self) -> dict[str, np.ndarray]:
        return {
            "orientation": self._xmat[:, self._pole, [_ZZ, _XZ]],
            "velocity": self._qvel[:, self._hinge],
        }

    def get_reward(self) -> np.ndarray:
        return rewards.tolerance(
            self._xmat[:, self._pole, _ZZ], (self._cosine_bound, 1), scalar=True
        )


tasks.register("dm_control.suite.pendulum.SwingUp", BatchSwingUp)
