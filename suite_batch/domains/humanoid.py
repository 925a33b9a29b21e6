"""Humanoid's `Humanoid` batched: stand, walk, run and run_pure_state.

`BatchHumanoid` also serves humanoid_CMU (`suite_batch.domains.humanoid_CMU`), whose task
differs only in its body and sensor names and in which axis of the upper body must point up.
"""

import sys

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# Entries of a row-major 3x3 orientation matrix, as dm_control names its xmat columns.
_ZX, _ZY, _ZZ = 6, 7, 8
# The free root joint's position (3) and quaternion (4) lead qpos.
_ROOT_QPOS = 7
# The x and y entries of a linear velocity.
_HORIZONTAL = 2
# The torso's orientation must be at least this upright for the full upright reward ...
_UPRIGHT_BOUND = 0.9
# ... falling linearly to 0 over this margin.
_UPRIGHT_MARGIN = 1.9
# Horizontal speeds fall off with this margin in the stand task.
_STILL_MARGIN = 2


class BatchHumanoid(tasks.SuiteBatchTask):
    """`humanoid.Humanoid` for every world: the product of a reward for the head's height,
    one for the torso's uprightness, one for small controls and one for the horizontal
    centre-of-mass speed (near 0 to stand, at least the task's speed to walk or run).
    Observes the raw qpos and qvel (pure state), or egocentric features: the joint angles,
    the head's height, the hands and feet in the torso's frame, the torso's z axis, the
    centre-of-mass velocity and qvel.

    Subclasses for other models set the names below and the upright entry.
    """

    #: The upper body whose frame the extremities are seen in and which must stand upright.
    TORSO = "torso"
    HEAD = "head"
    #: The hands and feet, in the order of the extremities observation.
    EXTREMITIES = ("left_hand", "left_foot", "right_hand", "right_foot")
    #: The sensor of the centre of mass's linear velocity.
    CENTER_OF_MASS_VELOCITY = "torso_subtreelinvel"
    #: The torso's xmat entry the upright reward reads.
    UPRIGHT_ENTRY = _ZZ

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        body = mujoco.mjtObj.mjOBJ_BODY
        self._torso = self._id(model, body, self.TORSO)
        self._head = self._id(model, body, self.HEAD)
        self._extremities = np.array([self._id(model, body, name) for name in self.EXTREMITIES])
        sensor = self._id(model, mujoco.mjtObj.mjOBJ_SENSOR, self.CENTER_OF_MASS_VELOCITY)
        first = int(model.sensor_adr[sensor])
        self._com_velocity = slice(first, first + int(model.sensor_dim[sensor]))
        self._horizontal_velocity = slice(first, first + _HORIZONTAL)
        self._stand_height = sys.modules[type(task).__module__]._STAND_HEIGHT
        self._move_speed = task._move_speed
        # humanoid_CMU's task has the egocentric observations only.
        self._pure_state = bool(getattr(task, "_pure_state", False))
        data = physics.data
        self._qpos, self._qvel, self._ctrl = data.qpos, data.qvel, data.ctrl
        self._xpos, self._xmat, self._sensordata = data.xpos, data.xmat, data.sensordata

    @staticmethod
    def _id(model, kind, name: str) -> int:
        index = mujoco.mj_name2id(model, kind, name)
        if index < 0:
            raise ValueError(
                f"the model has no {kind.name.removeprefix('mjOBJ_').lower()} {name!r}"
            )
        return index

    def _head_height(self) -> np.ndarray:
        return self._xpos[:, self._head, 2]

    def _extremities_in_torso_frame(self) -> np.ndarray:
        """Each hand's and foot's offset from the torso as a row vector times the torso's
        orientation matrix, (num_envs, 3 * number of extremities)."""
        n = self.physics.num_envs
        offsets = self._xpos[:, self._extremities] - self._xpos[:, self._torso, None]
        frame = self._xmat[:, self._torso].reshape(n, 1, 3, 3)
        # A stacked matmul of 1x3 rows makes, per extremity, the very BLAS call (dgemv) of
        # the CPU's vector-matrix np.dot; einsum and sums of products differ in the last bit.
        return np.matmul(offsets[:, :, None, :], frame).reshape(n, -1)

    def get_observation(self) -> dict[str, np.ndarray]:
        if self._pure_state:
            return {"position": np.array(self._qpos), "velocity": np.array(self._qvel)}
        return {
            "joint_angles": np.array(self._qpos[:, _ROOT_QPOS:]),
            "head_height": np.array(self._head_height()),
            "extremities": self._extremities_in_torso_frame(),
            "torso_vertical": np.array(self._xmat[:, self._torso, _ZX : _ZZ + 1]),
            "com_velocity": np.array(self._sensordata[:, self._com_velocity]),
            "velocity": np.array(self._qvel),
        }

    def get_reward(self) -> np.ndarray:
        # The head's height and the upright entry are one number each on the CPU; the
        # controls and the horizontal velocity arrays.
        standing = rewards.tolerance(
            self._head_height(),
            bounds=(self._stand_height, float("inf")),
            margin=self._stand_height / 4,
            scalar=True,
        )
        upright = rewards.tolerance(
            self._xmat[:, self._torso, self.UPRIGHT_ENTRY],
            bounds=(_UPRIGHT_BOUND, float("inf")),
            sigmoid="linear",
            margin=_UPRIGHT_MARGIN,
            value_at_margin=0,
            scalar=True,
        )
        stand_reward = standing * upright
        small_control = rewards.tolerance(
            self._ctrl, margin=1, value_at_margin=0, sigmoid="quadratic", scalar=False
        ).mean(axis=1)
        small_control = (4 + small_control) / 5
        horizontal_velocity = self._sensordata[:, self._horizontal_velocity]
        if self._move_speed == 0:
            dont_move = rewards.tolerance(
                horizontal_velocity, margin=_STILL_MARGIN, scalar=False
            ).mean(axis=1)
            return small_control * stand_reward * dont_move
        # np.linalg.norm: the square root of np.dot, matched row by row by np.vecdot.
        speed = np.sqrt(np.vecdot(horizontal_velocity, horizontal_velocity))
        move = rewards.tolerance(
            speed,
            bounds=(self._move_speed, float("inf")),
            margin=self._move_speed,
            value_at_margin=0,
            sigmoid="linear",
            scalar=True,
        )
        move = (5 * move + 1) / 6
        return small_control * stand_reward * move


tasks.register("dm_control.suite.humanoid.Humanoid", BatchHumanoid)
