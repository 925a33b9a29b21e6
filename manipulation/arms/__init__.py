"""Arms of the manipulation suite."""

from manipulation.arms.jaco_arm import JacoArm

__all__ = ["JacoArm"]
