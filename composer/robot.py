"""The robot: an entity that the agent's actions drive through its actuators."""

import abc

import numpy as np

from composer.entity import Entity


class Robot(Entity):
    """An entity with actuators.

    Subclasses provide `actuators` (the MJCF actuator elements the agent drives).
    `apply_action` writes an action into those actuators' controls; override it to
    map actions differently.
    """

    @property
    @abc.abstractmethod
    def actuators(self):
        """The MJCF actuator elements of this robot, in action order."""

    def apply_action(self, physics, action, random_state: np.random.RandomState) -> None:
        """Writes `action` (one value per actuator) into the actuators' controls."""
        physics.bind(self.actuators).ctrl = action
