"""`Lift` batched: every world's prop lifted off the table while the hand touches it."""

import numpy as np

from composer import batch
from manipulation.batch import reward_kernels
from manipulation.tasks import base
from manipulation.tasks.lift import Lift


class BatchLift(batch.BatchTask):
    """`Lift` for every world: the height of the prop's lowest corner, scaled to
    `lift_height`, while the hand touches the prop; 0 otherwise.

    The reward is one kernel (`reward_kernels.lift_reward`) after the contact watch; the
    array it returns is the task's own, rewritten by every `get_reward`.
    """

    def after_compile(self, physics) -> None:
        import warp as wp

        task = self.task
        sites = np.asarray(physics.bind(task.prop.vertices).element_id, np.int32).reshape(-1)
        self._touches = physics.contact_watch(
            base.entity_geom_mask(physics.host, task.hand),
            base.entity_geom_mask(physics.host, task.prop),
        )
        reward, self._reward = physics.arrays.empty((physics.num_envs,), np.float32)
        self._launch = wp.launch(
            reward_kernels.kernels().lift_reward,
            dim=physics.num_envs,
            inputs=[
                wp.array(sites, dtype=wp.int32, device=physics.device),
                physics.warp_data.site_xpos,
                self._touches.worlds,
                float(task.lift_height),
            ],
            outputs=[reward],
            device=physics.device,
            record_cmd=True,
        )

    def get_reward(self, physics):
        self._touches()
        self._launch.launch()
        return self._reward


batch.register(Lift, BatchLift)
