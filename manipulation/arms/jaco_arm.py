"""JacoArm: the six-joint Jaco-style arm as a composer robot."""

import numpy as np

import composer
import mjcf
from composer.observation import observable
from manipulation.models import arm as arm_model


class JacoArm(composer.Robot):
    """A 6-DOF Kinova Jaco-style arm driven by joint velocity servos.

    The model is named 'jaco_arm' and stands on its base at the origin of its frame. The
    default configuration is the home pose, with the hand pointing down 0.3 m above the
    table. The action is one velocity (rad/s) per joint: ±0.6283 for joints 1-3 and
    ±0.8378 for joints 4-6. `attach(hand)` mounts a hand at `wrist_site`.

    Observables: `joints_pos` (6, 2), the sine and cosine of each joint angle;
    `joints_vel` (6,) in rad/s; `joints_torque` (6,), the torque (N m) each joint
    transmits, measured about its axis.
    """

    def _build(self, name: str = "jaco_arm") -> None:
        self._mjcf_root = mjcf.from_xml_string(arm_model.jaco_arm_xml())
        self._mjcf_root.model = name
        root = self._mjcf_root
        self._joints = tuple(root.find("joint", joint) for joint in arm_model.JOINT_NAMES)
        self._actuators = tuple(
            root.find("actuator", actuator) for actuator in arm_model.ACTUATOR_NAMES
        )
        self._joint_torque_sensors = tuple(
            root.find("sensor", sensor) for sensor in arm_model.TORQUE_SENSOR_NAMES
        )
        self._wrist_site = root.find("site", arm_model.WRIST_SITE_NAME)

    def _build_observables(self) -> "JacoArmObservables":
        return JacoArmObservables(self)

    @property
    def mjcf_model(self):
        return self._mjcf_root

    @property
    def joints(self) -> tuple:
        """The six hinge joints, from the shoulder to the wrist."""
        return self._joints

    @property
    def actuators(self) -> tuple:
        """The six velocity actuators, in joint order."""
        return self._actuators

    @property
    def joint_torque_sensors(self) -> tuple:
        """The 3-axis torque sensors at each joint, in joint order."""
        return self._joint_torque_sensors

    @property
    def wrist_site(self):
        """The site where the hand is mounted; its +z axis points out of the wrist."""
        return self._wrist_site

    @property
    def attachment_site(self):
        return self._wrist_site


def _consecutive_view(array: np.ndarray, indices: np.ndarray):
    """`array[indices]` as a view when the indices are consecutive, else None."""
    first = int(indices[0])
    if np.array_equal(indices, np.arange(first, first + len(indices))):
        return array[first : first + len(indices)]
    return None


class JointAngleSinCos(observable.Observable):
    """The sine and cosine of hinge joint angles, as a (n_joints, 2) array.

    Args:
      joints: the hinge joints (MJCF elements) whose angles are read, in order.
    """

    def __init__(self, joints):
        self._joints = tuple(joints)
        super().__init__(
            update_interval=1, buffer_size=None, delay=None, aggregator=None, corruptor=None
        )

    @property
    def joints(self) -> tuple:
        """The hinge joints whose `qpos` this observable reads, in the order of its rows."""
        return self._joints

    def _writer(self, physics, out):
        qpos = physics.data.ptr.qpos
        addresses = np.array(physics.bind(self._joints).qposadr)
        sines, cosines = out[:, 0], out[:, 1]
        angles = _consecutive_view(qpos, addresses)
        if angles is None:

            def write():
                gathered = qpos.take(addresses)
                np.sin(gathered, sines)
                np.cos(gathered, cosines)

        else:

            def write():
                np.sin(angles, sines)
                np.cos(angles, cosines)

        return write

    def _callable(self, physics):
        out = np.empty((len(self._joints), 2))
        write = self._writer(physics, out)

        def read():
            write()
            return out

        return read


class JointTorques(observable.Observable):
    """The torque each joint transmits: its 3-axis torque sensor projected on its axis.

    Args:
      joints: the hinge joints (MJCF elements), in order.
      sensors: one 3-axis torque sensor per joint, in the same order, whose frame is
        aligned with its joint's link frame.
    """

    def __init__(self, joints, sensors):
        self._joints = tuple(joints)
        self._sensors = tuple(sensors)
        super().__init__(
            update_interval=1, buffer_size=None, delay=None, aggregator=None, corruptor=None
        )

    @property
    def joints(self) -> tuple:
        """The hinge joints whose `axis` each torque is projected on, in order."""
        return self._joints

    @property
    def sensors(self) -> tuple:
        """The torque sensors whose `sensordata` this observable reads, in joint order."""
        return self._sensors

    def _layout(self, physics) -> tuple[np.ndarray, np.ndarray]:
        """(rows, axes), both (n_joints, 3): each sensor's rows in sensordata and each
        joint's axis. The sensor frames are aligned with the joints' link frames, where the
        axes live."""
        rows = np.array(physics.bind(self._sensors).adr)[:, None] + np.arange(3)
        return rows, np.array(physics.bind(self._joints).axis)

    def _live_source(self, physics):
        rows, axes = self._layout(physics)
        if np.all((axes == 0.0) | (axes == 1.0)) and np.all(axes.sum(1) == 1.0):
            # Each axis is a coordinate axis: each torque is one component of its sensor.
            return physics.data.ptr.sensordata, rows[axes == 1.0]
        return None

    def _callable(self, physics):
        rows, axes = self._layout(physics)
        sensordata = physics.data.ptr.sensordata
        rows = rows.ravel()
        products = np.empty(axes.shape)
        out = np.empty(len(axes))

        def read():
            np.multiply(sensordata.take(rows).reshape(axes.shape), axes, products)
            return np.add.reduce(products, 1, None, out)

        return read


class JacoArmObservables(composer.Observables):
    """Proprioception of the arm: joint angles (as sine and cosine), velocities, torques."""

    @composer.observable
    def joints_pos(self):
        return JointAngleSinCos(self._entity.joints)

    @composer.observable
    def joints_vel(self):
        return observable.MJCFFeature("qvel", list(self._entity.joints))

    @composer.observable
    def joints_torque(self):
        return JointTorques(self._entity.joints, self._entity.joint_torque_sensors)
