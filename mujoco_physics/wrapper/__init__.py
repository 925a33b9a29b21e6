"""MuJoCo's structs with dm_control's interface, and the `mjbindings` aliases (served as
`dm_control.mujoco.wrapper`)."""

from mujoco_physics.wrapper import mjbindings
from mujoco_physics.wrapper.core import (
    Error,
    MjData,
    MjModel,
    MjrContext,
    MjvCamera,
    MjvFigure,
    MjvOption,
    MjvPerturb,
    MjvScene,
    callback_context,
    enable_timer,
    get_schema,
    save_last_parsed_model_to_xml,
    set_callback,
)

__all__ = [
    "Error",
    "MjData",
    "MjModel",
    "MjrContext",
    "MjvCamera",
    "MjvFigure",
    "MjvOption",
    "MjvPerturb",
    "MjvScene",
    "callback_context",
    "enable_timer",
    "get_schema",
    "mjbindings",
    "save_last_parsed_model_to_xml",
    "set_callback",
]
