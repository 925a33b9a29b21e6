"""LQR's `LQRLevel` batched: lqr_2_1 and lqr_6_2, whose joint stiffnesses each world draws
from its own seed (a model field with a row per world)."""

import numpy as np

from suite_batch import tasks


class BatchLQRLevel(tasks.SuiteBatchTask):
    """`lqr.LQRLevel` for every world: one minus the quadratic costs of the positions and
    the controls; the episode ends (discount 0) once the state's norm is below the task's
    tolerance."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        self._control_cost = float(task.control_cost_coef)
        self._terminal_tolerance = float(type(task)._TERMINAL_TOL)
        data = physics.data
        self._qpos, self._qvel, self._act, self._ctrl = data.qpos, data.qvel, data.act, data.ctrl

    def get_observation(self) -> dict[str, np.ndarray]:
        return {"position": np.array(self._qpos), "velocity": np.array(self._qvel)}

    def get_reward(self) -> np.ndarray:
        # The CPU's np.dot of two vectors (BLAS) is matched row by row by np.vecdot.
        state_cost = 0.5 * np.vecdot(self._qpos, self._qpos)
        control_cost = 0.5 * np.vecdot(self._ctrl, self._ctrl)
        return 1 - (state_cost + control_cost * self._control_cost)

    def get_termination(self) -> np.ndarray:
        state = np.concatenate([self._qpos, self._qvel, self._act], axis=1)
        norm = np.sqrt(np.vecdot(state, state))
        return np.where(norm < self._terminal_tolerance, 0.0, np.nan)


tasks.register("dm_control.suite.lqr.LQRLevel", BatchLQRLevel)
