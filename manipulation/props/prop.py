"""Prop: an entity around a standalone MJCF model, observed by its pose and velocity."""

import composer
import mjcf
from composer.entity import _RootBodyFeature
from composer.observation.observable import base


class _LiveRootBodyFeature(_RootBodyFeature):
    """A root-body feature that tells where its value lives, so that the updater gathers
    it with the others read from the same MuJoCo array instead of calling it."""

    def _live_source(self, physics):
        binding = physics.bind(self._entity.root_body)
        return base.view_source(getattr(binding, self._kind)[self._index])


class PropObservables(composer.Observables, composer.FreePropObservableMixin):
    """`position`, `orientation`, `linear_velocity` and `angular_velocity` in the world frame."""

    @composer.observable
    def position(self):
        return _LiveRootBodyFeature(self._entity, "xpos", slice(None))

    @composer.observable
    def orientation(self):
        return _LiveRootBodyFeature(self._entity, "xquat", slice(None))

    @composer.observable
    def linear_velocity(self):
        return _LiveRootBodyFeature(self._entity, "cvel", slice(3, 6))

    @composer.observable
    def angular_velocity(self):
        return _LiveRootBodyFeature(self._entity, "cvel", slice(0, 3))


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
