"""Dimensions, masses and tuned gains of the manipulation models (SI units, radians).

The arm's link lengths are the published kinematic offsets of a Kinova Jaco 2 with a
spherical wrist (j2s6s300); the masses follow that arm's published link masses. Everything
else (the hand, the props, the arena) is this project's own design.
"""

# Physics timing shared by every manipulation task.
PHYSICS_TIMESTEP = 0.002
CONTROL_TIMESTEP = 0.04
SUBSTEPS_PER_CONTROL_STEP = 20

# --- Arm -------------------------------------------------------------------------------
# Joint-to-joint offsets along the chain (metres).
BASE_HEIGHT = 0.15675  # table to joint 1
SHOULDER_HEIGHT = 0.11875  # joint 1 to joint 2
UPPER_ARM_LENGTH = 0.410  # joint 2 to joint 3
FOREARM_LENGTH = 0.2073  # joint 3 to joint 4
ELBOW_LATERAL_OFFSET = 0.0098  # sideways offset of the forearm from the upper arm
WRIST_LINK_LENGTH = 0.10375  # joint 4 to joint 5 and joint 5 to joint 6
WRIST_MOUNT_LENGTH = 0.045  # joint 6 to the hand mounting face (the wrist site)

# Link radii of the capsule geoms (metres).
BASE_RADIUS = 0.05
SHOULDER_RADIUS = 0.045
UPPER_ARM_RADIUS = 0.04
FOREARM_RADIUS = 0.035
WRIST_RADIUS = 0.03

# Link masses (kg): base, links 1..6.
BASE_MASS = 0.468
LINK_MASSES = (0.748, 0.990, 0.676, 0.426, 0.426, 0.250)

# Joint ranges (radians); None means the joint turns without limit.
ARM_JOINT_RANGES = (None, (-2.32, 2.32), (-2.81, 2.81), None, (-2.6, 2.6), None)

# Home pose, the model's default configuration: the hand points down at the workspace
# centre, 0.3 m above the table. IK from here reaches the whole workspace.
ARM_HOME_QPOS = (0.0, 0.3, 1.6, 0.0, 1.25, -1.5708)

# Velocity actuators: command bounds (rad/s), servo gain (N m s/rad), torque limit (N m).
ARM_VELOCITY_LIMITS = (0.6283, 0.6283, 0.6283, 0.8378, 0.8378, 0.8378)
ARM_KV = (4000.0, 4000.0, 4000.0, 500.0, 500.0, 500.0)
ARM_TORQUE_LIMITS = (40.0, 40.0, 40.0, 12.0, 12.0, 12.0)
# Reflected rotor inertia of the geared joint motors (kg m^2).
ARM_ARMATURE = (0.05, 0.05, 0.05, 0.02, 0.02, 0.02)
ARM_DAMPING = 0.1

# --- Hand ------------------------------------------------------------------------------
PALM_RADIUS = 0.038
PALM_LENGTH = 0.06
PALM_MASS = 0.55
# Finger layout: two fingers on one side of the palm oppose a thumb on the other. Each
# finger is a straight capsule link ending in a flat pad; a finger turns about one hinge.
FINGER_HINGE_HEIGHT = 0.055  # from the mounting face along the hand axis
FINGER_BASE_RADIUS = 0.0264  # distance of each finger hinge from the hand axis
FINGER_SPACING = 0.022  # sideways distance of the two fingers from the hand's mid-plane
PROXIMAL_LENGTH = 0.05
PROXIMAL_RADIUS = 0.008
PROXIMAL_SPLAY = 0.55  # outward tilt of a fully open finger from the hand axis
PAD_LENGTH = 0.026
PAD_HALF_WIDTH = 0.009
PAD_HALF_THICKNESS = 0.0045
PAD_INSET = 0.006  # inward offset of the pad's centre from the finger's centre line
FINGER_MASS = 0.05
FINGER_RANGE = (0.0, 1.0)  # 0 is fully open
FINGER_ARMATURE = 0.002
FINGER_DAMPING = 0.01
FINGER_VELOCITY_LIMIT = 5.0
FINGER_KV = 0.3
FINGER_TORQUE_LIMIT = 0.3
# The thumb faces two fingers, so it gets twice their gain and torque: the grip is then
# balanced for any closing command and the held object does not drift towards the thumb.
THUMB_STRENGTH_FACTOR = 2.0
# The pads' contacts (pads have priority, so these apply to every pad contact) are stiffer
# than MuJoCo's default: squeezing a 25 g brick must not sink the pads into it.
FINGER_FRICTION = (1.2, 0.02, 0.001)
PAD_SOLREF = (0.005, 1.0)
PAD_SOLIMP = (0.95, 0.99, 0.001)
# Width of the object whose grasp defines where the pinch site sits between the pads.
PINCH_REFERENCE_WIDTH = 0.0318

