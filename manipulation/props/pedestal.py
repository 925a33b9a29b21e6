"""Pedestal: a fixed column whose top holds the target of the place tasks."""

import composer
import mjcf
from composer.observation import observable
from manipulation.models import props


class Pedestal(composer.Entity):
    """A column standing on the table; its flat top is the origin of its frame.

    Attach it rigidly and move it with `set_pose`; the column reaches 0.2 m below its top,
    through the table when the top is lower than that (static geometry does not collide).
    A cradle or a brick goes on top with `attach(entity)` (at `cradle_site`).

    Observables: `position` (3,), the world position of the `target` site on the top.

    Args (to the constructor):
      name: the model name, which scopes the observables ('pedestal/position').
    """

    def _build(self, name: str = "pedestal") -> None:
        self._mjcf_root = mjcf.from_xml_string(props.pedestal_xml(name))
        self._target_site = self._mjcf_root.find("site", "target")
        self._cradle_site = self._mjcf_root.find("site", "cradle_site")

    def _build_observables(self) -> "PedestalObservables":
        return PedestalObservables(self)

    @property
    def mjcf_model(self):
        return self._mjcf_root

    @property
    def target_site(self):
        """The goal marker on the top (radius 0.05 m, drawn only in site group 3)."""
        return self._target_site

    @property
    def attachment_site(self):
        return self._cradle_site


class PedestalObservables(composer.Observables):
    """The position of the pedestal's target site."""

    @composer.observable
    def position(self):
        return observable.MJCFFeature("xpos", self._entity.target_site)
