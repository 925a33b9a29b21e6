"""Swimmer's `Swimmer` batched: swimmer6 and swimmer15 (dm_control generates a model per
number of links; one class serves any), whose target, drawn each episode, is a model field
with a row per world."""

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# The root joints (x and y slides, z hinge) lead qpos; the links' hinges follow.
_ROOT_DOFS = 3
# Per link, a velocimeter (3 entries) then a gyro (3): its local x and y velocities and
# its rotational velocity about z.
_LINK_SENSOR_ENTRIES = 6
_VX, _VY, _WZ = 0, 1, 5


class BatchSwimmer(tasks.SuiteBatchTask):
    """`swimmer.Swimmer` for every world: a long-tailed reward of the nose's distance to
    the target (1 within the target's radius; its position drawn each episode, a row of
    `geom_pos` per world). Observes the links' joint angles, the target seen from the nose
    (in the head's frame, x and y) and each link's local x, y and rotational z velocity."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        geom = mujoco.mjtObj.mjOBJ_GEOM
        self._nose = mujoco.mj_name2id(model, geom, "nose")
        self._target = mujoco.mj_name2id(model, geom, "target")
        self._head = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "head")
        self._target_size = float(model.geom_size[self._target, 0])
        # From the head's velocimeter on, every link's sensors (head first).
        head_velocity = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, "head_vel")
        first = int(model.sensor_adr[head_velocity])
        links = (model.nsensordata - first) // _LINK_SENSOR_ENTRIES
        starts = first + _LINK_SENSOR_ENTRIES * np.arange(links)
        self._body_velocities = (starts[:, None] + np.array([_VX, _VY, _WZ])).ravel()
        data = physics.data
        self._qpos, self._sensordata = data.qpos, data.sensordata
        self._geom_xpos, self._xmat = data.geom_xpos, data.xmat

    def _nose_to_target(self) -> np.ndarray:
        """The target's offset from the nose in the head's frame, x and y, (num_envs, 2):
        the world offset as a row vector times the head's orientation matrix."""
        n = self.physics.num_envs
        offset = self._geom_xpos[:, self._target] - self._geom_xpos[:, self._nose]
        orientation = self._xmat[:, self._head].reshape(n, 3, 3)
        # The CPU's vector-matrix np.dot (BLAS) is matched world by world by a stacked
        # matmul; einsum and sums of products differ in the last bit.
        return np.matmul(offset[:, None, :], orientation)[:, 0, :2]

    def get_observation(self) -> dict[str, np.ndarray]:
        return {
            "joints": np.array(self._qpos[:, _ROOT_DOFS:]),
            "to_target": self._nose_to_target(),
            "body_velocities": self._sensordata[:, self._body_velocities],
        }

    def get_reward(self) -> np.ndarray:
        to_target = self._nose_to_target()
        # np.linalg.norm: the square root of np.dot, matched row by row by np.vecdot.
        distance = np.sqrt(np.vecdot(to_target, to_target))
        return rewards.tolerance(
            distance,
            bounds=(0, self._target_size),
            margin=5 * self._target_size,
            sigmoid="long_tail",
            scalar=True,
        )


tasks.register("dm_control.suite.swimmer.Swimmer", BatchSwimmer)
