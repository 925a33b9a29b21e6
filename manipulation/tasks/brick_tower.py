"""What the brick-tower tasks (stack, reassemble) share: their bricks, the tower's desired
order, its 'desired_order' observable and how well the tower's bricks sit on each other."""

import numpy as np

from composer.observation import observable
from composer.utils import rewards
from manipulation.tasks import base, bricks
from manipulation.tasks import task_constants as tc
from manipulation.tasks.observation_settings import ObservationSettings
from manipulation.tasks.seating import SeatErrors


class BrickTowerTask(base.ManipulationTask):
    """A task whose goal is a tower of bricks in a desired order, bottom first.

    Subclasses add the bricks to the arena, draw each episode's order in
    `initialize_episode` and then call `_build_tower`; `_seated_fraction` is their reward.

    Args:
      obs_settings: which observables to enable.
      num_bricks: how many bricks to make (`bricks.make_bricks`).
      desired_order: the tower's brick indices, bottom first, until an episode draws
        another.
    """

    def __init__(
        self, obs_settings: ObservationSettings, num_bricks: int, desired_order: np.ndarray
    ):
        super().__init__(obs_settings)
        self._bricks = bricks.make_bricks(num_bricks)
        self._desired_order = desired_order
        self._seat_errors = None

    @property
    def bricks(self) -> list:
        return list(self._bricks)

    @property
    def desired_order(self) -> np.ndarray:
        """Indices of the tower's bricks, bottom first, for the current episode."""
        return self._desired_order.copy()

    def _observe_desired_order(self) -> None:
        """Adds 'desired_order' (float brick indices), enabled with features."""
        self._add_feature_observable(
            "desired_order",
            observable.Generic(lambda physics: self._desired_order.astype(float)),
        )

    def _build_tower(self, physics) -> None:
        """Watches the seats of the desired tower's consecutive pairs this episode."""
        tower = [self._bricks[i] for i in self._desired_order]
        self._seat_errors = SeatErrors(physics, list(zip(tower[:-1], tower[1:])))

    def _seated_fraction(self, margin: float) -> float:
        """The mean over the tower's pairs of how well the upper brick sits on the lower:
        1 within `SEAT_TOLERANCE` of its seat, Gaussian decay to 0.1 at `margin` beyond."""
        seated = [
            rewards.tolerance(
                error, bounds=(0.0, tc.SEAT_TOLERANCE), margin=margin, sigmoid="gaussian"
            )
            for error in self._seat_errors()
        ]
        return sum(seated) / len(seated)
