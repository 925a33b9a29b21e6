"""Batched readers of the arm's observables that are not MJCF features (registered with
`composer.batch.batch_reader` on import): joint angles as (sin, cos) and joint torques."""

import numpy as np

from composer import batch
from manipulation.arms.jaco_arm import JointAngleSinCos, JointTorques


@batch.batch_reader.register
def _joint_angles(observable: JointAngleSinCos, physics):
    """Every world's (sin, cos) of each joint angle, (num_envs, n_joints, 2)."""
    joints = physics.bind(list(observable.joints))
    xp = physics.xp
    return lambda: xp.stack([xp.sin(q := joints.qpos), xp.cos(q)], axis=-1)


@batch.batch_reader.register
def _joint_torques(observable: JointTorques, physics):
    """Every world's torque about each joint's axis, (num_envs, n_joints): the torque
    sensors' 3-vectors projected on the axes."""
    sensors = physics.bind(list(observable.sensors))
    axes = np.asarray(physics.host.bind(list(observable.joints)).axis, dtype=np.float32)
    device_axes = physics.arrays.asarray(axes)
    xp = physics.xp
    return lambda: xp.sum(xp.reshape(sensors.sensordata, (-1, *axes.shape)) * device_axes, axis=-1)
