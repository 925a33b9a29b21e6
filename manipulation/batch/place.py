"""`Place` batched: every world's brick put on (or in) the target on its pedestal."""

import numpy as np

from composer import batch
from composer.utils import rewards
from manipulation.batch.seating import SeatErrors
from manipulation.tasks import base
from manipulation.tasks import task_constants as tc
from manipulation.tasks.place import Place


class BatchPlace(batch.BatchTask):
    """`Place` for every world: 1 when the brick is within the task's `seat_tolerance` of its
    seat on the target, Gaussian beyond (0.1 at `PLACE_MARGIN`), times `HELD_FACTOR` while
    the hand touches the brick.

    The pedestal is fixed to the table and placed at every reset, which writes its body's
    pose in the model: `body_pos` and `body_quat` are per-world model fields.
    """

    batched_model_fields = ("body_pos", "body_quat")

    def after_compile(self, physics) -> None:
        task = self.task
        self._seat_errors = SeatErrors(physics, [task.target, task.prop], task.seat_height)
        # The one pair of every world: the brick (entity 1) on the target (entity 0).
        self._tower = physics.arrays.asarray(np.tile(np.arange(2), (physics.num_envs, 1)))
        self._touches = physics.contact_watch(
            base.entity_geom_mask(physics.host, task.hand),
            base.entity_geom_mask(physics.host, task.prop),
        )

    def get_reward(self, physics):
        xp = physics.xp
        placed = rewards.tolerance(
            self._seat_errors(self._tower)[:, 0],
            bounds=(0.0, self.task.seat_tolerance),
            margin=tc.PLACE_MARGIN,
            sigmoid="gaussian",
        )
        return xp.where(self._touches(), tc.HELD_FACTOR * placed, placed)


batch.register(Place, BatchPlace)
