"""Base class for objects that set up part of the simulation state at the start of an episode."""

import abc

import numpy as np


class Initializer(abc.ABC):
    """Sets part of the physics state at the start of every episode.

    Subclasses implement `initialize_episode`, which a task calls from its own
    `initialize_episode(physics, random_state)` hook (inside `physics.reset_context()`).
    """

    @abc.abstractmethod
    def initialize_episode(self, physics, random_state: np.random.RandomState) -> None:
        """Writes this initializer's part of the episode's initial state into `physics`."""
