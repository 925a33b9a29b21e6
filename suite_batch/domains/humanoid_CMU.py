"""Humanoid_CMU's `HumanoidCMU` batched: stand, walk and run.

The task is humanoid's (`suite_batch.domains.humanoid`) on the CMU model: the thorax is its
upper body, and the thorax's y axis, not its z axis, must point up.
"""

from suite_batch import tasks
from suite_batch.domains import humanoid

# The thorax's y axis's z entry of its row-major orientation matrix (dm_control's "zy").
_ZY = 7


class BatchHumanoidCMU(humanoid.BatchHumanoid):
    """`humanoid_CMU.HumanoidCMU` for every world: `BatchHumanoid`'s rewards and egocentric
    observations (it has no pure-state task) on the CMU model's thorax, head, hands and
    feet, with the thorax's y axis as the upright one."""

    TORSO = "thorax"
    HEAD = "head"
    EXTREMITIES = ("lhand", "lfoot", "rhand", "rfoot")
    CENTER_OF_MASS_VELOCITY = "thorax_subtreelinvel"
    UPRIGHT_ENTRY = _ZY


tasks.register("dm_control.suite.humanoid_CMU.HumanoidCMU", BatchHumanoidCMU)
