"""MJCF of a three-fingered Jaco-style hand built from a cylinder, capsules and boxes."""

import math

from manipulation.models import constants as c
from manipulation.models._xml import quat_about_axis, vec

FINGER_JOINT_NAMES = ("finger_1", "finger_2", "finger_3")
FINGER_ACTUATOR_NAMES = tuple(f"{name}_velocity" for name in FINGER_JOINT_NAMES)
FINGER_BODY_NAMES = tuple(f"{name}_link" for name in FINGER_JOINT_NAMES)
PINCH_SITE_NAME = "pinch_site"

_PALM_RGBA = "0.18 0.19 0.21 1"
_FINGER_RGBA = "0.62 0.64 0.67 1"
_PAD_RGBA = "0.1 0.1 0.1 1"
_COLLIDE = f'contype="{c.ROBOT_CONTYPE}" conaffinity="{c.ROBOT_CONAFFINITY}"'


def pinch_height() -> float:
    """Height of the pinch site above the mounting face.

    It is where the pad faces touch an object of width `constants.PINCH_REFERENCE_WIDTH`
    held between them; the centre of a pad face moves on a circle about its finger hinge.
    """
    along = c.PROXIMAL_LENGTH + c.PAD_LENGTH / 2
    inward = c.PAD_INSET + c.PAD_HALF_THICKNESS
    sideways = c.PINCH_REFERENCE_WIDTH / 2 - c.FINGER_BASE_RADIUS
    return c.FINGER_HINGE_HEIGHT + math.sqrt(along**2 + inward**2 - sideways**2)


def _finger(index: int, x: float, side: float) -> str:
    """A finger whose hinge is at (x, side * base radius); side +1 is the thumb's side."""
    name = FINGER_JOINT_NAMES[index]
    body = FINGER_BODY_NAMES[index]
    # The frame of a finger on the -y side is turned half a turn about z, so every finger
    # opens towards its local +y and closes by turning about its local +x.
    quat = (1.0, 0.0, 0.0, 0.0) if side > 0 else (0.0, 0.0, 0.0, 1.0)
    splay = c.PROXIMAL_SPLAY
    direction = (0.0, math.sin(splay), math.cos(splay))
    inward = (0.0, -math.cos(splay), math.sin(splay))
    knuckle = tuple(c.PROXIMAL_LENGTH * d for d in direction)
    along = c.PROXIMAL_LENGTH + c.PAD_LENGTH / 2
    pad_pos = tuple(along * d + c.PAD_INSET * n for d, n in zip(direction, inward))
    pos = (x, side * c.FINGER_BASE_RADIUS, c.FINGER_HINGE_HEIGHT)
    return (
        f'<body name="{body}" pos="{vec(pos)}" quat="{vec(quat)}">'
        f'<joint name="{name}" type="hinge" axis="1 0 0" range="{vec(c.FINGER_RANGE)}" '
        f'armature="{c.FINGER_ARMATURE:.6g}" damping="{c.FINGER_DAMPING:.6g}"/>'
        f'<geom name="{name}_proximal" type="capsule" fromto="0 0 0 {vec(knuckle)}" '
        f'size="{c.PROXIMAL_RADIUS:.6g}" mass="{0.6 * c.FINGER_MASS:.6g}" '
        f'rgba="{_FINGER_RGBA}" {_COLLIDE}/>'
        f'<geom name="{name}_pad" type="box" pos="{vec(pad_pos)}" '
        f'quat="{vec(quat_about_axis((1.0, 0.0, 0.0), -splay))}" size="{c.PAD_HALF_WIDTH:.6g} '
        f'{c.PAD_HALF_THICKNESS:.6g} {c.PAD_LENGTH / 2:.6g}" mass="{0.4 * c.FINGER_MASS:.6g}" '
        f'friction="{vec(c.FINGER_FRICTION)}" condim="4" priority="1" '
        f'solref="{vec(c.PAD_SOLREF)}" solimp="{vec(c.PAD_SOLIMP)}" rgba="{_PAD_RGBA}" '
        f"{_COLLIDE}/>"
        "</body>"
    )


def jaco_hand_xml() -> str:
    """Returns the standalone MJCF of the hand, model name 'jaco_hand'.

    The mounting face is the model's origin and the hand points along +z. Two fingers
    (`finger_1`, `finger_2`) on the -y side oppose the thumb (`finger_3`) on the +y side;
    each finger has one hinge (0 = open, positive closes) driven by a velocity actuator
    `<finger>_velocity`. `pinch_site` is the tool centre point between the pads, with +z
    along the hand axis.
    """
    half_palm = c.PALM_LENGTH / 2
    fingers = (
        _finger(0, c.FINGER_SPACING, -1.0)
        + _finger(1, -c.FINGER_SPACING, -1.0)
        + _finger(2, 0.0, 1.0)
    )
    actuators = "".join(
        f'<velocity name="{FINGER_ACTUATOR_NAMES[i]}" joint="{FINGER_JOINT_NAMES[i]}" '
        f'kv="{c.FINGER_KV * strength:.6g}" ctrlrange="{-c.FINGER_VELOCITY_LIMIT:.6g} '
        f'{c.FINGER_VELOCITY_LIMIT:.6g}" forcerange="{-c.FINGER_TORQUE_LIMIT * strength:.6g} '
        f'{c.FINGER_TORQUE_LIMIT * strength:.6g}"/>'
        for i, strength in enumerate((1.0, 1.0, c.THUMB_STRENGTH_FACTOR))
    )
    return (
        '<mujoco model="jaco_hand">'
        '<compiler angle="radian" autolimits="true"/>'
        "<worldbody>"
        '<body name="palm">'
        f'<geom name="palm_geom" type="cylinder" size="{c.PALM_RADIUS:.6g} {half_palm:.6g}" '
        f'pos="0 0 {half_palm:.6g}" mass="{c.PALM_MASS:.6g}" rgba="{_PALM_RGBA}" {_COLLIDE}/>'
        f"{fingers}"
        f'<site name="{PINCH_SITE_NAME}" pos="0 0 {pinch_height():.6g}" size="0.006" '
        'group="4" rgba="1 0.5 0 0.6"/>'
        "</body>"
        "</worldbody>"
        f"<actuator>{actuators}</actuator>"
        "</mujoco>"
    )
