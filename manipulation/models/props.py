"""MJCF of the props: a Duplo-style brick, boxes with corner sites, a pedestal, a cradle.

Prop geoms sit directly in the worldbody: the framework attaches a prop's model under a
frame (with a free joint for a movable prop), and that frame is the prop's body.
"""

import itertools
import math
from collections.abc import Sequence

from composer.constants import SENSOR_SITES_GROUP
from manipulation.models import constants as c
from manipulation.models._xml import check_name, check_positive, check_rgba, vec

BRICK_STUD_POSITIONS = tuple(
    (sx * c.BRICK_PITCH / 2, sy * c.BRICK_PITCH / 2) for sy in (-3, -1, 1, 3) for sx in (-1, 1)
)

_SITE = 'group="3" rgba="1 0 0 0.4"'


def _vertex_sites(half_size: Sequence[float], centre: Sequence[float]) -> str:
    """Sites `vertex_0`..`vertex_7` at the corners of a box."""
    offsets = itertools.product(*((-h, h) for h in half_size))
    return "".join(
        f'<site name="vertex_{i}" type="sphere" size="0.002" '
        f'pos="{vec(o + p for o, p in zip(offset, centre))}" {_SITE}/>'
        for i, offset in enumerate(offsets)
    )


def duplo_brick_xml(
    name: str = "duplo",
    rgba: Sequence[float] = (0.8, 0.1, 0.1, 1.0),
    easy_align: bool = False,
) -> str:
    """Returns the MJCF of a Duplo-style 2x4 brick.

    The origin is the centre of the brick's bottom face, so a brick placed at z = 0
    rests on the table. The brick is a hollow shell (top plate and four walls) with eight
    studs on top, standing on four small corner feet. The studs of a brick below fit
    inside the shell of a brick on top with 0.3 to 0.4 mm of play, which keeps a stacked
    brick seated. With `easy_align`, the studs are taller capsules whose rounded tops
    guide a brick lowered up to about 3 mm off its seat into place. Sites:
    `bounding_box` (a box site over the body without studs) and `vertex_0`..`vertex_7`
    at its corners.
    """
    check_name(name, "duplo_brick_xml")
    rgba = check_rgba(rgba, "duplo_brick_xml")
    hw, hl, height = c.BRICK_HALF_WIDTH, c.BRICK_HALF_LENGTH, c.BRICK_HEIGHT
    wall, top, lift = c.BRICK_WALL_THICKNESS, c.BRICK_TOP_THICKNESS, c.BRICK_WALL_LIFT
    wall_half_height = (height - lift) / 2
    wall_z = lift + wall_half_height
    # (name, half size, position) of the shell's boxes: the walls form the whole outside,
    # so a fingertip pressing on a side touches one geom; the top plate fits between them.
    inner = (hw - wall, hl - wall)
    boxes = (
        ("top", (*inner, top / 2), (0.0, 0.0, height - top / 2)),
        ("wall_px", (wall / 2, hl, wall_half_height), (hw - wall / 2, 0.0, wall_z)),
        ("wall_nx", (wall / 2, hl, wall_half_height), (wall / 2 - hw, 0.0, wall_z)),
        ("wall_py", (inner[0], wall / 2, wall_half_height), (0.0, hl - wall / 2, wall_z)),
        ("wall_ny", (inner[0], wall / 2, wall_half_height), (0.0, wall / 2 - hl, wall_z)),
    )
    # The brick stands on one small sphere under each corner of its walls: four contact
    # points carry it instead of the four or more that every wall box would make.
    foot = wall / 2
    feet = tuple(
        (sx * (hw - foot), sy * (hl - foot)) for sx, sy in ((-1, -1), (1, -1), (-1, 1), (1, 1))
    )
    if easy_align:
        # Capsules: a cylindrical band that holds like a plain stud, under a rounded top
        # that guides the walls of a brick lowered onto it. The lower cap is sunk into the
        # top plate.
        stud_radius, band = c.STUD_RADIUS, c.EASY_ALIGN_STUD_HEIGHT - c.STUD_RADIUS
        stud_shape = f'type="capsule" size="{stud_radius:.6g}"'
        stud_ends = (height, height + band)
        stud_volume = math.pi * stud_radius**2 * (band + 4 / 3 * stud_radius)
    else:
        stud_shape = f'type="cylinder" size="{c.STUD_RADIUS:.6g}"'
        stud_ends = (height, height + c.STUD_HEIGHT)
        stud_volume = math.pi * c.STUD_RADIUS**2 * c.STUD_HEIGHT
    foot_volume = 4 / 3 * math.pi * foot**3
    volume = sum(8 * sx * sy * sz for _, (sx, sy, sz), _ in boxes)
    volume += 8 * stud_volume + 4 * foot_volume
    density = c.BRICK_MASS / volume
    colour = vec(rgba)
    common = f'density="{density:.6g}" friction="{vec(c.BRICK_FRICTION)}" rgba="{colour}"'
    shell = "".join(
        f'<geom name="{geom}" type="box" size="{vec(size)}" pos="{vec(pos)}" {common}/>'
        for geom, size, pos in boxes
    )
    feet_xml = "".join(
        f'<geom name="foot_{i}" type="sphere" size="{foot:.6g}" pos="{vec((x, y, foot))}" '
        f"{common}/>"
        for i, (x, y) in enumerate(feet)
    )
    studs = "".join(
        f'<geom name="stud_{i}" {stud_shape} '
        f'fromto="{vec((x, y, stud_ends[0], x, y, stud_ends[1]))}" {common}/>'
        for i, (x, y) in enumerate(BRICK_STUD_POSITIONS)
    )
    half_size = (hw, hl, height / 2)
    centre = (0.0, 0.0, height / 2)
    return (
        f'<mujoco model="{name}"><worldbody>{shell}{feet_xml}{studs}'
        f'<site name="bounding_box" type="box" size="{vec(half_size)}" pos="{vec(centre)}" '
        f'group="4" rgba="0 0 1 0.2"/>'
        f"{_vertex_sites(half_size, centre)}</worldbody></mujoco>"
    )


