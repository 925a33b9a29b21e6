"""Walker's `PlanarWalker` batched: its stand, walk and run tasks."""

import sys

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# Entries of a row-major 3x3 orientation matrix, as dm_control names its xmat columns.
_XX, _XZ, _ZZ = 0, 2, 8
#: Entries of an xmat row (a flattened 3x3) and of an xpos row.
_XMAT_SIZE, _Z = 9, 2


class BatchPlanarWalker(tasks.SuiteBatchTask):
    """`walker.PlanarWalker` for every world: a reward for a high, upright torso, times
    (walk and run) a linear ramp up to the task's forward speed of the centre of mass."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        self._torso = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "torso")
        sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, "torso_subtreelinvel")
        self._speed_entry = int(model.sensor_adr[sensor])
        # The xx and xz entries of every body but the world, in the order of a row-major
        # flattening of (body, entry): columns of the worlds' flattened xmat.
        bodies = np.arange(1, model.nbody)[:, None]
        self._orientation_columns = (bodies * _XMAT_SIZE + np.array([_XX, _XZ])).ravel()
        self._move_speed = float(task._move_speed)
        self._stand_height = sys.modules[type(task).__module__]._STAND_HEIGHT
        data = physics.data
        self._xmat, self._xpos = data.xmat, data.xpos
        self._qvel, self._sensordata = data.qvel, data.sensordata

    def _torso_height(self) -> np.ndarray:
        return self._xpos[:, self._torso, _Z]

    def get_observation(self) -> dict[str, np.ndarray]:
        xmat = self._xmat.reshape(self.physics.num_envs, -1)
        return {
            "orientations": xmat[:, self._orientation_columns],
            "height": np.array(self._torso_height()),
            "velocity": np.array(self._qvel),
        }

    def get_reward(self) -> np.ndarray:
        # The torso's height and the speed are one number each on the CPU.
        standing = rewards.tolerance(
            self._torso_height(),
            bounds=(self._stand_height, float("inf")),
            margin=self._stand_height / 2,
            scalar=True,
        )
        upright = (1 + self._xmat[:, self._torso, _ZZ]) / 2
        stand_reward = (3 * standing + upright) / 4
        if self._move_speed == 0:
            return stand_reward
        move_reward = rewards.tolerance(
            self._sensordata[:, self._speed_entry],
            bounds=(self._move_speed, float("inf")),
            margin=self._move_speed / 2,
            value_at_margin=0.5,
            sigmoid="linear",
            scalar=True,
        )
        return stand_reward * (5 * move_reward + 1) / 6


tasks.register("dm_control.suite.walker.PlanarWalker", BatchPlanarWalker)
