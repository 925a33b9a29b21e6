"""MuJoCo's enums, constants, array sizes and functions under dm_control's `mjbindings`
names, all read from the installed `mujoco` (served as
`dm_control.mujoco.wrapper.mjbindings`)."""

from mujoco_physics.wrapper.mjbindings import constants, enums, functions, sizes
from mujoco_physics.wrapper.mjbindings.functions import mjlib

__all__ = ["constants", "enums", "functions", "mjlib", "sizes"]
