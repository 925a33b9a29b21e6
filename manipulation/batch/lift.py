"""`Lift` batched: every world's prop lifted off the table while the hand touches it."""

from composer import batch
from composer.utils import rewards
from manipulation.tasks import base
from manipulation.tasks.lift import Lift


class BatchLift(batch.BatchTask):
    """`Lift` for every world: the height of the prop's lowest corner, scaled to
    `lift_height`, while the hand touches the prop; 0 otherwise."""

    def after_compile(self, physics) -> None:
        task = self.task
        self._vertices = physics.bind(task.prop.vertices)
        self._touches = physics.contact_watch(
            base.entity_geom_mask(physics.host, task.hand),
            base.entity_geom_mask(physics.host, task.prop),
        )

    def get_reward(self, physics):
        xp = physics.xp
        height = xp.min(self._vertices.xpos[:, :, 2], axis=1)
        lift_height = self.task.lift_height
        progress = rewards.tolerance(
            height,
            bounds=(lift_height, float("inf")),
            margin=lift_height,
            sigmoid="linear",
            value_at_margin=0.0,
        )
        earns = (height > 0.0) & (progress > 0.0) & self._touches()
        return xp.where(earns, progress, xp.zeros_like(progress))


batch.register(Lift, BatchLift)
