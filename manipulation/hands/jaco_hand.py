"""JacoHand: the three-fingered Jaco-style hand as a composer robot."""

import numpy as np

import composer
import mjcf
from composer.observation import observable
from manipulation.models import hand as hand_model


class JacoHand(composer.Robot):
    """A three-fingered Jaco-style hand: two fingers opposing a thumb.

    The model is named 'jaco_hand'; its mounting face is the origin of its frame and it
    points along +z. Each finger has one hinge (0 = open, 1 = fully closed) driven by a
    velocity actuator bounded by ±5 rad/s. `tool_center_point` is the pinch site between
    the finger pads; its +y axis points from the fingers towards the thumb.

    Observables: `joints_pos` (3,) and `joints_vel` (3,) of the fingers,
    `pinch_site_pos` (3,) and `pinch_site_rmat` (9,), the pinch site's world position
    and orientation matrix.
    """

    def _build(self, name: str = "jaco_hand") -> None:
        self._mjcf_root = mjcf.from_xml_string(hand_model.jaco_hand_xml())
        self._mjcf_root.model = name
        root = self._mjcf_root
        self._joints = tuple(root.find("joint", joint) for joint in hand_model.FINGER_JOINT_NAMES)
        self._actuators = tuple(
            root.find("actuator", actuator) for actuator in hand_model.FINGER_ACTUATOR_NAMES
        )
        self._pinch_site = root.find("site", hand_model.PINCH_SITE_NAME)

    def _build_observables(self) -> "JacoHandObservables":
        return JacoHandObservables(self)

    @property
    def mjcf_model(self):
        return self._mjcf_root

    @property
    def joints(self) -> tuple:
        """The three finger hinges: two fingers, then the thumb."""
        return self._joints

    @property
    def actuators(self) -> tuple:
        """The three finger velocity actuators, in joint order."""
        return self._actuators

    def set_grasp(self, physics, close_factors) -> None:
        """Sets the fingers' positions: 0 is fully open, 1 fully closed.

        Args:
          physics: the compiled physics.
          close_factors: one number for every finger or three (two fingers, then the thumb).

        Raises:
          ValueError: if a factor is outside [0, 1] or there are not 1 or 3 of them.
        """
        factors = np.asarray(close_factors, dtype=np.float64).ravel()
        if factors.size not in (1, 3) or np.any((factors < 0.0) | (factors > 1.0)):
            raise ValueError(
                f"set_grasp: close_factors must be 1 or 3 numbers in [0, 1], got {close_factors!r}"
            )
        joints = physics.bind(self._joints)
        low, high = joints.range.T
        joints.qpos = low + factors * (high - low)

    @property
    def tool_center_point(self):
        """The pinch site: where the pads meet when they grip a brick."""
        return self._pinch_site


class JacoHandObservables(composer.Observables):
    """Finger proprioception and the pose of the pinch site."""

    @composer.observable
    def joints_pos(self):
        return observable.MJCFFeature("qpos", list(self._entity.joints))

    @composer.observable
    def joints_vel(self):
        return observable.MJCFFeature("qvel", list(self._entity.joints))

    @composer.observable
    def pinch_site_pos(self):
        return observable.MJCFFeature("xpos", self._entity.tool_center_point)

    @composer.observable
    def pinch_site_rmat(self):
        return observable.MJCFFeature("xmat", self._entity.tool_center_point)
