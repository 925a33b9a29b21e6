"""`Lift` batched: every world's prop lifted off the table while the hand touches it."""

import numpy as np

from composer import batch
from composer.utils import rewards
from manipulation.batch import reward_kernels
from manipulation.tasks import base
from manipulation.tasks.lift import Lift


class BatchLift(batch.BatchTask):
    """`Lift` for every world: the height of the prop's lowest corner, scaled to
    `lift_height`, while the hand touches the prop; 0 otherwise.

    On MuJoCo Warp the reward is one kernel (`reward_kernels.lift_reward`) after the contact
    watch, and the array it returns is the task's own, rewritten by every `get_reward`. On
    the CPU batch it is the CPU task's formula on NumPy arrays, whose contacts are looked up
    only in the worlds whose prop is off the table (`Lift.get_reward`'s order).
    """

    def after_compile(self, physics) -> None:
        task = self.task
        sites = np.asarray(physics.bind(task.prop.vertices).element_id, np.int32).reshape(-1)
        self._touches = physics.contact_watch(
            base.entity_geom_mask(physics.host, task.hand),
            base.entity_geom_mask(physics.host, task.prop),
        )
        self._on_warp = physics.on_warp
        if not physics.on_warp:
            self._vertices = physics.bind(task.prop.vertices)
            return
        import warp as wp

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
        if not self._on_warp:
            return self._host_reward()
        self._touches()
        self._launch.launch()
        return self._reward

    def _host_reward(self) -> np.ndarray:
        lift_height = float(self.task.lift_height)
        height = np.minimum.reduce(self._vertices.xpos[..., 2], axis=1)
        progress = rewards.tolerance(
            height,
            bounds=(lift_height, np.inf),
            margin=lift_height,
            sigmoid="linear",
            value_at_margin=0.0,
        )
        candidates = (height > 0.0) & (progress != 0.0)
        if not candidates.any():
            return np.zeros_like(height)
        return np.where(candidates & self._touches(candidates), progress, 0.0)


batch.register(Lift, BatchLift)
