"""`Stack` batched: every world's bricks built into its desired tower, and let go of."""

import mjcf
from composer import batch
from composer.utils import rewards
from manipulation.batch.brick_tower import BatchBrickTowerTask
from manipulation.tasks import base
from manipulation.tasks import task_constants as tc
from manipulation.tasks.stack import Stack


class BatchStack(BatchBrickTowerTask):
    """`Stack` for every world: the mean over the desired tower's pairs of how well the
    upper brick sits on the lower one (1 within `SEAT_TOLERANCE`, Gaussian, 0.1 at
    `PLACE_MARGIN` beyond it), times `HELD_FACTOR` while the hand touches any brick.

    A base brick fixed to the table is placed at every reset, which writes its body's pose
    in the model: with a fixed base, `body_pos` and `body_quat` are per-world model fields.
    """

    def __init__(self, task: Stack):
        super().__init__(task)
        fixed = any(mjcf.get_frame_freejoint(brick.mjcf_model) is None for brick in task.bricks)
        self.batched_model_fields = ("body_pos", "body_quat") if fixed else ()

    def after_compile(self, physics) -> None:
        super().after_compile(physics)
        host, bricks = physics.host, self.task.bricks
        any_brick = base.entity_geom_mask(host, bricks[0])
        for brick in bricks[1:]:
            any_brick |= base.entity_geom_mask(host, brick)
        self._touches = physics.contact_watch(
            base.entity_geom_mask(host, self.task.hand), any_brick
        )

    def get_reward(self, physics):
        xp = physics.xp
        seated = rewards.tolerance(
            self.seat_errors(physics),
            bounds=(0.0, tc.SEAT_TOLERANCE),
            margin=tc.PLACE_MARGIN,
            sigmoid="gaussian",
        )
        reward = xp.mean(seated, axis=1)
        return xp.where(self._touches(), tc.HELD_FACTOR * reward, reward)


batch.register(Stack, BatchStack)