def box_with_sites_xml(
    name: str = "box",
    half_size: float = c.SMALL_BOX_HALF_SIZE,
    mass: float = c.SMALL_BOX_MASS,
    rgba: Sequence[float] = (0.2, 0.4, 0.8, 1.0),
) -> str:
    """Returns the MJCF of a cube with a site at its centre and at each corner.

    The origin is the cube's centre. Geom `box`; sites `centre` and `vertex_0`..`vertex_7`.
    """
    check_name(name, "box_with_sites_xml")
    rgba = check_rgba(rgba, "box_with_sites_xml")
    half = (check_positive(half_size, "half_size", "box_with_sites_xml"),) * 3
    check_positive(mass, "mass", "box_with_sites_xml")
    origin = (0.0, 0.0, 0.0)
    return (
        f'<mujoco model="{name}"><worldbody>'
        f'<geom name="box" type="box" size="{vec(half)}" mass="{mass:.6g}" rgba="{vec(rgba)}"/>'
        f'<site name="centre" type="sphere" size="0.004" {_SITE}/>'
        f"{_vertex_sites(half, origin)}</worldbody></mujoco>"
    )


def large_box_xml(name: str = "box") -> str:
    """Returns the MJCF of an 18 cm, 1.3 kg cube: too large to hold in a pinch grip."""
    return box_with_sites_xml(name, c.LARGE_BOX_HALF_SIZE, c.LARGE_BOX_MASS, (0.6, 0.45, 0.3, 1))


def pedestal_xml(name: str = "pedestal") -> str:
    """Returns the MJCF of a fixed column whose flat top is the model's origin.

    `cradle_site` on the top is where a cradle (or a brick) is attached; the `target`
    site (radius `constants.TARGET_RADIUS`, in the task-site group 3) marks the goal.
    """
    check_name(name, "pedestal_xml")
    half_height = c.PEDESTAL_HEIGHT / 2
    return (
        f'<mujoco model="{name}"><worldbody>'
        f'<geom name="column" type="cylinder" size="{c.PEDESTAL_RADIUS:.6g} {half_height:.6g}" '
        f'pos="0 0 {-half_height:.6g}" rgba="0.55 0.5 0.45 1"/>'
        f'<site name="cradle_site" type="sphere" size="0.003" group="{SENSOR_SITES_GROUP}"/>'
        f'<site name="target" type="sphere" size="{c.TARGET_RADIUS:.6g}" {_SITE}/>'
        "</worldbody></mujoco>"
    )


def cradle_xml(name: str = "cradle") -> str:
    """Returns the MJCF of a tray with a ring of posts that keeps a placed brick in place.

    The origin is the centre of the tray's bottom face; a brick inside rests on the tray
    top at z = 2 * `constants.CRADLE_BASE_HALF_HEIGHT` and can turn freely between the posts.
    """
    check_name(name, "cradle_xml")
    base = c.CRADLE_BASE_HALF_HEIGHT
    plate = c.CRADLE_RADIUS + c.CRADLE_POST_RADIUS
    posts = "".join(
        f'<geom name="post_{i}" type="capsule" size="{c.CRADLE_POST_RADIUS:.6g}" '
        f'fromto="{vec((x, y, 2 * base, x, y, 2 * base + c.CRADLE_POST_HEIGHT))}" '
        'rgba="0.9 0.75 0.2 1"/>'
        for i, (x, y) in enumerate(
            (c.CRADLE_RADIUS * math.cos(a), c.CRADLE_RADIUS * math.sin(a))
            for a in (2 * math.pi * k / c.CRADLE_POSTS for k in range(c.CRADLE_POSTS))
        )
    )
    return (
        f'<mujoco model="{name}"><worldbody>'
        f'<geom name="tray" type="box" size="{vec((plate, plate, base))}" '
        f'pos="0 0 {base:.6g}" rgba="0.9 0.75 0.2 1"/>'
        f"{posts}</worldbody></mujoco>"
    )
