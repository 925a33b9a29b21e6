"""Dog's `Stand`, `Move` and `Fetch` batched: its stand, walk, trot, run and fetch tasks.

The tasks rotate world vectors into a body's frame with NumPy's 1-D `dot` (`v.dot(R)`) and
measure distances with `np.linalg.norm`, both of which NumPy hands to BLAS, whose kernels
fuse multiplies and adds: sums of products written out in NumPy differ from them in the
last bit. `np.matmul` on stacks of the same shapes calls the same BLAS routines per world
and equals them bit for bit, so every world's rotation and norm here is a `matmul`.
"""

import sys

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# Entries of a row-major 3x3 orientation matrix, as dm_control names its xmat columns:
# the body's z axis in world coordinates.
_ZX, _ZY, _ZZ = 6, 7, 8


def _id(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> int:
    index = mujoco.mj_name2id(model, kind, name)
    if index < 0:
        raise ValueError(f"dog model: no {kind.name.removeprefix('mjOBJ_').lower()} {name!r}")
    return index


def _sensor_entries(model: mujoco.MjModel, names: tuple[str, ...]) -> np.ndarray:
    """The sensordata entries of the sensors `names`, each sensor's in order, concatenated
    (dm_control's named indexing of a list of sensors)."""
    entries = []
    for name in names:
        sensor = _id(model, mujoco.mjtObj.mjOBJ_SENSOR, name)
        start = int(model.sensor_adr[sensor])
        entries.extend(range(start, start + int(model.sensor_dim[sensor])))
    return np.array(entries)


def _in_frame(vectors: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Each world's `vector.dot(frame)`: (num_envs, 3) vectors, (num_envs, 9) row-major
    frames, through the BLAS routine of NumPy's 1-D dot."""
    return np.matmul(vectors[:, None, :], frames.reshape(-1, 3, 3))[:, 0]


def _norm(vectors: np.ndarray) -> np.ndarray:
    """Each world's `np.linalg.norm(vector)` of (num_envs, 3) vectors: the square root of
    the BLAS dot product of the vector with itself."""
    return np.sqrt(np.matmul(vectors[:, None, :], vectors[:, :, None])[:, 0, 0])


class BatchStand(tasks.SuiteBatchTask):
    """`dog.Stand` for every world: the product of four kinds of factor, the torso's and the
    pelvis's height (1 at or above 0.9 of the default pose's), the skull's, torso's and
    pelvis's uprightness, and the paws' touch forces (1 at or above the body's weight).

    The heights and the weight that `initialize_episode` measures are the same every
    episode (of the default pose and the model's masses), so they are measured once here.
    """

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        constants = sys.modules[type(task).__module__]
        self._min_upright_cosine = constants._MIN_UPRIGHT_COSINE
        self._observe_reward_factors = bool(task._observe_reward_factors)
        hinges = model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
        self._hinge_qpos = model.jnt_qposadr[hinges]
        self._hinge_dofs = model.jnt_dofadr[hinges]
        body = mujoco.mjtObj.mjOBJ_BODY
        self._torso = _id(model, body, "torso")
        self._torso_pelvis = np.array([self._torso, _id(model, body, "pelvis")])
        self._z_bodies = np.array([_id(model, body, "skull"), *self._torso_pelvis])
        self._com_velocity = _sensor_entries(model, ("torso_linvel",))
        self._inertial = _sensor_entries(model, ("accelerometer", "velocimeter", "gyro"))
        self._touch = _sensor_entries(model, ("palm_L", "palm_R", "sole_L", "sole_R"))
        self._foot_forces = _sensor_entries(model, ("foot_L", "foot_R", "hand_L", "hand_R"))
        default_pose = mujoco.MjData(model)
        mujoco.mj_forward(model, default_pose)
        heights = default_pose.xpos[self._torso_pelvis, 2] * constants._STAND_HEIGHT_FRACTION
        self._stand_heights = (heights[0], heights[1])
        self._body_weight = -model.opt.gravity[2] * model.body_subtreemass[self._torso]
        data = physics.data
        self._qpos, self._qvel, self._act = data.qpos, data.qvel, data.act
        self._xpos, self._xmat, self._sensordata = data.xpos, data.xmat, data.sensordata

    def _torso_pelvis_height(self) -> np.ndarray:
        return self._xpos[:, self._torso_pelvis, 2]

    def _torso_com_velocity(self) -> np.ndarray:
        return _in_frame(self._sensordata[:, self._com_velocity], self._xmat[:, self._torso])

    def get_observation(self) -> dict[str, np.ndarray]:
        n = self.physics.num_envs
        z_axes = self._xmat[:, self._z_bodies][:, :, [_ZX, _ZY, _ZZ]]
        observation = {
            "joint_angles": self._qpos[:, self._hinge_qpos],
            # The task's own key, misspelt.
            "joint_velocites": self._qvel[:, self._hinge_dofs],
            "torso_pelvis_height": self._torso_pelvis_height(),
            "z_projection": z_axes.reshape(n, 9),
            "torso_com_velocity": self._torso_com_velocity(),
            "inertial_sensors": self._sensordata[:, self._inertial],
            "foot_forces": self._sensordata[:, self._foot_forces],
            "touch_sensors": self._sensordata[:, self._touch],
            "actuator_state": np.array(self._act),
        }
        observation.update(self._task_observation())
        if self._observe_reward_factors:
            observation["reward_factors"] = self._reward_factors()
        return observation

    def _task_observation(self) -> dict[str, np.ndarray]:
        """The observations a subclass's task adds after the standing ones, in order."""
        return {}

    def _reward_factors(self) -> np.ndarray:
        """Every world's reward factors, float64 (num_envs, factors), in the task's order."""
        heights = self._torso_pelvis_height()
        torso_height, pelvis_height = self._stand_heights
        torso = rewards.tolerance(
            heights[:, 0], bounds=(torso_height, float("inf")), margin=torso_height, scalar=True
        )
        pelvis = rewards.tolerance(
            heights[:, 1], bounds=(pelvis_height, float("inf")), margin=pelvis_height, scalar=True
        )
        upright = rewards.tolerance(
            self._xmat[:, self._z_bodies, _ZZ],
            bounds=(self._min_upright_cosine, float("inf")),
            sigmoid="linear",
            margin=self._min_upright_cosine + 1,
            value_at_margin=0,
            scalar=False,
        )
        touch = rewards.tolerance(
            self._sensordata[:, self._touch].sum(axis=1),
            bounds=(self._body_weight, float("inf")),
            margin=self._body_weight,
            sigmoid="linear",
            value_at_margin=0.9,
            scalar=True,
        )
        return np.column_stack([torso, pelvis, upright, touch, *self._task_factors()])

    def _task_factors(self) -> list[np.ndarray]:
        """The (num_envs,) reward factors a subclass's task adds after the standing ones."""
        return []

    def get_reward(self) -> np.ndarray:
        return self._reward_factors().prod(axis=1)


class BatchMove(BatchStand):
    """`dog.Move` for every world: the standing factors and one for the torso-frame forward
    speed of the centre of mass, 1 between the task's speed and twice it, falling linearly
    to 1/5 outside."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        self._move_speed = task._move_speed

    def _task_factors(self) -> list[np.ndarray]:
        forward = rewards.tolerance(
            self._torso_com_velocity()[:, 0],
            bounds=(self._move_speed, 2 * self._move_speed),
            margin=max(1.0, self._move_speed),
            value_at_margin=0,
            sigmoid="linear",
            scalar=True,
        )
        return [(4 * forward + 1) / 5]


class BatchFetch(BatchStand):
    """`dog.Fetch` for every world: the standing factors, one for the mouth's closeness to
    the ball (1 once the ball is near the target) and one for the ball's closeness to the
    target; it observes the ball's and the target's position and the ball's velocity in
    the head's frame."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        site, geom = mujoco.mjtObj.mjOBJ_SITE, mujoco.mjtObj.mjOBJ_GEOM
        self._head = _id(model, site, "head")
        self._upper_bite = _id(model, site, "upper_bite")
        self._lower_bite = _id(model, site, "lower_bite")
        self._ball = _id(model, geom, "ball")
        self._target = _id(model, geom, "target")
        self._head_body = int(model.site_bodyid[self._head])
        self._ball_body = int(model.geom_bodyid[self._ball])
        self._bite_radius = model.site_size[self._upper_bite, 0]
        self._target_radius = model.geom_size[self._target, 0]
        self._floor_size = model.geom_size[_id(model, geom, "floor"), 0]
        self._roots = model.body_rootid
        data = physics.data
        self._site_xpos, self._site_xmat = data.site_xpos, data.site_xmat
        self._geom_xpos, self._cvel, self._subtree_com = data.geom_xpos, data.cvel, data.subtree_com

    def _linear_velocity(self, body: int, position: np.ndarray) -> np.ndarray:
        """The world-frame linear velocity of the point `position` (num_envs, 3) fixed to
        `body`, as `mj_objectVelocity` computes it: the body's spatial velocity moved from
        its root's centre of mass."""
        angular, linear = self._cvel[:, body, :3], self._cvel[:, body, 3:]
        offset = position - self._subtree_com[:, self._roots[body]]
        cross = np.column_stack(
            [
                offset[:, 1] * angular[:, 2] - offset[:, 2] * angular[:, 1],
                offset[:, 2] * angular[:, 0] - offset[:, 0] * angular[:, 2],
                offset[:, 0] * angular[:, 1] - offset[:, 1] * angular[:, 0],
            ]
        )
        return linear - cross

    def _task_observation(self) -> dict[str, np.ndarray]:
        head_frame = self._site_xmat[:, self._head]
        head = self._site_xpos[:, self._head]
        ball = self._geom_xpos[:, self._ball]
        ball_velocity = self._linear_velocity(self._ball_body, ball) - self._linear_velocity(
            self._head_body, head
        )
        return {
            "ball_state": np.concatenate(
                [_in_frame(ball - head, head_frame), _in_frame(ball_velocity, head_frame)],
                axis=1,
            ),
            "target_position": _in_frame(self._geom_xpos[:, self._target] - head, head_frame),
        }

    def _task_factors(self) -> list[np.ndarray]:
        ball = self._geom_xpos[:, self._ball]
        upper = _norm(ball - self._site_xpos[:, self._upper_bite])
        lower = _norm(ball - self._site_xpos[:, self._lower_bite])
        reach_ball = rewards.tolerance(
            0.5 * (upper + lower),
            bounds=(0, self._bite_radius),
            sigmoid="reciprocal",
            margin=2,
            scalar=True,
        )
        reach_ball = (6 * reach_ball + 1) / 7
        to_target = _norm(ball - self._geom_xpos[:, self._target])
        ball_near_target = rewards.tolerance(
            to_target,
            bounds=(0, self._target_radius),
            sigmoid="reciprocal",
            margin=self._floor_size,
            scalar=True,
        )
        fetch_ball = (ball_near_target + 1) / 2
        # Once the ball is near the target, reaching for it no longer counts.
        reach_ball = np.where(to_target < 2 * self._target_radius, 1.0, reach_ball)
        return [reach_ball, fetch_ball]


tasks.register("dm_control.suite.dog.Stand", BatchStand)
tasks.register("dm_control.suite.dog.Move", BatchMove)
tasks.register("dm_control.suite.dog.Fetch", BatchFetch)