# --- Duplo-style 2x4 brick -------------------------------------------------------------
BRICK_HALF_WIDTH = 0.0159  # x
BRICK_HALF_LENGTH = 0.0318  # y
BRICK_HEIGHT = 0.0192  # body height, without the studs
BRICK_WALL_THICKNESS = 0.0028
BRICK_TOP_THICKNESS = 0.003
BRICK_WALL_LIFT = 0.0005  # walls end this far above the feet the brick stands on
BRICK_PITCH = 0.016
STUD_RADIUS = 0.0047
STUD_HEIGHT = 0.0045
EASY_ALIGN_STUD_HEIGHT = 0.0065  # capsule studs: 1.8 mm straight band, then a dome
BRICK_MASS = 0.025
BRICK_FRICTION = (0.5, 0.005, 0.0001)  # plastic on plastic

# --- Boxes, pedestal, cradle -----------------------------------------------------------
SMALL_BOX_HALF_SIZE = 0.025
SMALL_BOX_MASS = 0.1
LARGE_BOX_HALF_SIZE = 0.09
LARGE_BOX_MASS = 1.3
PEDESTAL_RADIUS = 0.07
PEDESTAL_HEIGHT = 0.2
TARGET_RADIUS = 0.05
CRADLE_RADIUS = 0.05  # radius of the ring of posts that holds a placed object
CRADLE_POST_RADIUS = 0.008
CRADLE_POST_HEIGHT = 0.02
CRADLE_BASE_HALF_HEIGHT = 0.004
CRADLE_POSTS = 6

# --- Arena -----------------------------------------------------------------------------
# The table top is the plane z = 0; the workspace is centred on the origin and the arm's
# base stands on the table at ARM_OFFSET, facing the workspace (-y).
ARM_OFFSET = (0.0, 0.4, 0.0)
TABLE_HALF_SIZE = (0.6, 0.5, 0.02)
TABLE_CENTRE_Y = 0.0
TABLE_HEIGHT = 0.75
LEG_HALF_SIZE = 0.03

# Camera poses (position, xyaxes) looking at the workspace.
CAMERAS = {
    "front_close": ((0.0, -0.6, 0.75), (1.0, 0.0, 0.0, 0.0, 0.7, 0.75)),
    "front_far": ((0.0, -0.8, 1.0), (1.0, 0.0, 0.0, 0.0, 0.7, 0.75)),
    "top_down": ((0.0, 0.0, 2.5), (1.0, 0.0, 0.0, 0.0, 1.0, 0.0)),
    "left_close": ((-0.6, 0.0, 0.75), (0.0, -1.0, 0.0, 0.7, 0.0, 0.75)),
    "right_close": ((0.6, 0.0, 0.75), (0.0, 1.0, 0.0, -0.7, 0.0, 0.75)),
}

# Geom collision bits: the arm and hand collide with everything else but not each other.
ROBOT_CONTYPE = 2
ROBOT_CONAFFINITY = 1
