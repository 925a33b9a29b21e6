"""Manipulator's `Bring` batched: its four tasks, bringing a ball or a peg to a target,
with or without a receptacle (cup, slot) at the target (bring_ball, bring_peg, insert_ball,
insert_peg).

Each episode start draws the target's (and receptacle's) pose into the model's `body_pos`
and `body_quat`, which then have a row per world; the array code reads the resulting
body and site positions from the data.
"""

import mujoco
import numpy as np

from suite_batch import rewards, tasks

#: The arm's hinges, in the order of the `arm_pos` and `arm_vel` observations.
ARM_JOINTS = (
    "arm_root",
    "arm_shoulder",
    "arm_elbow",
    "arm_wrist",
    "finger",
    "fingertip",
    "thumb",
    "thumbtip",
)
#: The hand's touch sensors, in the order of the `touch` observation.
TOUCH_SENSORS = ("palm_touch", "finger_touch", "thumb_touch", "fingertip_touch", "thumbtip_touch")
#: A distance (metres) under which two sites count as close.
CLOSE = 0.01

#: The entries of a body's position and of its quaternion in its planar pose: x and z,
#: w and y (the arm moves in the xz plane, turning about y).
POSITION_XZ = [0, 2]
QUATERNION_WY = [0, 2]


def ids(model: mujoco.MjModel, kind: mujoco.mjtObj, names) -> np.ndarray:
    """The ids of the objects of `kind` named `names`, in order.

    Raises:
      ValueError: for a name the model lacks, naming it.
    """
    found = []
    for name in names:
        index = mujoco.mj_name2id(model, kind, name)
        if index < 0:
            raise ValueError(f"model: no {kind.name.removeprefix('mjOBJ_').lower()} {name!r}")
        found.append(index)
    return np.array(found, dtype=np.intp)


def planar_poses(xpos: np.ndarray, xquat: np.ndarray, bodies) -> np.ndarray:
    """Every world's planar pose of `bodies` (an id or an array of them): x, z, qw, qy
    along the last axis."""
    positions, quaternions = xpos[:, bodies][..., POSITION_XZ], xquat[:, bodies][..., QUATERNION_WY]
    return np.concatenate([positions, quaternions], axis=-1)


class BatchBring(tasks.SuiteBatchTask):
    """`manipulator.Bring` for every world: 1 while the prop is within `CLOSE` of its
    target, falling off over twice that. For the peg, the larger of the mean closeness of
    its centre and tip to the target's and a third of the mean closeness of its grasp and
    pinch points to the hand's."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        joints = ids(model, mujoco.mjtObj.mjOBJ_JOINT, ARM_JOINTS)
        object_joints = ids(model, mujoco.mjtObj.mjOBJ_JOINT, task._object_joints)
        self._arm_qpos = model.jnt_qposadr[joints]
        self._arm_dofs = model.jnt_dofadr[joints]
        self._object_dofs = model.jnt_dofadr[object_joints]
        self._touch = model.sensor_adr[ids(model, mujoco.mjtObj.mjOBJ_SENSOR, TOUCH_SENSORS)]
        body = mujoco.mjtObj.mjOBJ_BODY
        self._hand, self._object, self._target = ids(
            model, body, ("hand", task._object, task._target)
        )
        self._use_peg = bool(task._use_peg)
        self._fully_observable = bool(task._fully_observable)
        site = mujoco.mjtObj.mjOBJ_SITE
        if self._use_peg:
            # (site, site) pairs whose distances make the reward, as the task measures them.
            pairs = (
                ("peg_grasp", "grasp"),
                ("peg_pinch", "pinch"),
                ("peg", "target_peg"),
                ("target_peg_tip", "peg_tip"),
            )
        else:
            pairs = ((task._object, task._target),)
        self._from_sites = ids(model, site, [first for first, _ in pairs])
        self._to_sites = ids(model, site, [second for _, second in pairs])
        data = physics.data
        self._qpos, self._qvel = data.qpos, data.qvel
        self._xpos, self._xquat = data.xpos, data.xquat
        self._site_xpos, self._sensordata = data.site_xpos, data.sensordata

    def get_observation(self) -> dict[str, np.ndarray]:
        angles = self._qpos[:, self._arm_qpos]
        observation = {
            "arm_pos": np.stack([np.sin(angles), np.cos(angles)], axis=-1),
            "arm_vel": self._qvel[:, self._arm_dofs],
            "touch": np.log1p(self._sensordata[:, self._touch]),
        }
        if self._fully_observable:
            observation["hand_pos"] = planar_poses(self._xpos, self._xquat, self._hand)
            observation["object_pos"] = planar_poses(self._xpos, self._xquat, self._object)
            observation["object_vel"] = self._qvel[:, self._object_dofs]
            observation["target_pos"] = planar_poses(self._xpos, self._xquat, self._target)
        return observation

    def _closeness(self) -> np.ndarray:
        """Every world's closeness of each site pair: (num_envs, pairs)."""
        offsets = self._site_xpos[:, self._from_sites] - self._site_xpos[:, self._to_sites]
        # The CPU's np.linalg.norm of one offset is the square root of its np.dot, which
        # np.vecdot matches row by row; the CPU passes each distance as one number.
        distances = np.sqrt(np.vecdot(offsets, offsets))
        return rewards.tolerance(distances, (0, CLOSE), 2 * CLOSE, scalar=True)

    def get_reward(self) -> np.ndarray:
        closeness = self._closeness()
        if not self._use_peg:
            return closeness[:, 0]
        grasp, pinch, bring, bring_tip = closeness.T
        grasping = (grasp + pinch) / 2
        bringing = (bring + bring_tip) / 2
        return np.maximum(bringing, grasping / 3)


tasks.register("dm_control.suite.manipulator.Bring", BatchBring)
