"""MJCF of a 6-DOF Jaco-style arm built from capsules and cylinders."""

from composer.constants import SENSOR_SITES_GROUP
from manipulation.models import constants as c
from manipulation.models._xml import quat_about_axis, vec

JOINT_NAMES = tuple(f"joint_{i}" for i in range(1, 7))
ACTUATOR_NAMES = tuple(f"{name}_velocity" for name in JOINT_NAMES)
TORQUE_SENSOR_NAMES = tuple(f"{name}_torque" for name in JOINT_NAMES)
TORQUE_SITE_NAMES = tuple(f"{name}_site" for name in JOINT_NAMES)
LINK_NAMES = tuple(f"link_{i}" for i in range(1, 7))
WRIST_SITE_NAME = "wrist_site"

_LINK_RGBA = "0.18 0.19 0.21 1"
_RING_RGBA = "0.62 0.64 0.67 1"
_COLLIDE = f'contype="{c.ROBOT_CONTYPE}" conaffinity="{c.ROBOT_CONAFFINITY}"'
_VISUAL = 'contype="0" conaffinity="0" group="1" mass="0"'

# Per joint: axis in its link's frame, position of the next link's frame in this link,
# and the link's capsule (from, to, radius).
_X = (1.0, 0.0, 0.0)
_Z = (0.0, 0.0, 1.0)
_E = c.ELBOW_LATERAL_OFFSET
_AXES = (_Z, _X, _X, _Z, _X, _Z)
_CHILD_OFFSETS = (
    (0.0, 0.0, c.SHOULDER_HEIGHT),
    (0.0, 0.0, c.UPPER_ARM_LENGTH),
    (_E, 0.0, c.FOREARM_LENGTH),
    (0.0, 0.0, c.WRIST_LINK_LENGTH),
    (0.0, 0.0, c.WRIST_LINK_LENGTH),
)
_CAPSULES = (
    ((0, 0, 0), (0, 0, c.SHOULDER_HEIGHT), c.SHOULDER_RADIUS),
    ((0, 0, 0), (0, 0, c.UPPER_ARM_LENGTH), c.UPPER_ARM_RADIUS),
    ((_E, 0, 0), (_E, 0, c.FOREARM_LENGTH), c.FOREARM_RADIUS),
    ((0, 0, 0), (0, 0, c.WRIST_LINK_LENGTH), c.WRIST_RADIUS),
    ((0, 0, 0), (0, 0, c.WRIST_LINK_LENGTH), c.WRIST_RADIUS),
    ((0, 0, 0), (0, 0, c.WRIST_MOUNT_LENGTH - c.WRIST_RADIUS), c.WRIST_RADIUS),
)


def _link(index: int, pos: tuple[float, float, float], inner: str) -> str:
    """One link body at `pos` in its parent: joint, torque site, geoms, then `inner`."""
    name = LINK_NAMES[index]
    axis = _AXES[index]
    joint_range = c.ARM_JOINT_RANGES[index]
    limits = f' range="{vec(joint_range)}"' if joint_range else ' limited="false"'
    start, end, radius = _CAPSULES[index]
    # A ring around each joint axis marks the motor housing.
    ring_half_length = 0.9 * radius if axis == _X else 0.02
    ring = (
        f'<geom name="{name}_ring" type="cylinder" size="{radius * 1.08:.6g} '
        f'{ring_half_length:.6g}" zaxis="{vec(axis)}" rgba="{_RING_RGBA}" {_VISUAL}/>'
    )
    # The link is written turned to its home angle, which is also the joint's reference
    # angle: the model's default configuration is the home pose, while angles keep
    # meaning "0 = straight up".
    home = c.ARM_HOME_QPOS[index]
    return (
        f'<body name="{name}" pos="{vec(pos)}" quat="{vec(quat_about_axis(axis, home))}">'
        f'<joint name="{JOINT_NAMES[index]}" type="hinge" axis="{vec(axis)}"{limits} '
        f'ref="{home:.6g}" '
        f'armature="{c.ARM_ARMATURE[index]:.6g}" damping="{c.ARM_DAMPING:.6g}"/>'
        f'<site name="{TORQUE_SITE_NAMES[index]}" size="0.005" '
        f'group="{SENSOR_SITES_GROUP}" rgba="1 0 0 0.5"/>'
        f'<geom name="{name}_geom" type="capsule" fromto="{vec(start + end)}" '
        f'size="{radius:.6g}" mass="{c.LINK_MASSES[index]:.6g}" rgba="{_LINK_RGBA}" '
        f"{_COLLIDE}/>"
        f"{ring}{inner}</body>"
    )


def _chain() -> str:
    """Nested link bodies from link 1 (shoulder) to link 6 (wrist mount)."""
    inner = (
        f'<site name="{WRIST_SITE_NAME}" pos="0 0 {c.WRIST_MOUNT_LENGTH:.6g}" '
        f'size="0.006" group="4" rgba="0 1 0 0.5"/>'
    )
    for index in range(5, -1, -1):
        pos = _CHILD_OFFSETS[index - 1] if index else (0.0, 0.0, c.BASE_HEIGHT)
        inner = _link(index, pos, inner)
    return inner


def jaco_arm_xml() -> str:
    """Returns the standalone MJCF of the arm, model name 'jaco_arm'.

    The base stands at the origin of the model's frame; joint 1 turns about +z and, at
    zero joint angles, the arm points straight up. Positive joint 2 and joint 3 angles lean
    the arm towards -y. The hand attaches at `wrist_site`, whose +z axis points out of
    the wrist. Each joint has a velocity actuator `joint_<i>_velocity` and a 3-axis torque
    sensor `joint_<i>_torque` at `joint_<i>_site` (the joint's position, aligned with its
    link's frame, so the joint torque is the sensor reading projected on the joint axis).
    """
    actuators = "".join(
        f'<velocity name="{ACTUATOR_NAMES[i]}" joint="{JOINT_NAMES[i]}" '
        f'kv="{c.ARM_KV[i]:.6g}" ctrlrange="{-c.ARM_VELOCITY_LIMITS[i]:.6g} '
        f'{c.ARM_VELOCITY_LIMITS[i]:.6g}" forcerange="{-c.ARM_TORQUE_LIMITS[i]:.6g} '
        f'{c.ARM_TORQUE_LIMITS[i]:.6g}"/>'
        for i in range(6)
    )
    sensors = "".join(
        f'<torque name="{TORQUE_SENSOR_NAMES[i]}" site="{TORQUE_SITE_NAMES[i]}"/>' for i in range(6)
    )
    half_base = c.BASE_HEIGHT / 2
    return (
        '<mujoco model="jaco_arm">'
        '<compiler angle="radian" autolimits="true"/>'
        "<worldbody>"
        '<body name="base">'
        f'<geom name="base_geom" type="cylinder" size="{c.BASE_RADIUS:.6g} {half_base:.6g}" '
        f'pos="0 0 {half_base:.6g}" mass="{c.BASE_MASS:.6g}" rgba="{_LINK_RGBA}" {_COLLIDE}/>'
        f"{_chain()}"
        "</body>"
        "</worldbody>"
        f"<actuator>{actuators}</actuator>"
        f"<sensor>{sensors}</sensor>"
        "</mujoco>"
    )
