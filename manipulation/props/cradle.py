"""Cradle: a tray with a ring of posts that holds a placed brick."""

import composer
import mjcf
from manipulation.models import constants, props


class Cradle(composer.Entity):
    """A square tray with six posts on a 5 cm ring; its origin is the tray's bottom centre.

    A brick put down inside the ring, in any yaw, rests `SEAT_HEIGHT` above the origin.

    Args (to the constructor):
      name: the model name.
    """

    SEAT_HEIGHT = 2 * constants.CRADLE_BASE_HALF_HEIGHT

    def _build(self, name: str = "cradle") -> None:
        self._mjcf_root = mjcf.from_xml_string(props.cradle_xml(name))

    @property
    def mjcf_model(self):
        return self._mjcf_root
