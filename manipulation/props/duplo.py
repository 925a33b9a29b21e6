"""Duplo2x4: a Duplo-style 2x4 brick whose studs let bricks stack."""

from collections.abc import Sequence

from manipulation.models import constants, props
from manipulation.props.prop import Prop


class Duplo2x4(Prop):
    """A 25 g, 3.18 x 6.36 x 1.92 cm brick with eight studs on top.

    The origin is the centre of the bottom face, so a brick posed at height 0 rests on
    the table, and a brick is seated on another when its origin is `HEIGHT` above the
    other's along the other's z axis with their long sides parallel. With `easy_align`
    the studs are taller and rounded, and guide a brick lowered a few millimetres off its
    seat into place.

    Args (to the constructor):
      name: the model name, which scopes the brick's observables ('duplo2x4/position').
      rgba: the colour.
      easy_align: whether to use the guiding studs.
    """

    HEIGHT = constants.BRICK_HEIGHT

    def _build(
        self,
        name: str = "duplo2x4",
        rgba: Sequence[float] = (0.8, 0.1, 0.1, 1.0),
        easy_align: bool = False,
    ) -> None:
        super()._build(props.duplo_brick_xml(name=name, rgba=rgba, easy_align=easy_align))
        root = self.mjcf_model
        self._vertices = tuple(root.find("site", f"vertex_{i}") for i in range(8))
        self._bounding_box = root.find("site", "bounding_box")

    @property
    def vertices(self) -> tuple:
        """Sites at the eight corners of the brick's body (without the studs)."""
        return self._vertices

    @property
    def bounding_box(self):
        """A box site over the brick's body; its centre is the brick's centre."""
        return self._bounding_box
