"""Fish's `Upright` and `Swim` batched: the upright and swim tasks (swim's target, drawn
each episode, is a model field with a row per world)."""

import sys

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# The z-z entry of a row-major 3x3 orientation matrix, as dm_control names xmat's columns.
_ZZ = 8


class _BatchFish(tasks.SuiteBatchTask):
    """What fish's two tasks share: the actuated joints' angles, the torso's uprightness
    (the world z axis in the torso's frame, its z entry) and the joint velocities."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        joints = sys.modules[type(task).__module__]._JOINTS
        joint = mujoco.mjtObj.mjOBJ_JOINT
        ids = [mujoco.mj_name2id(model, joint, name) for name in joints]
        self._joint_angles = model.jnt_qposadr[ids]
        self._torso = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "torso")
        data = physics.data
        self._qpos, self._qvel, self._xmat = data.qpos, data.qvel, data.xmat

    def _upright(self) -> np.ndarray:
        return self._xmat[:, self._torso, _ZZ]

    def _joint_values(self) -> np.ndarray:
        return self._qpos[:, self._joint_angles]


class BatchUpright(_BatchFish):
    """`fish.Upright` for every world: a gaussian reward of the torso's uprightness, 1 when
    upright. Its episodes hide the target (the same model change in every world)."""

    def get_observation(self) -> dict[str, np.ndarray]:
        return {
            "joint_angles": self._joint_values(),
            "upright": np.array(self._upright()),
            "velocity": np.array(self._qvel),
        }

    def get_reward(self) -> np.ndarray:
        return rewards.tolerance(self._upright(), bounds=(1, 1), margin=1, scalar=True)


class BatchSwim(_BatchFish):
    """`fish.Swim` for every world: 7 parts a gaussian reward for the mouth reaching the
    target (within their radii's sum; the target's position drawn each episode, a row of
    `geom_pos` per world), 1 part uprightness, in eighths. Observes, besides fish's
    shared ones, the target seen from the mouth (in the mouth's frame)."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        geom = mujoco.mjtObj.mjOBJ_GEOM
        self._mouth = mujoco.mj_name2id(model, geom, "mouth")
        self._target = mujoco.mj_name2id(model, geom, "target")
        # The radii's sum as the task sums them: an array's sum, mouth then target.
        self._radii = float(model.geom_size[[self._mouth, self._target], 0].sum())
        data = physics.data
        self._geom_xpos, self._geom_xmat = data.geom_xpos, data.geom_xmat

    def _mouth_to_target(self) -> np.ndarray:
        """The target's offset from the mouth in the mouth's frame, (num_envs, 3): the
        world offset as a row vector times the mouth's orientation matrix."""
        n = self.physics.num_envs
        offset = self._geom_xpos[:, self._target] - self._geom_xpos[:, self._mouth]
        orientation = self._geom_xmat[:, self._mouth].reshape(n, 3, 3)
        # The CPU's vector-matrix np.dot (BLAS) is matched world by world by a stacked
        # matmul; einsum and sums of products differ in the last bit.
        return np.matmul(offset[:, None, :], orientation)[:, 0]

    def get_observation(self) -> dict[str, np.ndarray]:
        return {
            "joint_angles": self._joint_values(),
            "upright": np.array(self._upright()),
            "target": self._mouth_to_target(),
            "velocity": np.array(self._qvel),
        }

    def get_reward(self) -> np.ndarray:
        to_target = self._mouth_to_target()
        # np.linalg.norm: the square root of np.dot, matched row by row by np.vecdot.
        distance = np.sqrt(np.vecdot(to_target, to_target))
        in_target = rewards.tolerance(
            distance, bounds=(0, self._radii), margin=2 * self._radii, scalar=True
        )
        is_upright = 0.5 * (self._upright() + 1)
        return (7 * in_target + is_upright) / 8


tasks.register("dm_control.suite.fish.Upright", BatchUpright)
tasks.register("dm_control.suite.fish.Swim", BatchSwim)
