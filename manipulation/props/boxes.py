"""Boxes with sites at their centre and corners."""

from collections.abc import Sequence

from manipulation.models import constants, props
from manipulation.props.prop import Prop


class BoxWithSites(Prop):
    """A cube with a site at its centre and at each corner; its origin is its centre.

    Args (to the constructor):
      name: the model name, which scopes the box's observables.
      half_size: half the edge length (m).
      mass: the mass (kg).
      rgba: the colour.
    """

    def _build(
        self,
        name: str = "box",
        half_size: float = constants.SMALL_BOX_HALF_SIZE,
        mass: float = constants.SMALL_BOX_MASS,
        rgba: Sequence[float] = (0.2, 0.4, 0.8, 1.0),
    ) -> None:
        super()._build(props.box_with_sites_xml(name, half_size, mass, rgba))
        self._set_sites()

    def _set_sites(self) -> None:
        root = self.mjcf_model
        self._centre = root.find("site", "centre")
        self._vertices = tuple(root.find("site", f"vertex_{i}") for i in range(8))
        self._geom = root.find("geom", "box")

    @property
    def geom(self):
        """The box geom."""
        return self._geom

    @property
    def centre(self):
        """The site at the box's centre."""
        return self._centre

    @property
    def vertices(self) -> tuple:
        """The sites at the box's eight corners."""
        return self._vertices


class LargeBox(BoxWithSites):
    """An 18 cm, 1.3 kg cube: too large to hold in a pinch grip.

    Args (to the constructor):
      name: the model name, which scopes the box's observables.
    """

    HALF_SIZE = constants.LARGE_BOX_HALF_SIZE

    def _build(self, name: str = "box") -> None:
        Prop._build(self, props.large_box_xml(name))
        self._set_sites()
