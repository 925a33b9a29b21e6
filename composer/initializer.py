"""Base class for objects that set up part of the simulation state at the start of an episode."""

import abc

import numpy as np


class Initializer(metaclass=abc.ABCMeta):
    """Sets part of the physics state at the start of every episode.

    Subclasses implement `__call__(physics, random_state)`, as in dm_control; a task calls
    the initializer from its own `initialize_episode(physics, random_state)` hook (inside
    `physics.reset_context()`). `initialize_episode` is the same call under the name of that
    hook.
    """

    @abc.abstractmethod
    def __call__(self, physics, random_state: np.random.RandomState) -> None:
        """Writes this initializer's part of the episode's initial state into `physics`."""

    def initialize_episode(self, physics, random_state: np.random.RandomState) -> None:
        """Calls the initializer: `initializer.initialize_episode(p, r)` is `initializer(p, r)`."""
        self(physics, random_state)
