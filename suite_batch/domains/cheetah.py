"""Cheetah's `Cheetah` batched: the run task's speed reward."""

import sys

import mujoco
import numpy as np

from suite_batch import rewards, tasks


class BatchCheetah(tasks.SuiteBatchTask):
    """`cheetah.Cheetah` for every world: 1 at or above the domain's running speed, a
    linear ramp below it, of the torso's forward subtree velocity."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, "torso_subtreelinvel")
        self._speed_entry = int(model.sensor_adr[sensor])
        self._run_speed = sys.modules[type(task).__module__]._RUN_SPEED
        data = physics.data
        self._qpos, self._qvel, self._sensordata = data.qpos, data.qvel, data.sensordata

    def get_observation(self) -> dict[str, np.ndarray]:
        # The horizontal position is left out (translational invariance), as the task does.
        return {"position": np.array(self._qpos[:, 1:]), "velocity": np.array(self._qvel)}

    def get_reward(self) -> np.ndarray:
        return rewards.tolerance(
            self._sensordata[:, self._speed_entry],
            bounds=(self._run_speed, float("inf")),
            margin=self._run_speed,
            value_at_margin=0,
            sigmoid="linear",
            scalar=True,
        )


tasks.register("dm_control.suite.cheetah.Cheetah", BatchCheetah)
