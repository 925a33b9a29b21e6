"""MJCF models of the manipulation suite, built from MuJoCo primitives.

Each function returns a standalone `<mujoco>` XML string; the composer entities in
`manipulation` wrap them. Dimensions and tuned gains live in `constants`.
"""

from manipulation.models.arena import table_arena_xml
from manipulation.models.arm import jaco_arm_xml
from manipulation.models.hand import jaco_hand_xml
from manipulation.models.props import (
    box_with_sites_xml,
    cradle_xml,
    duplo_brick_xml,
    large_box_xml,
    pedestal_xml,
)

__all__ = [
    "box_with_sites_xml",
    "cradle_xml",
    "duplo_brick_xml",
    "jaco_arm_xml",
    "jaco_hand_xml",
    "large_box_xml",
    "pedestal_xml",
    "table_arena_xml",
]
