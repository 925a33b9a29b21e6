"""Quadruped's `Move` and `Fetch` batched: its walk, run and fetch tasks.

`Escape` is not batched: its episode start draws a new terrain into the model's height
field (`hfield_data`), which `mujoco.batch` cannot give each world a row of, so the batch
environment refuses it.

Fetch observes world vectors in the torso's frame, which the task computes with NumPy's
`dot` (`v.dot(R)` of a vector, `S.dot(R)` of three stacked vectors) and its distances with
`np.linalg.norm`; NumPy hands all three to BLAS, whose fused multiply-adds differ in the
last bit from sums of products written out or `einsum` (measured over 6,000 fetch states:
70% of the target positions, 95% of the ball states, 10% of the distances). A
stacked `np.matmul` of the same shapes calls the same BLAS routine per world and equals
them bit for bit, and so does `np.vecdot` of a vector with itself.
"""

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# Entry of a row-major 3x3 orientation matrix, as dm_control names its xmat columns: the z
# component of the body's z axis.
_ZZ = 8

_SENSOR = mujoco.mjtSensor
#: The sensor types of the imu observation, and of the force_torque one.
_IMU_SENSORS = (_SENSOR.mjSENS_GYRO, _SENSOR.mjSENS_ACCELEROMETER)
_FORCE_TORQUE_SENSORS = (_SENSOR.mjSENS_FORCE, _SENSOR.mjSENS_TORQUE)

#: The tilt (degrees) within which the walk, run and fetch tasks count the torso upright.
_UPRIGHT_DEVIATION_DEGREES = 0


