"""Reacher's `Reacher` batched: its easy and hard tasks (a large and a small target)."""

import mujoco
import numpy as np

from suite_batch import rewards, tasks


class BatchReacher(tasks.SuiteBatchTask):
    """`reacher.Reacher` for every world: 1 while the finger touches the target, whose
    position each episode draws (a model field with a row per world)."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        geom = mujoco.mjtObj.mjOBJ_GEOM
        self._target = mujoco.mj_name2id(model, geom, "target")
        self._finger = mujoco.mj_name2id(model, geom, "finger")
        # The episode start sets the target's radius to the task's; the finger's is the
        # compiled one. Their sum, in the task's order.
        self._radii = float(task._target_size) + float(model.geom_size[self._finger, 0])
        data = physics.data
        self._qpos, self._qvel, self._geom_xpos = data.qpos, data.qvel, data.geom_xpos

    def _finger_to_target(self) -> np.ndarray:
        xpos = self._geom_xpos
        return xpos[:, self._target, :2] - xpos[:, self._finger, :2]

    def get_observation(self) -> dict[str, np.ndarray]:
        return {
            "position": np.array(self._qpos),
            "to_target": self._finger_to_target(),
            "velocity": np.array(self._qvel),
        }

    def get_reward(self) -> np.ndarray:
        offset = self._finger_to_target()
        # The CPU's np.linalg.norm is the square root of np.dot (BLAS), which np.vecdot
        # matches row by row (a sum of products does not, in the last bit).
        distance = np.sqrt(np.vecdot(offset, offset))
        return rewards.tolerance(distance, (0, self._radii), scalar=True)


tasks.register("dm_control.suite.reacher.Reacher", BatchReacher)
