"""Stack tasks: build a tower of bricks in a given order, and let go of it."""

import numpy as np

from composer import initializers
from manipulation.tasks import base, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.brick_tower import BrickTowerTask
from manipulation.tasks.observation_settings import ObservationSettings

_MAX_PLACEMENT_ATTEMPTS = 50


class Stack(BrickTowerTask):
    """Stack bricks lying on the table into a tower, bottom to top in a desired order.

    Every brick lies at a random place and yaw. Without `random_order` the tower is
    brick 0 (the base), brick 1, brick 2, ...; with it, a random choice of
    `num_to_stack` bricks in a random order, observed (with features) as
    'desired_order' (brick indices, bottom first). The reward is the mean over the
    tower's consecutive pairs of how well the upper brick sits on the lower one (1 within
    `SEAT_TOLERANCE` of its seat, Gaussian decay, 0.1 at `PLACE_MARGIN` beyond it); it is
    halved while the hand touches any brick.

    Args:
      obs_settings: which observables to enable; with features, every brick's pose and
        velocity ('duplo2x4/position', 'duplo2x4_2/position', ...).
      num_bricks: how many bricks there are.
      fixed_base: whether brick 0 is fixed to the table (it still starts at a random
        place); only without `random_order`.
      random_order: whether the tower's bricks and order are drawn every episode.
      num_to_stack: how many bricks the tower has (all of them by default).

    Raises:
      ValueError: for fewer than 2 bricks to stack, more than there are, or a fixed base
        with a random order.
    """

    def __init__(
        self,
        obs_settings: ObservationSettings,
        num_bricks: int,
        fixed_base: bool = False,
        random_order: bool = False,
        num_to_stack: int | None = None,
    ):
        num_to_stack = num_bricks if num_to_stack is None else num_to_stack
        if not 2 <= num_to_stack <= num_bricks:
            raise ValueError(
                f"Stack: num_to_stack must be between 2 and num_bricks={num_bricks}, "
                f"got {num_to_stack}"
            )
        if fixed_base and random_order:
            raise ValueError("Stack: fixed_base cannot be combined with random_order")
        super().__init__(obs_settings, num_bricks, np.arange(num_to_stack))
        for index, brick in enumerate(self._bricks):
            if index == 0 and fixed_base:
                self.arena.attach(brick)
            else:
                self.arena.add_free_entity(brick)
            self._enable_features(brick)
        self._watch_touches(self._bricks)
        self._random_order = random_order
        self._num_to_stack = num_to_stack
        if random_order:
            self._observe_desired_order()
        self._placer = initializers.PropPlacer(
            self._bricks,
            position=base.table_positions(0.0),
            quaternion=base.random_yaw(),
            max_attempts_per_prop=_MAX_PLACEMENT_ATTEMPTS,
        )

    def initialize_episode(self, physics, random_state) -> None:
        super().initialize_episode(physics, random_state)
        self._placer(physics, random_state)
        if self._random_order:
            chosen = random_state.permutation(len(self._bricks))[: self._num_to_stack]
            self._desired_order = chosen
        self._build_tower(physics)

    def get_reward(self, physics) -> float:
        reward = self._seated_fraction(tc.PLACE_MARGIN)
        if self._hand_touches():
            return tc.HELD_FACTOR * reward
        return reward


def stack_2_bricks(obs_settings: ObservationSettings) -> Stack:
    """Put a brick on a base brick fixed to the table."""
    return Stack(obs_settings, num_bricks=2, fixed_base=True)


def stack_2_bricks_moveable_base(obs_settings: ObservationSettings) -> Stack:
    """Put a brick on another brick that is free to move."""
    return Stack(obs_settings, num_bricks=2)


def stack_3_bricks(obs_settings: ObservationSettings) -> Stack:
    """Stack two bricks, in order, on a base brick fixed to the table."""
    return Stack(obs_settings, num_bricks=3, fixed_base=True)


def stack_3_bricks_random_order(obs_settings: ObservationSettings) -> Stack:
    """Stack three free bricks in an order drawn every episode."""
    return Stack(obs_settings, num_bricks=3, random_order=True)


def stack_2_of_3_bricks_random_order(obs_settings: ObservationSettings) -> Stack:
    """Put one of three free bricks on another, both drawn every episode."""
    return Stack(obs_settings, num_bricks=3, random_order=True, num_to_stack=2)


registry.add("stack_2_bricks", stack_2_bricks)
registry.add("stack_2_bricks_moveable_base", stack_2_bricks_moveable_base)
registry.add("stack_3_bricks", stack_3_bricks)
registry.add("stack_3_bricks_random_order", stack_3_bricks_random_order, vision=False)
registry.add("stack_2_of_3_bricks_random_order", stack_2_of_3_bricks_random_order)