def _id(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> int:
    index = mujoco.mj_name2id(model, kind, name)
    if index < 0:
        raise ValueError(f"quadruped model: no {kind.name.removeprefix('mjOBJ_').lower()} {name!r}")
    return index


def _entries_of_sensor_types(model: mujoco.MjModel, types: tuple[int, ...]) -> np.ndarray:
    """The sensordata entries of every sensor of one of `types`, sensor by sensor in the
    order of their ids (as the task picks its sensors)."""
    sensors = np.flatnonzero(np.isin(model.sensor_type, types))
    return np.concatenate(
        [np.arange(model.sensor_adr[s], model.sensor_adr[s] + model.sensor_dim[s]) for s in sensors]
    )


def _in_frame(vectors: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Each world's `vectors.dot(frame)`: (num_envs, 3) or (num_envs, k, 3) vectors and the
    (num_envs, 9) row-major frames, by the BLAS routine of NumPy's `dot`."""
    frames = frames.reshape(-1, 3, 3)
    if vectors.ndim == 2:
        return np.matmul(vectors[:, None, :], frames)[:, 0]
    return np.matmul(vectors, frames)


def _norm(vectors: np.ndarray) -> np.ndarray:
    """Each world's `np.linalg.norm` of (num_envs, k) vectors: the square root of the BLAS
    dot product of the vector with itself."""
    return np.sqrt(np.vecdot(vectors, vectors))


class _BatchQuadruped(tasks.SuiteBatchTask):
    """What quadruped's tasks share: the observations of every task (the hinges' angles
    and velocities and the actuators' activations, the torso's velocimeter and
    uprightness, the imu and the toes' scaled forces and torques) and the uprightness
    reward factor (1 upright, falling linearly to 0 upside down)."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        hinges = model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
        self._hinge_qpos = model.jnt_qposadr[hinges]
        self._hinge_dofs = model.jnt_dofadr[hinges]
        self._torso = _id(model, mujoco.mjtObj.mjOBJ_BODY, "torso")
        velocimeter = _id(model, mujoco.mjtObj.mjOBJ_SENSOR, "velocimeter")
        start = int(model.sensor_adr[velocimeter])
        self._velocimeter = np.arange(start, start + int(model.sensor_dim[velocimeter]))
        self._imu = _entries_of_sensor_types(model, _IMU_SENSORS)
        self._force_torque = _entries_of_sensor_types(model, _FORCE_TORQUE_SENSORS)
        self._upright_cosine = np.cos(np.deg2rad(_UPRIGHT_DEVIATION_DEGREES))
        data = physics.data
        self._qpos, self._qvel, self._act = data.qpos, data.qvel, data.act
        self._xpos, self._xmat, self._sensordata = data.xpos, data.xmat, data.sensordata

    def _torso_upright(self) -> np.ndarray:
        return self._xmat[:, self._torso, _ZZ]

    def _torso_frame(self) -> np.ndarray:
        return self._xmat[:, self._torso]

    def get_observation(self) -> dict[str, np.ndarray]:
        sensordata = self._sensordata
        observation = {
            "egocentric_state": np.concatenate(
                [self._qpos[:, self._hinge_qpos], self._qvel[:, self._hinge_dofs], self._act],
                axis=1,
            ),
            "torso_velocity": sensordata[:, self._velocimeter],
            "torso_upright": np.array(self._torso_upright()),
            "imu": sensordata[:, self._imu],
            "force_torque": np.arcsinh(sensordata[:, self._force_torque]),
        }
        observation.update(self._task_observation())
        return observation

    def _task_observation(self) -> dict[str, np.ndarray]:
        """The observations a subclass's task adds after the shared ones, in order."""
        return {}

    def _upright_reward(self) -> np.ndarray:
        # The task passes the uprightness as a 0-d array: the array path.
        return rewards.tolerance(
            self._torso_upright(),
            bounds=(self._upright_cosine, float("inf")),
            sigmoid="linear",
            margin=1 + self._upright_cosine,
            value_at_margin=0,
            scalar=False,
        )


class BatchMove(_BatchQuadruped):
    """`quadruped.Move` for every world: uprightness times a forward-speed factor (the
    torso-frame velocimeter's x), 1 at or above the task's speed, falling linearly to 1/2
    at standstill and 0 at as fast backwards."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        self._desired_speed = task._desired_speed
        self._forward_speed = int(self._velocimeter[0])

    def get_reward(self) -> np.ndarray:
        move = rewards.tolerance(
            self._sensordata[:, self._forward_speed],
            bounds=(self._desired_speed, float("inf")),
            margin=self._desired_speed,
            value_at_margin=0.5,
            sigmoid="linear",
            scalar=True,
        )
        return self._upright_reward() * move


class BatchFetch(_BatchQuadruped):
    """`quadruped.Fetch` for every world: uprightness times a reach factor (the ball's
    horizontal closeness to the quadruped's workspace) times one half plus half a fetch
    factor (the ball's horizontal closeness to the target), both falling linearly from their
    radii to 0 over the arena's half diagonal; it observes the ball's position and linear
    velocity relative to the torso, its angular velocity, and the target's position, in the
    torso's frame."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        kind = mujoco.mjtObj
        self._ball = _id(model, kind.mjOBJ_BODY, "ball")
        self._target = _id(model, kind.mjOBJ_SITE, "target")
        self._workspace = _id(model, kind.mjOBJ_SITE, "workspace")
        ball_root = int(model.jnt_dofadr[_id(model, kind.mjOBJ_JOINT, "ball_root")])
        root = int(model.jnt_dofadr[_id(model, kind.mjOBJ_JOINT, "root")])
        self._ball_linear = np.arange(ball_root, ball_root + 3)
        self._ball_angular = np.arange(ball_root + 3, ball_root + 6)
        self._root_linear = np.arange(root, root + 3)
        floor = _id(model, kind.mjOBJ_GEOM, "floor")
        ball_geom = _id(model, kind.mjOBJ_GEOM, "ball")
        self._arena_radius = model.geom_size[floor, 0] * np.sqrt(2)
        self._reach_radius = model.site_size[self._workspace, 0] + model.geom_size[ball_geom, 0]
        self._target_radius = model.site_size[self._target, 0]
        self._site_xpos = physics.data.site_xpos

    def _task_observation(self) -> dict[str, np.ndarray]:
        xpos, qvel = self._xpos, self._qvel
        torso = xpos[:, self._torso]
        ball = np.stack(
            [
                xpos[:, self._ball] - torso,
                qvel[:, self._ball_linear] - qvel[:, self._root_linear],
                qvel[:, self._ball_angular],
            ],
            axis=1,
        )
        frame = self._torso_frame()
        return {
            "ball_state": _in_frame(ball, frame).reshape(-1, 9),
            "target_position": _in_frame(self._site_xpos[:, self._target] - torso, frame),
        }

    def _horizontal_distance(self, positions: np.ndarray) -> np.ndarray:
        """Each world's horizontal distance from `positions` (num_envs, 3) to the ball."""
        return _norm(positions[:, :2] - self._xpos[:, self._ball, :2])

    def get_reward(self) -> np.ndarray:
        reach = rewards.tolerance(
            self._horizontal_distance(self._site_xpos[:, self._workspace]),
            bounds=(0, self._reach_radius),
            sigmoid="linear",
            margin=self._arena_radius,
            value_at_margin=0,
            scalar=True,
        )
        fetch = rewards.tolerance(
            self._horizontal_distance(self._site_xpos[:, self._target]),
            bounds=(0, self._target_radius),
            sigmoid="linear",
            margin=self._arena_radius,
            value_at_margin=0,
            scalar=True,
        )
        return self._upright_reward() * (reach * (0.5 + 0.5 * fetch))


tasks.register("dm_control.suite.quadruped.Move", BatchMove)
tasks.register("dm_control.suite.quadruped.Fetch", BatchFetch)
