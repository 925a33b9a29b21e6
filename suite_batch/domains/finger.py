"""Finger's `Spin` and `Turn` batched: spinning the hinged body fast, and turning its tip
onto a target that each episode places (a model field with a row per world)."""

import sys

import mujoco
import numpy as np

from suite_batch import tasks

# The horizontal and vertical entries of a sensor's world position (x, y, z).
_X, _Z = 0, 2


def _sensor_entries(model: mujoco.MjModel, name: str, entries: tuple[int, ...] = (0,)) -> list[int]:
    """The indices in `sensordata` of the `entries` of the sensor called `name`."""
    sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, name)
    if sensor < 0:
        raise ValueError(f"finger model: no sensor named {name!r}")
    return [int(model.sensor_adr[sensor]) + entry for entry in entries]


class _FingerObservations(tasks.SuiteBatchTask):
    """What both finger tasks observe, all from the sensors: the finger's joint angles and
    the spinner's tip relative to its hinge, three joint velocities, and the two touch
    sensors on a log scale."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        self._joints = _sensor_entries(model, "proximal") + _sensor_entries(model, "distal")
        self._tip = _sensor_entries(model, "tip", (_X, _Z))
        self._spinner = _sensor_entries(model, "spinner", (_X, _Z))
        self._velocities = [
            entry
            for name in ("proximal_velocity", "distal_velocity", "hinge_velocity")
            for entry in _sensor_entries(model, name)
        ]
        self._hinge_velocity = self._velocities[-1]
        self._touches = _sensor_entries(model, "touchtop") + _sensor_entries(model, "touchbottom")
        self._sensordata = physics.data.sensordata

    def _tip_position(self) -> np.ndarray:
        sensordata = self._sensordata
        return sensordata[:, self._tip] - sensordata[:, self._spinner]

    def get_observation(self) -> dict[str, np.ndarray]:
        sensordata = self._sensordata
        return {
            "position": np.concatenate([sensordata[:, self._joints], self._tip_position()], axis=1),
            "velocity": sensordata[:, self._velocities],
            "touch": np.log1p(sensordata[:, self._touches]),
        }


class BatchSpin(_FingerObservations):
    """`finger.Spin` for every world: 1 while the hinge turns at the domain's spin speed or
    faster (in the negative sense), else 0."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        self._spin_velocity = float(sys.modules[type(task).__module__]._SPIN_VELOCITY)

    def get_reward(self) -> np.ndarray:
        velocity = self._sensordata[:, self._hinge_velocity]
        return (velocity <= -self._spin_velocity).astype(np.float64)


class BatchTurn(_FingerObservations):
    """`finger.Turn` for every world: 1 while the tip is inside the target, whose place on
    the tip's circle each episode draws (`site_pos` has a row per world); the target's
    position and its signed distance to the tip are observed too."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        self._target = _sensor_entries(model, "target", (_X, _Z))
        # The episode start sets the target site's radius to the task's.
        self._target_radius = float(task._target_radius)

    def _target_position(self) -> np.ndarray:
        sensordata = self._sensordata
        return sensordata[:, self._target] - sensordata[:, self._spinner]

    def _distance_to_target(self, target_position: np.ndarray) -> np.ndarray:
        """The tip's signed distance to the target's surface (negative inside)."""
        to_target = target_position - self._tip_position()
        # The CPU's np.linalg.norm is the square root of np.dot (BLAS), which np.vecdot
        # matches row by row.
        return np.sqrt(np.vecdot(to_target, to_target)) - self._target_radius

    def get_observation(self) -> dict[str, np.ndarray]:
        observation = super().get_observation()
        target_position = self._target_position()
        observation["target_position"] = target_position
        observation["dist_to_target"] = self._distance_to_target(target_position)
        return observation

    def get_reward(self) -> np.ndarray:
        distance = self._distance_to_target(self._target_position())
        return (distance <= 0).astype(np.float64)


tasks.register("dm_control.suite.finger.Spin", BatchSpin)
tasks.register("dm_control.suite.finger.Turn", BatchTurn)
