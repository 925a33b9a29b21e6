"""Utilities shared by tasks: shaped rewards, rotations and inverse kinematics.

Counterparts of `dm_control.utils.rewards`, `.transformations` and `.inverse_kinematics`.
"""

from composer.utils import inverse_kinematics, rewards, transformations

__all__ = ["inverse_kinematics", "rewards", "transformations"]
