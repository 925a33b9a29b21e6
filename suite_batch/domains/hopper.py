"""Hopper's `Hopper` batched: its stand and hop tasks."""

import sys

import mujoco
import numpy as np

from suite_batch import rewards, tasks

#: The z entry of an xipos row.
_Z = 2


class BatchHopper(tasks.SuiteBatchTask):
    """`hopper.Hopper` for every world: 1 while the torso is within the standing heights
    above the foot, times a small-control bonus (stand) or a linear ramp up to the
    hopping speed of the centre of mass (hop)."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        body, sensor = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_SENSOR
        self._torso = mujoco.mj_name2id(model, body, "torso")
        self._foot = mujoco.mj_name2id(model, body, "foot")
        speed = mujoco.mj_name2id(model, sensor, "torso_subtreelinvel")
        self._speed_entry = int(model.sensor_adr[speed])
        # The toe's, then the heel's touch sensor (one entry each).
        self._touch_entries = np.array(
            [
                model.sensor_adr[mujoco.mj_name2id(model, sensor, name)]
                for name in ("touch_toe", "touch_heel")
            ]
        )
        self._hopping = bool(task._hopping)
        domain = sys.modules[type(task).__module__]
        self._stand_height, self._hop_speed = domain._STAND_HEIGHT, domain._HOP_SPEED
        data = physics.data
        self._qpos, self._qvel, self._xipos = data.qpos, data.qvel, data.xipos
        self._sensordata, self._ctrl = data.sensordata, data.ctrl

    def get_observation(self) -> dict[str, np.ndarray]:
        # The horizontal position is left out (translational invariance), as the task does.
        return {
            "position": np.array(self._qpos[:, 1:]),
            "velocity": np.array(self._qvel),
            "touch": np.log1p(self._sensordata[:, self._touch_entries]),
        }

    def get_reward(self) -> np.ndarray:
        height = self._xipos[:, self._torso, _Z] - self._xipos[:, self._foot, _Z]
        standing = rewards.tolerance(height, (self._stand_height, 2), scalar=True)
        if self._hopping:
            hopping = rewards.tolerance(
                self._sensordata[:, self._speed_entry],
                bounds=(self._hop_speed, float("inf")),
                margin=self._hop_speed / 2,
                value_at_margin=0.5,
                sigmoid="linear",
                scalar=True,
            )
            return standing * hopping
        # The controls are an array on the CPU, averaged over the actuators.
        small_control = rewards.tolerance(
            self._ctrl, margin=1, value_at_margin=0, sigmoid="quadratic", scalar=False
        ).mean(axis=1)
        small_control = (small_control + 4) / 5
        return standing * small_control


tasks.register("dm_control.suite.hopper.Hopper", BatchHopper)
