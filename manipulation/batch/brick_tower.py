"""`BrickTowerTask` batched: what the batched stack and reassemble tasks share, each world's
desired tower of bricks, its 'desired_order' observable and the seat errors of its
consecutive pairs."""

import numpy as np

from composer import batch
from manipulation.batch.seating import SeatErrors

_ORDER = "desired_order"


class BatchBrickTowerTask(batch.BatchTask):
    """The batched hooks of a `BrickTowerTask` (`Stack`, `Reassemble`): its `bricks` and
    per-episode `desired_order`; subclasses implement `get_reward` from `seat_errors`.

    The desired order is an episode value (`BatchTask.initial_values`), so each world's
    reward follows the tower its own episode asks for, whether the CPU task draws it every
    episode or keeps it fixed.
    """

    def initial_values(self) -> dict:
        return {_ORDER: self.task.desired_order}

    def after_compile(self, physics) -> None:
        self._seat_errors = SeatErrors(physics, self.task.bricks)

    def observable_readers(self, physics) -> dict:
        if _ORDER not in self.task.observables:
            return {}
        # The episode values exist from the first reset on; before it (an observation spec
        # reads the observables) every world shows the CPU task's value before any episode.
        order = self.task.desired_order.astype(np.float32)
        before_first_reset = physics.arrays.asarray(np.tile(order, (physics.num_envs, 1)))
        return {_ORDER: lambda: self.episode_values.get(_ORDER, before_first_reset)}

    def seat_errors(self, physics):
        """float32 (num_envs, m - 1): how far (m) each brick of each world's desired tower
        is from its seat on the brick below."""
        xp = physics.xp
        return self._seat_errors(xp.astype(self.episode_values[_ORDER], xp.int64))
