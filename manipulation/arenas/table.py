"""TableArena: the table-top workspace every manipulation task is set in."""

from collections.abc import Sequence

import composer
import mjcf
from manipulation.models import arena as arena_model


class TableArena(composer.Arena):
    """A table whose top face is the plane z = 0, with lights and fixed cameras.

    The workspace is centred on the origin; the arm stands on the table at
    `manipulation.models.constants.ARM_OFFSET`. The model sets the physics options of the
    suite: a 2 ms time step and the implicitfast integrator, which keeps the arm's stiff
    velocity servos stable.

    Args (to the constructor):
      name: the model name.
      cameras: which fixed cameras to add, from 'front_close' (looking at the workspace
        from the front, used by the vision tasks), 'front_far', 'top_down', 'left_close'
        and 'right_close'; all of them by default.
    """

    def _build(
        self, name: str = "arena", cameras: Sequence[str] = arena_model.CAMERA_NAMES
    ) -> None:
        self._mjcf_root = mjcf.from_xml_string(arena_model.table_arena_xml(name, cameras))
        self._table_top = self._mjcf_root.find("geom", arena_model.TABLE_GEOM_NAME)

    @property
    def table_top(self):
        """The table-top geom."""
        return self._table_top

    def camera(self, name: str):
        """Returns the camera element called `name`.

        Raises:
          ValueError: if the arena has no such camera.
        """
        camera = self._mjcf_root.find("camera", name)
        if camera is None:
            cameras = [c.name for c in self._mjcf_root.find_all("camera")]
            raise ValueError(f"TableArena has no camera named {name!r}; it has {cameras}")
        return camera
