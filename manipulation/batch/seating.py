"""How far entities are from their seats on others in every world: the batched twin of
`manipulation.tasks.seating.SeatErrors`, for towers whose order may differ per world."""

from manipulation.batch import vectors
from manipulation.props import Duplo2x4


def _gather(xp, values, indices):
    """`values[w, indices[w, k]]` for every world w and k: (num_envs, m, 3) from values
    (num_envs, n, 3) and int indices (num_envs, m)."""
    shape = (*indices.shape, values.shape[-1])
    return xp.take_along_axis(values, xp.broadcast_to(indices[:, :, None], shape), axis=1)


class SeatErrors:
    """Distances of entities from their seats, for towers given per world at every call.

    An entity is seated on another when its origin is `seat_height` above the other's
    along the other's z axis, as in `manipulation.tasks.seating.SeatErrors`. Built once the
    worlds exist on the device; calling it reads the current body poses of every world.

    Args:
      physics: the `BatchPhysics` of the worlds.
      entities: the n entities a tower may be built of; a tower names them by index.
      seat_height: the height (m) of a seat above the lower entity's origin.
    """

    def __init__(self, physics, entities, seat_height: float = Duplo2x4.HEIGHT):
        self._bodies = physics.bind([entity.root_body for entity in entities])
        self._seat_height = float(seat_height)
        self._xp = physics.xp

    def __call__(self, towers):
        """The distance (m) of each tower's upper entities from their seats.

        Args:
          towers: int (num_envs, m) array of the namespace, m >= 2: each world's tower,
            entity indices bottom first.

        Returns:
          float32 (num_envs, m - 1): the distance of entity towers[w, k + 1] from its seat
          on entity towers[w, k].
        """
        xp = self._xp
        positions = self._bodies.xpos
        # The z axis of a body: elements 2, 5 and 8 of its row-major rotation matrix.
        z_axes = self._bodies.xmat[:, :, 2::3]
        lower, upper = towers[:, :-1], towers[:, 1:]
        offsets = (
            _gather(xp, positions, upper)
            - _gather(xp, positions, lower)
            - self._seat_height * _gather(xp, z_axes, lower)
        )
        return vectors.lengths(xp, offsets)
