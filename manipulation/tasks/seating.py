"""How far entities are from their seats on others: a brick on a brick, a brick in a cradle."""

import numpy as np

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
        self._lower = np.array([physics.bind(lower.root_body).element_id for lower, _ in pairs])
        self._upper = np.array([physics.bind(upper.root_body).element_id for _, upper in pairs])
        # Elements 2, 5 and 8 of a body's row-major rotation matrix are its z axis.
        self._lower_z = (self._lower[:, None] * 9 + np.array([2, 5, 8])).ravel()
        self._seat_height = seat_height
        data = physics.data.ptr
        self._xpos = data.xpos
        self._xmat = data.xmat.reshape(-1)

    def __call__(self) -> np.ndarray:
        """The distance (m) of each pair's upper entity from its seat on the lower one."""
        xpos = self._xpos
        up = self._xmat.take(self._lower_z).reshape(-1, 3)
        offset = xpos.take(self._upper, 0) - xpos.take(self._lower, 0) - self._seat_height * up
        return np.sqrt((offset * offset).sum(1))
