"""`Reach` batched: every world's pinch site brought to its target."""

from composer import batch
from composer.utils import rewards
from manipulation.batch import vectors
from manipulation.tasks import task_constants as tc
from manipulation.tasks.reach import Reach


class BatchReach(batch.BatchTask):
    """`Reach` for every world: 1 within `REACH_RADIUS` of the target, Gaussian beyond.

    A target site's position is a model parameter set at every reset, so reach_site has
    `site_pos` as a per-world model field; reach_duplo's target is the brick's own site,
    which moves with the brick's state.
    """

    def __init__(self, task: Reach):
        super().__init__(task)
        self.batched_model_fields = ("site_pos",) if task.prop is None else ()

    def after_compile(self, physics) -> None:
        self._pinch = physics.bind(self.task.hand.tool_center_point)
        self._target = physics.bind(self.task.target)

    def get_reward(self, physics):
        xp = physics.xp
        distance = vectors.lengths(xp, self._pinch.xpos - self._target.xpos)
        return rewards.tolerance(
            distance, bounds=(0.0, tc.REACH_RADIUS), margin=tc.REACH_MARGIN, sigmoid="gaussian"
        )


batch.register(Reach, BatchReach)
