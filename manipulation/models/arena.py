"""MJCF of the table-top arena: physics options, floor, table, lights and cameras."""

from collections.abc import Sequence

from manipulation.models import constants as c
from manipulation.models._xml import check_name, vec

TABLE_GEOM_NAME = "table_top"
CAMERA_NAMES = tuple(c.CAMERAS)


def _table() -> str:
    """The table top (its upper face is z = 0) and four legs, which are only drawn."""
    hx, hy, hz = c.TABLE_HALF_SIZE
    top = (
        f'<geom name="{TABLE_GEOM_NAME}" type="box" size="{vec((hx, hy, hz))}" '
        f'pos="0 {c.TABLE_CENTRE_Y:.6g} {-hz:.6g}" material="table" friction="1 0.005 0.0001"/>'
    )
    leg_half_height = (c.TABLE_HEIGHT - 2 * hz) / 2
    leg_size = vec((c.LEG_HALF_SIZE, c.LEG_HALF_SIZE, leg_half_height))
    inset = 2 * c.LEG_HALF_SIZE
    corners = ((-1, -1), (1, -1), (-1, 1), (1, 1))
    leg_positions = (
        (sx * (hx - inset), c.TABLE_CENTRE_Y + sy * (hy - inset), leg_half_height - c.TABLE_HEIGHT)
        for sx, sy in corners
    )
    legs = "".join(
        f'<geom name="leg_{i}" type="box" size="{leg_size}" pos="{vec(pos)}" contype="0" '
        'conaffinity="0" material="leg"/>'
        for i, pos in enumerate(leg_positions)
    )
    return top + legs


def _cameras(names: Sequence[str]) -> str:
    unknown = [name for name in names if name not in c.CAMERAS]
    if unknown or isinstance(names, str):
        raise ValueError(
            f"table_arena_xml argument 'cameras': expected a sequence of names from "
            f"{CAMERA_NAMES}, got {names!r}"
        )
    return "".join(
        f'<camera name="{name}" pos="{vec(c.CAMERAS[name][0])}" '
        f'xyaxes="{vec(c.CAMERAS[name][1])}" fovy="45"/>'
        for name in names
    )


def table_arena_xml(name: str = "arena", cameras: Sequence[str] = CAMERA_NAMES) -> str:
    """Returns the standalone MJCF of the arena.

    It sets the physics options every manipulation task relies on: a 2 ms time step and
    the `implicitfast` integrator, which keeps the arm's stiff velocity servos stable. The
    table top's upper face is the plane z = 0 and spans the workspace around the origin;
    the floor lies `constants.TABLE_HEIGHT` below. `cameras` picks which of the fixed
    cameras (`front_close`, `front_far`, `top_down`, `left_close`, `right_close`) to add.
    """
    check_name(name, "table_arena_xml")
    return (
        f'<mujoco model="{name}">'
        '<compiler angle="radian" autolimits="true"/>'
        f'<option timestep="{c.PHYSICS_TIMESTEP:.6g}" integrator="implicitfast"/>'
        "<visual>"
        '<headlight ambient="0.25 0.25 0.25" diffuse="0.3 0.3 0.3" specular="0.05 0.05 0.05"/>'
        '<global offwidth="1280" offheight="960"/>'
        '<quality shadowsize="2048"/>'
        "</visual>"
        "<asset>"
        '<texture name="skybox" type="skybox" builtin="gradient" rgb1="0.55 0.65 0.75" '
        'rgb2="0.1 0.12 0.15" width="256" height="256"/>'
        '<texture name="table" type="2d" builtin="checker" rgb1="0.56 0.46 0.36" '
        'rgb2="0.52 0.42 0.33" width="256" height="256"/>'
        '<texture name="floor" type="2d" builtin="checker" rgb1="0.3 0.32 0.35" '
        'rgb2="0.25 0.27 0.3" width="256" height="256"/>'
        '<material name="table" texture="table" texrepeat="6 6"/>'
        '<material name="floor" texture="floor" texrepeat="8 8"/>'
        '<material name="leg" rgba="0.35 0.28 0.22 1"/>'
        "</asset>"
        "<worldbody>"
        '<light name="top" pos="0 0 2.5" dir="0 0 -1" directional="true" '
        'diffuse="0.45 0.45 0.45" castshadow="true"/>'
        '<light name="front_left" pos="-1 -1.5 2" dir="1 1.5 -2" diffuse="0.2 0.2 0.2" '
        'castshadow="false"/>'
        '<light name="front_right" pos="1 -1.5 2" dir="-1 1.5 -2" diffuse="0.2 0.2 0.2" '
        'castshadow="false"/>'
        f'<geom name="floor" type="plane" size="3 3 0.1" pos="0 0 {-c.TABLE_HEIGHT:.6g}" '
        'material="floor"/>'
        f"{_table()}{_cameras(cameras)}"
        "</worldbody>"
        "</mujoco>"
    )
