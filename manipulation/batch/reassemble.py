"""`Reassemble` batched: every world's tower rebuilt in its desired order."""

from composer import batch
from composer.utils import rewards
from manipulation.batch.brick_tower import BatchBrickTowerTask
from manipulation.tasks import task_constants as tc
from manipulation.tasks.reassemble import Reassemble


class BatchReassemble(BatchBrickTowerTask):
    """`Reassemble` for every world: the fraction of the desired tower's pairs whose upper
    brick sits on the lower one (each 1 within `SEAT_TOLERANCE`, Gaussian, 0.1 at
    `REASSEMBLE_MARGIN` beyond it)."""

    def get_reward(self, physics):
        seated = rewards.tolerance(
            self.seat_errors(physics),
            bounds=(0.0, tc.SEAT_TOLERANCE),
            margin=tc.REASSEMBLE_MARGIN,
            sigmoid="gaussian",
        )
        return physics.xp.mean(seated, axis=1)


batch.register(Reassemble, BatchReassemble)
