"""Reassemble tasks: take a tower of bricks apart and rebuild it in another order."""

import numpy as np

from composer.variation import distributions
from manipulation.props import Duplo2x4
from manipulation.tasks import base, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.brick_tower import BrickTowerTask
from manipulation.tasks.observation_settings import ObservationSettings


class Reassemble(BrickTowerTask):
    """Rebuild a tower of free bricks so that it reads, bottom to top, a desired order.

    Every episode starts with all bricks stacked into one tower at a random place and yaw
    on the table. With a fixed order the tower starts as bricks 0, 1, ..., n-1 and must be
    rebuilt upside down (n-1, ..., 0); with a random order the starting and desired orders
    are distinct random permutations, and the desired one is observed (with features) as
    'desired_order' (brick indices, bottom first). The reward is the fraction of the
    desired tower's consecutive pairs whose upper brick sits on the lower one (each pair
    counts 1 within `SEAT_TOLERANCE` of its seat, falling to 0.1 at `REASSEMBLE_MARGIN`
    beyond it).

    Args:
      obs_settings: which observables to enable; with features, every brick's pose and
        velocity ('duplo2x4/position', 'duplo2x4_2/position', ...).
      num_bricks: how many bricks the tower has (at least 2).
      random_order: whether the starting and desired orders are drawn every episode.

    Raises:
      ValueError: for fewer than 2 bricks.
    """

    def __init__(self, obs_settings: ObservationSettings, num_bricks: int, random_order: bool):
        if num_bricks < 2:
            raise ValueError(f"Reassemble: num_bricks must be at least 2, got {num_bricks}")
        self._initial_order = np.arange(num_bricks)
        super().__init__(obs_settings, num_bricks, self._initial_order[::-1].copy())
        for brick in self._bricks:
            self.arena.add_free_entity(brick)
            self._enable_features(brick)
        self._random_order = random_order
        if random_order:
            self._observe_desired_order()
        (x0, y0), (x1, y1) = tc.PROP_XY_BOUNDS
        self._tower_position = distributions.Uniform((x0, y0), (x1, y1))
        self._tower_yaw = base.random_yaw()

    def initialize_episode(self, physics, random_state) -> None:
        super().initialize_episode(physics, random_state)
        if self._random_order:
            self._initial_order = random_state.permutation(len(self._bricks))
            desired = random_state.permutation(len(self._bricks))
            while np.array_equal(desired, self._initial_order):
                desired = random_state.permutation(len(self._bricks))
            self._desired_order = desired
        x, y = self._tower_position(random_state=random_state)
        quaternion = self._tower_yaw(random_state=random_state)
        for level, index in enumerate(self._initial_order):
            height = level * Duplo2x4.HEIGHT + tc.PROP_DROP_HEIGHT
            self._bricks[index].set_pose(physics, position=(x, y, height), quaternion=quaternion)
        self._build_tower(physics)

    def get_reward(self, physics) -> float:
        return self._seated_fraction(tc.REASSEMBLE_MARGIN)


def reassemble_3_bricks_fixed_order(obs_settings: ObservationSettings) -> Reassemble:
    """Rebuild a tower of three bricks upside down."""
    return Reassemble(obs_settings, num_bricks=3, random_order=False)


def reassemble_5_bricks_random_order(obs_settings: ObservationSettings) -> Reassemble:
    """Rebuild a tower of five bricks in an order drawn every episode."""
    return Reassemble(obs_settings, num_bricks=5, random_order=True)


registry.add("reassemble_3_bricks_fixed_order", reassemble_3_bricks_fixed_order)
registry.add("reassemble_5_bricks_random_order", reassemble_5_bricks_random_order)
