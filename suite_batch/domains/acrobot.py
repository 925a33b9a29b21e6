"""Acrobot's `Balance` batched: its swing-up tasks, smooth and sparse."""

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# Entries of a row-major 3x3 orientation matrix, as dm_control names its xmat columns.
_ZZ, _XZ = 8, 2


class BatchBalance(tasks.SuiteBatchTask):
    """`acrobot.Balance` for every world: the tip's distance to the target above, 1 inside
    the target and (smooth) a gaussian fall-off over a margin of 1 outside it, (sparse) 0
    outside it."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        body, site = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_SITE
        arms = [mujoco.mj_name2id(model, body, name) for name in ("upper_arm", "lower_arm")]
        # The arms' horizontal then vertical z-axis components, as one gather.
        self._orientation_bodies = arms + arms
        self._orientation_entries = [_XZ, _XZ, _ZZ, _ZZ]
        self._target = mujoco.mj_name2id(model, site, "target")
        self._tip = mujoco.mj_name2id(model, site, "tip")
        self._target_radius = float(model.site_size[self._target, 0])
        self._margin = 0 if task._sparse else 1
        data = physics.data
        self._qvel, self._xmat, self._site_xpos = data.qvel, data.xmat, data.site_xpos

    def get_observation(self) -> dict[str, np.ndarray]:
        return {
            "orientations": self._xmat[:, self._orientation_bodies, self._orientation_entries],
            "velocity": np.array(self._qvel),
        }

    def get_reward(self) -> np.ndarray:
        xpos = self._site_xpos
        tip_to_target = xpos[:, self._target] - xpos[:, self._tip]
        # The CPU's np.linalg.norm is the square root of np.dot (BLAS), which np.vecdot
        # matches row by row.
        distance = np.sqrt(np.vecdot(tip_to_target, tip_to_target))
        return rewards.tolerance(
            distance, (0, self._target_radius), margin=self._margin, scalar=True
        )


tasks.register("dm_control.suite.acrobot.Balance", BatchBalance)
