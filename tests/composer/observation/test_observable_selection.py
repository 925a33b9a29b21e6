"""The public `selection` of MJCF-bound observables: which element, field and index keys
they read, and that the CPU value is exactly that part of the bound field."""

import numpy as np
import pytest

import composer
import mjcf
from composer.observation import observable


class _Scene:
    """A hinge-and-slide arm with a tip site and a position sensor on it."""

    def __init__(self):
        self.model = mjcf.RootElement(model="scene")
        arm = self.model.worldbody.add("body", name="arm", pos=[0, 0, 0.5])
        self.hinge = arm.add("joint", name="hinge", type="hinge", axis=[0, 1, 0])
        self.slide = arm.add("joint", name="slide", type="slide", axis=[1, 0, 0])
        arm.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.03])
        self.tip = arm.add("site", name="tip", pos=[0.3, 0, 0])
        self.sensor = self.model.sensor.add("framepos", objtype="site", objname=self.tip)
        self.physics = mjcf.Physics.from_mjcf_model(self.model)
        self.physics.bind([self.hinge, self.slide]).qpos = [0.4, 0.1]
        self.physics.forward()


@pytest.fixture(scope="module")
def scene():
    return _Scene()


def test_site_position_feature_selects_the_site_and_xpos(scene):
    selection = observable.MJCFFeature("xpos", scene.tip).selection
    assert selection.element is scene.tip
    assert selection.field == "xpos"
    assert selection.indices == ()


def test_index_argument_is_the_selections_only_key(scene):
    selection = observable.MJCFFeature("xpos", scene.tip, index=2).selection
    assert selection.indices == (2,)


def test_indexing_a_feature_appends_each_key_and_leaves_the_original_alone(scene):
    joints = [scene.hinge, scene.slide]
    whole = observable.MJCFFeature("qpos", joints)
    indexed = whole[::-1][0]
    assert indexed.selection.element == joints
    assert indexed.selection.field == "qpos"
    assert indexed.selection.indices == (slice(None, None, -1), 0)
    assert whole.selection.indices == ()


def test_cpu_values_are_the_bound_field_indexed_by_hand(scene):
    physics = scene.physics
    tip_z = observable.MJCFFeature("xpos", scene.tip, index=2)
    slide_qpos = observable.MJCFFeature("qpos", [scene.hinge, scene.slide])[::-1][0]
    sensor_yz = observable.MJCFFeature("sensordata", scene.sensor)[1:]
    assert tip_z(physics) == physics.bind(scene.tip).xpos[2]
    assert slide_qpos(physics) == 0.1
    np.testing.assert_array_equal(sensor_yz(physics), physics.bind(scene.sensor).sensordata[1:])


def test_the_selections_reader_reads_what_the_observable_reads(scene):
    feature = observable.MJCFFeature("xpos", scene.tip)[::2]
    read = feature.selection.reader(scene.physics)
    # The tip is 0.3 + 0.1 along the arm's x axis, turned 0.4 rad about y, 0.5 m up.
    np.testing.assert_allclose(read(), [0.4 * np.cos(0.4), 0.5 - 0.4 * np.sin(0.4)])


class _Box(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="box")
        self._model.worldbody.add("geom", type="box", size=[0.05] * 3, mass=0.2)

    def _build_observables(self):
        return _BoxObservables(self)

    @property
    def mjcf_model(self):
        return self._model


class _BoxObservables(composer.Observables, composer.FreePropObservableMixin):
    pass


def test_root_body_selection_follows_the_box_to_its_attachment_frame():
    box = _Box()
    assert box.observables.position.selection.element is box.mjcf_model.worldbody
    arena = composer.Arena()
    frame = arena.add_free_entity(box)
    selection = box.observables.position.selection
    assert selection.element is frame
    assert selection.field == "xpos"
    assert selection.indices == (slice(None),)


def test_root_body_velocities_select_the_halves_of_cvel_and_read_them():
    box = _Box()
    arena = composer.Arena()
    arena.add_free_entity(box)
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    box.set_velocity(physics, velocity=[1.0, 2.0, 3.0], angular_velocity=[0.0, 0.0, 0.5])
    physics.forward()
    linear = box.observables.linear_velocity
    angular = box.observables.angular_velocity
    assert (linear.selection.field, linear.selection.indices) == ("cvel", (slice(3, 6),))
    assert (angular.selection.field, angular.selection.indices) == ("cvel", (slice(0, 3),))
    # The box's centre of mass is its body's origin: cvel is its own velocity there.
    np.testing.assert_allclose(linear(physics), [1.0, 2.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(angular(physics), [0.0, 0.0, 0.5], atol=1e-12)


def test_root_body_position_is_sampled_from_mujoco_memory():
    box = _Box()
    arena = composer.Arena()
    arena.add_free_entity(box)
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    box.set_pose(physics, position=[0.1, 0.2, 0.3])
    physics.forward()
    flat, indices = box.observables.position.live_source(physics)
    np.testing.assert_array_equal(flat[indices], [0.1, 0.2, 0.3])
    assert np.shares_memory(flat, physics.data.xpos)
