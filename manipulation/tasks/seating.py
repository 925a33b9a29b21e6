"""How far entities are from their seats on others: a brick on a brick, a brick in a cradle."""

import math

from manipulation.props import Duplo2x4


class SeatErrors:
    """Distances of entities from their seats on other entities, for fixed (lower, upper) pairs.

    An entity is seated on another when its origin is `seat_height` above the other's
    along the other's z axis. For bricks (the default height) that is where the studs of
    the lower brick hold the upper one, its long side parallel to the lower one's. Built
    once the model is compiled; calling it reads the current body poses.

    Args:
      physics: the compiled physics.
      pairs: (lower, upper) pairs of entities.
      seat_height: the height (m) of a seat above the lower entity's origin.
    """

    def __init__(self, physics, pairs, seat_height: float = Duplo2x4.HEIGHT):
        data = physics.data.ptr
        xpos, xmat = data.xpos, data.xmat
        self._seat_height = float(seat_height)
        # Per pair, views of MuJoCo's arrays: the upper body's position, the lower body's,
        # and the lower body's z axis (elements 2, 5 and 8 of its row-major rotation matrix).
        self._views = []
        for lower, upper in pairs:
            lower_id = physics.bind(lower.root_body).element_id
            upper_id = physics.bind(upper.root_body).element_id
            self._views.append((xpos[upper_id], xpos[lower_id], xmat[lower_id, 2::3]))

    def __call__(self) -> list[float]:
        """The distance (m) of each pair's upper entity from its seat on the lower one."""
        # A few pairs: plain float arithmetic costs less than NumPy calls.
        height = self._seat_height
        distances = []
        for upper, lower, axis in self._views:
            ux, uy, uz = upper.tolist()
            lx, ly, lz = lower.tolist()
            ax, ay, az = axis.tolist()
            dx = ux - lx - height * ax
            dy = uy - ly - height * ay
            dz = uz - lz - height * az
            distances.append(math.sqrt(dx * dx + dy * dy + dz * dz))
        return distances
