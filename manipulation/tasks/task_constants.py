"""Timing, workspaces and reward scales shared by the manipulation tasks (SI units).

Positions are in the world frame: the table top is the plane z = 0 and the arm's base
stands at `manipulation.models.constants.ARM_OFFSET`, 0.4 m behind the workspace centre.
"""

import numpy as np

from manipulation.models import constants as model_constants

CONTROL_TIMESTEP = model_constants.CONTROL_TIMESTEP
PHYSICS_TIMESTEP = model_constants.PHYSICS_TIMESTEP
TIME_LIMIT = 10.0

# Orientation of a pinch site pointing straight down with its grip axis along world x.
DOWN_QUATERNION = np.array([0.0, np.sqrt(0.5), np.sqrt(0.5), 0.0])

# Where the pinch site starts an episode (lower, upper corners of a box).
TCP_BOUNDS = ((-0.1, -0.1, 0.2), (0.1, 0.1, 0.4))
# Where props are put on the table (x, y); they start at a random yaw.
PROP_XY_BOUNDS = ((-0.1, -0.1), (0.1, 0.1))
# Props are put this far above their resting height, so that they start clear of the table.
PROP_DROP_HEIGHT = 1e-4
# Where the target of the reach_site task appears.
REACH_TARGET_BOUNDS = ((-0.1, -0.1, 0.05), (0.1, 0.1, 0.3))
# Where the top of the pedestal of the place tasks is.
PEDESTAL_TOP_BOUNDS = ((-0.1, -0.1, 0.05), (0.1, 0.1, 0.15))

# Reach: full reward within REACH_RADIUS of the target, 0.1 at REACH_MARGIN beyond it.
REACH_RADIUS = 0.05
REACH_MARGIN = 0.1
# Lift: the reward grows linearly with the height of the prop's lowest corner above the
# table, from 0 on the table to 1 at LIFT_HEIGHT, while the hand touches the prop.
LIFT_HEIGHT = 0.1
# Place and stack: full reward when the prop's origin is within SEAT_TOLERANCE of where it
# rests on its target (a brick resting on unaligned studs is 4.5 mm too high), 0.1 at
# PLACE_MARGIN beyond it; half of that while the hand still touches the prop.
SEAT_TOLERANCE = 0.003
CRADLE_TOLERANCE = 0.01
PLACE_MARGIN = 0.05
HELD_FACTOR = 0.5
# Reassemble: a brick counts as seated on the one below it within SEAT_TOLERANCE, falling
# to 0.1 at REASSEMBLE_MARGIN beyond it, so that a neighbouring seat earns almost nothing.
REASSEMBLE_MARGIN = 0.005

# The colours of the bricks, in the order the tasks create them.
BRICK_COLOURS = (
    (0.8, 0.1, 0.1, 1.0),
    (0.1, 0.55, 0.15, 1.0),
    (0.15, 0.3, 0.85, 1.0),
    (0.9, 0.75, 0.1, 1.0),
    (0.6, 0.2, 0.7, 1.0),
)
