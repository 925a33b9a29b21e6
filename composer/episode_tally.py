"""The steps and return of the episodes a loop runs: one tally for the viewer, `record_video`
and the Gymnasium `VideoRecorder`."""

from collections.abc import Callable
from typing import Any

import dm_env
import numpy as np

__all__ = ["EpisodeTally", "Policy"]

#: A policy as the viewer and `record_video` take it: TimeStep in, action out.
Policy = Callable[[dm_env.TimeStep], Any]


class EpisodeTally:
    """Counts the steps and sums the rewards of the current episode and of all episodes.

    A reward that is an array counts as the sum of its entries; a None reward (the first
    TimeStep of an episode) adds nothing.

    Attributes:
      steps: steps taken in all episodes.
      episodes: episodes started.
      episode_steps: steps taken in the current episode.
      episode_return: the sum of the current episode's rewards.
      last_reward: the last step's reward (summed), or None before the first step of an
        episode.
    """

    def __init__(self):
        self.steps = 0
        self.episodes = 0
        self.episode_steps = 0
        self.episode_return = 0.0
        self.last_reward: float | None = None

    def start_episode(self) -> None:
        """Starts counting a new episode."""
        self.episodes += 1
        self.episode_steps = 0
        self.episode_return = 0.0
        self.last_reward = None

    def add_step(self, reward) -> None:
        """Counts one step with `reward` (a number, an array, or None)."""
        self.steps += 1
        self.episode_steps += 1
        self.last_reward = None if reward is None else float(np.sum(reward))
        if self.last_reward is not None:
            self.episode_return += self.last_reward
