"""Stacker's `Stack` batched: its two tasks, putting one of two or four boxes on the target
(stack_2, stack_4).

Each episode start draws the target's position (its height a whole number of boxes) into
the model's `body_pos`, which then has a row per world; the array code reads the
resulting body and site positions from the data.
"""

import mujoco
import numpy as np

from suite_batch import rewards, tasks
from suite_batch.domains.manipulator import ARM_JOINTS, POSITION_XZ, ids, planar_poses

#: The distance (metres) from the target beyond which the hand counts as away from it.
HAND_AWAY = 0.1
#: The margin (metres) over which the hand's reward falls off inside `HAND_AWAY`.
CLOSE = 0.01


class BatchStack(tasks.SuiteBatchTask):
    """`stacker.Stack` for every world: how close the box nearest the target is to it
    (1 at the target, falling off over two box half-sizes), times whether the hand is
    away from the target (1 beyond `HAND_AWAY`, falling off over `CLOSE`)."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        joints = ids(model, mujoco.mjtObj.mjOBJ_JOINT, ARM_JOINTS)
        box_joints = ids(model, mujoco.mjtObj.mjOBJ_JOINT, task._box_joint_names)
        self._arm_qpos = model.jnt_qposadr[joints]
        self._arm_dofs = model.jnt_dofadr[joints]
        self._box_dofs = model.jnt_dofadr[box_joints]
        body = mujoco.mjtObj.mjOBJ_BODY
        self._hand, self._target = ids(model, body, ("hand", "target"))
        self._boxes = ids(model, body, task._box_names)
        site = mujoco.mjtObj.mjOBJ_SITE
        self._box_sites = ids(model, site, task._box_names)
        self._target_site, self._grasp_site = ids(model, site, ("target", "grasp"))
        target_geom = ids(model, mujoco.mjtObj.mjOBJ_GEOM, ("target",))[0]
        # The target is one box; the episode starts move it, never resize it.
        self._box_margin = 2 * float(model.geom_size[target_geom, 0])
        self._fully_observable = bool(task._fully_observable)
        data = physics.data
        self._qpos, self._qvel = data.qpos, data.qvel
        self._xpos, self._xquat = data.xpos, data.xquat
        self._site_xpos, self._sensordata = data.site_xpos, data.sensordata

    def get_observation(self) -> dict[str, np.ndarray]:
        angles = self._qpos[:, self._arm_qpos]
        observation = {
            "arm_pos": np.stack([np.sin(angles), np.cos(angles)], axis=-1),
            "arm_vel": self._qvel[:, self._arm_dofs],
            # Every sensor of the model is one of the hand's touch sensors.
            "touch": np.log1p(self._sensordata),
        }
        if self._fully_observable:
            observation["hand_pos"] = planar_poses(self._xpos, self._xquat, self._hand)
            observation["box_pos"] = planar_poses(self._xpos, self._xquat, self._boxes)
            observation["box_vel"] = self._qvel[:, self._box_dofs]
            observation["target_pos"] = self._xpos[:, self._target][:, POSITION_XZ]
        return observation

    def _distances_to_target(self, sites: np.ndarray) -> np.ndarray:
        """Every world's distance from each of `sites` to the target's: (num_envs, sites)."""
        offsets = self._site_xpos[:, sites] - self._site_xpos[:, self._target_site, None]
        # The CPU's np.linalg.norm of one offset is the square root of its np.dot, which
        # np.vecdot matches row by row.
        return np.sqrt(np.vecdot(offsets, offsets))

    def get_reward(self) -> np.ndarray:
        nearest_box = self._distances_to_target(self._box_sites).min(axis=1)
        hand = self._distances_to_target(self._grasp_site[None])[:, 0]
        # The CPU passes each distance as one number.
        box_is_close = rewards.tolerance(nearest_box, margin=self._box_margin, scalar=True)
        hand_is_away = rewards.tolerance(
            hand, bounds=(HAND_AWAY, float("inf")), margin=CLOSE, scalar=True
        )
        return box_is_close * hand_is_away


tasks.register("dm_control.suite.stacker.Stack", BatchStack)
