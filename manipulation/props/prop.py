"""Prop: an entity around a standalone MJCF model, observed by its pose and velocity."""

import composer
import mjcf


class PropObservables(composer.Observables, composer.FreePropObservableMixin):
    """`position`, `orientation`, `linear_velocity` and `angular_velocity` in the world frame."""


class Prop(composer.Entity):
    """An object built from a standalone MJCF string whose geoms sit in its worldbody.

    Attached with a free joint (`arena.add_free_entity`) it moves freely; attached rigidly
    it stays where it is put. Either way its observables are the pose and velocity of the
    body it is attached as (see `composer.FreePropObservableMixin`).
    """

    def _build(self, xml_string: str) -> None:
        self._mjcf_root = mjcf.from_xml_string(xml_string)

    def _build_observables(self) -> PropObservables:
        return PropObservables(self)

    @property
    def mjcf_model(self):
        return self._mjcf_root
