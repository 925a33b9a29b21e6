"""Batched readers of the arm's observables that are not MJCF features (registered with
`composer.batch.batch_reader` on import): joint angles as (sin, cos) and joint torques.

Both are `composer.batch.gather.FieldGather`s, read with the MJCF features by one kernel.
"""

import numpy as np

from composer import batch
from composer.batch.gather import FieldGather
from manipulation.arms.jaco_arm import JointAngleSinCos, JointTorques


def _entries(physics, elements, name: str) -> tuple:
    """(the field, the flat indices in one world's row of `name` of `elements`)."""
    field, index = physics.bind(elements).selection(name)
    if not isinstance(index, (int, slice, np.integer)):
        index = physics.arrays.to_host(index)
    every = np.arange(int(np.prod(field.c_shape))).reshape(field.c_shape)
    return field, np.asarray(every[index]).reshape(-1)


@batch.batch_reader.register
def _joint_angles(observable: JointAngleSinCos, physics):
    """Every world's (sin, cos) of each joint angle, (num_envs, n_joints, 2)."""
    field, qpos = _entries(physics, list(observable.joints), "qpos")
    entries = np.repeat(qpos[:, None, None], 2, axis=1)
    ops = np.tile(np.array(["sin", "cos"]), (qpos.size, 1))
    return FieldGather(physics, field, entries, ops=ops)


@batch.batch_reader.register
def _joint_torques(observable: JointTorques, physics):
    """Every world's torque about each joint's axis, (num_envs, n_joints): the torque
    sensors' 3-vectors projected on the axes."""
    field, sensordata = _entries(physics, list(observable.sensors), "sensordata")
    axes = np.asarray(physics.host.bind(list(observable.joints)).axis, dtype=np.float32)
    return FieldGather(physics, field, sensordata.reshape(axes.shape), weights=axes)
