"""composer.Entity: the entity tree, poses, velocities and frames."""

import abc

import mujoco
import numpy as np
import pytest
from composer_scene import Arm, Box, Floor

import composer
import mjcf


def _compiled(arena):
    return mjcf.Physics.from_mjcf_model(arena.mjcf_model)


def _quat_about_z(angle):
    return np.array([np.cos(angle / 2), 0, 0, np.sin(angle / 2)])


def test_constructor_passes_arguments_to_build():
    box = Box(name="crate", half_size=0.2)
    assert box.mjcf_model.model == "crate"
    np.testing.assert_allclose(box.geom.size, [0.2, 0.2, 0.2])


def test_observable_options_configure_observables_at_construction():
    box = Box(observable_options={"position": {"enabled": True, "buffer_size": 3}})
    assert box.observables.position.enabled
    assert box.observables.position.buffer_size == 3
    assert not box.observables.orientation.enabled


def test_entity_without_build_cannot_be_instantiated():
    class NoBuild(composer.Entity):
        @property
        def mjcf_model(self):
            return None

    with pytest.raises(TypeError, match="_build"):
        NoBuild()


class InitPuck(composer.Entity):
    """The mistake a new user makes: building in __init__ instead of _build."""

    def __init__(self):
        self._model = mjcf.RootElement(model="puck")
        self._model.worldbody.add("geom", type="cylinder", size=[0.05, 0.02])

    def _build(self):
        pass

    @property
    def mjcf_model(self):
        return self._model


class RadiusPuck(composer.Entity):
    """Overrides __init__ too, but calls the base, which runs _build."""

    def __init__(self, radius):
        self.radius = radius
        super().__init__()

    def _build(self):
        self._model = mjcf.RootElement(model="puck")
        self._model.worldbody.add("geom", type="cylinder", size=[self.radius, 0.02])

    @property
    def mjcf_model(self):
        return self._model


_INIT_PUCK_NOT_SET_UP = (
    "InitPuck was never set up by composer.Entity.__init__ (it has no {name!r}): "
    "InitPuck.__init__ replaces Entity.__init__ without calling it. Build the model in "
    "_build(self, ...), which Entity.__init__ calls with the constructor's arguments, instead "
    "of overriding __init__; or call super().__init__(...) in InitPuck.__init__"
)


def test_attaching_an_entity_whose_init_skips_the_base_names_the_mistake_and_the_fix():
    arena = composer.Arena()
    with pytest.raises(AttributeError) as raised:
        arena.add_free_entity(InitPuck())
    assert str(raised.value) == _INIT_PUCK_NOT_SET_UP.format(name="_parent")


def test_observables_of_an_entity_whose_init_skips_the_base_name_the_mistake():
    with pytest.raises(AttributeError) as raised:
        InitPuck().observables  # noqa: B018
    assert str(raised.value) == _INIT_PUCK_NOT_SET_UP.format(name="_observables")


def test_an_init_override_that_calls_the_base_builds_and_attaches():
    arena = composer.Arena()
    puck = RadiusPuck(radius=0.07)
    arena.add_free_entity(puck)
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    assert puck.parent is arena
    assert physics.bind(puck.mjcf_model.find_all("geom")[0]).size[0] == pytest.approx(0.07)


def test_reading_observables_inside_build_says_they_are_built_after_it():
    class Early(composer.Entity):
        def _build(self):
            self._model = mjcf.RootElement(model="early")
            self.observables.enable_all()

        @property
        def mjcf_model(self):
            return self._model

    with pytest.raises(AttributeError) as raised:
        Early()
    assert str(raised.value) == (
        "Early.observables do not exist yet: Entity.__init__ builds them (with "
        "_build_observables) after _build returns, so _build cannot use them; configure them "
        "after construction, or pass observable_options to the constructor"
    )


def test_attach_returns_frame_and_sets_parent():
    arena, arm = Floor(), Arm()
    frame = arena.attach(arm)
    assert arm.parent is arena
    assert frame is mjcf.get_attachment_frame(arm.mjcf_model)
    assert arena.mjcf_model.find("site", "arm/tip") is arm.tip


def test_attach_to_named_site_puts_child_under_that_site():
    arm, box = Arm(), Box()
    arm.attach(box, attach_site="tip")
    assert mjcf.get_attachment_frame(box.mjcf_model).parent is arm.tip.parent


def test_attach_to_missing_site_names_the_site():
    arm, box = Arm(), Box()
    with pytest.raises(ValueError, match="'wrist'"):
        arm.attach(box, attach_site="wrist")


def test_attach_entity_that_already_has_a_parent_is_an_error():
    first, second, box = Floor(), Floor(name="other"), Box()
    first.attach(box)
    with pytest.raises(ValueError, match="already attached"):
        second.attach(box)


def test_attach_entity_to_itself_is_an_error():
    arena = Floor()
    with pytest.raises(ValueError, match="itself"):
        arena.attach(arena)


def test_iter_entities_is_depth_first_in_attachment_order():
    arena, arm, box, other = Floor(), Arm(), Box(), Box(name="other")
    arena.attach(arm)
    arm.attach(box, attach_site="tip")
    arena.attach(other)
    assert list(arena.iter_entities()) == [arena, arm, box, other]
    assert list(arena.iter_entities(exclude_self=True)) == [arm, box, other]


def test_detach_removes_entity_and_its_model():
    arena, box = Floor(), Box()
    arena.attach(box)
    box.detach()
    assert box.parent is None
    assert list(arena.iter_entities()) == [arena]
    assert arena.mjcf_model.find("geom", "box/geom") is None


def test_detach_unattached_entity_is_an_error():
    with pytest.raises(RuntimeError, match="not attached"):
        Box().detach()


def test_root_body_is_worldbody_when_unattached_and_frame_when_attached():
    arena, box = Floor(), Box()
    assert box.root_body is box.mjcf_model.worldbody
    frame = arena.attach(box)
    assert box.root_body is frame


def test_model_attached_with_mjcf_directly_is_carried_by_its_frame():
    arena, box = Floor(), Box()
    site = arena.mjcf_model.worldbody.add("site", name="mount", xyaxes=[0, 1, 0, -1, 0, 0])
    frame = site.attach(box.mjcf_model)
    assert box.root_body is frame
    physics = _compiled(arena)
    # The frame's x axis is the world's y axis, its y axis the world's -x axis.
    np.testing.assert_allclose(
        box.global_vector_to_local_frame(physics, [0, 1, 0]), [1, 0, 0], atol=1e-12
    )
    np.testing.assert_allclose(
        box.global_vector_to_local_frame(physics, [-1, 0]), [0, 1], atol=1e-12
    )


def test_create_root_joints_adds_a_free_joint():
    arena, box = Floor(), Box()
    frame = arena.attach(box)
    box.create_root_joints(frame)
    assert mjcf.get_freejoint(box.root_body) is not None


def test_set_pose_of_free_entity_writes_its_joint_qpos():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_pose(physics, position=[0.1, 0.2, 0.3], quaternion=_quat_about_z(0.5))
    physics.forward()
    np.testing.assert_allclose(physics.bind(box.root_body).xpos, [0.1, 0.2, 0.3])
    np.testing.assert_allclose(physics.bind(box.root_body).xquat, _quat_about_z(0.5))


def test_set_pose_of_free_entity_normalises_the_quaternion():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_pose(physics, quaternion=[2.0, 0.0, 0.0, 2.0])
    np.testing.assert_allclose(box.get_pose(physics)[1], [0.5**0.5, 0, 0, 0.5**0.5])


def test_get_pose_of_free_entity_reads_its_joint_qpos():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    physics.bind(mjcf.get_freejoint(box.root_body)).qpos = [1, 2, 3, 0, 1, 0, 0]
    position, quaternion = box.get_pose(physics)
    np.testing.assert_allclose(position, [1, 2, 3])
    np.testing.assert_allclose(quaternion, [0, 1, 0, 0])


def test_set_pose_of_fixed_entity_moves_its_frame_and_normalises_quaternion():
    arena, box = Floor(), Box()
    arena.attach(box)
    physics = _compiled(arena)
    box.set_pose(physics, position=[0.5, 0, 0.25], quaternion=[2, 0, 0, 0])
    physics.forward()
    np.testing.assert_allclose(physics.bind(box.geom).xpos, [0.5, 0, 0.25])
    position, quaternion = box.get_pose(physics)
    np.testing.assert_allclose(position, [0.5, 0, 0.25])
    np.testing.assert_allclose(quaternion, [1, 0, 0, 0])


def test_pose_of_unattached_entity_is_an_error():
    box = Box()
    physics = mjcf.Physics.from_mjcf_model(box.mjcf_model)
    with pytest.raises(RuntimeError, match="not attached"):
        box.get_pose(physics)


def test_shift_pose_adds_position_and_premultiplies_quaternion():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_pose(physics, position=[1, 0, 0], quaternion=_quat_about_z(0.25))
    box.shift_pose(physics, position=[0, 1, 0], quaternion=_quat_about_z(0.5))
    position, quaternion = box.get_pose(physics)
    np.testing.assert_allclose(position, [1, 1, 0])
    np.testing.assert_allclose(quaternion, _quat_about_z(0.75))


def test_shift_pose_with_rotate_velocity_rotates_linear_velocity():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_velocity(physics, velocity=[1, 0, 0], angular_velocity=[0, 0, 2])
    box.shift_pose(physics, quaternion=_quat_about_z(np.pi / 2), rotate_velocity=True)
    linear, angular = box.get_velocity(physics)
    np.testing.assert_allclose(linear, [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(angular, [0, 0, 2])


def test_set_velocity_then_get_velocity_round_trips():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_velocity(physics, velocity=[1, 2, 3], angular_velocity=[4, 5, 6])
    linear, angular = box.get_velocity(physics)
    np.testing.assert_allclose(linear, [1, 2, 3])
    np.testing.assert_allclose(angular, [4, 5, 6])


def test_get_velocity_of_entity_without_free_joint_is_an_error():
    arena, box = Floor(), Box()
    arena.attach(box)
    physics = _compiled(arena)
    with pytest.raises(ValueError, match="no free joint"):
        box.get_velocity(physics)


def test_global_vector_to_local_frame_undoes_the_entity_rotation():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_pose(physics, quaternion=_quat_about_z(np.pi / 2))
    physics.forward()
    local = box.global_vector_to_local_frame(physics, np.array([1.0, 0, 0]))
    np.testing.assert_allclose(local, [0, -1, 0], atol=1e-12)
    local_2d = box.global_vector_to_local_frame(physics, np.array([[0.0, 1], [1, 0]]))
    np.testing.assert_allclose(local_2d, [[1, 0], [0, -1]], atol=1e-12)


def test_global_vector_to_local_frame_rejects_other_sizes():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    with pytest.raises(ValueError, match="size 2 or 3"):
        box.global_vector_to_local_frame(physics, np.zeros(4))


def test_global_xmat_to_local_frame_expresses_rotation_relative_to_entity():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_pose(physics, quaternion=_quat_about_z(0.3))
    physics.forward()
    world = np.empty(9)
    mujoco.mju_quat2Mat(world, _quat_about_z(0.8))
    expected = np.empty(9)
    mujoco.mju_quat2Mat(expected, _quat_about_z(0.5))
    np.testing.assert_allclose(box.global_xmat_to_local_frame(physics, world), expected, atol=1e-12)


def test_model_wrapper_entity_wraps_an_existing_model():
    model = mjcf.RootElement(model="thing")
    entity = composer.ModelWrapperEntity(model)
    assert entity.mjcf_model is model
    assert list(entity.observables.as_dict()) == []


def test_free_prop_observables_report_pose_and_velocity_of_the_body():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    box.set_pose(physics, position=[0.1, 0.2, 0.3], quaternion=_quat_about_z(0.4))
    box.set_velocity(physics, velocity=[0.5, 0, 0], angular_velocity=[0, 0, 1.5])
    physics.forward()
    random_state = np.random.RandomState(0)

    def value(name):
        return getattr(box.observables, name).observation_callable(physics, random_state)()

    np.testing.assert_allclose(value("position"), [0.1, 0.2, 0.3])
    np.testing.assert_allclose(value("orientation"), _quat_about_z(0.4))
    np.testing.assert_allclose(value("linear_velocity"), [0.5, 0, 0], atol=1e-12)
    np.testing.assert_allclose(value("angular_velocity"), [0, 0, 1.5], atol=1e-12)


def test_configure_joints_sets_the_entity_own_joint_positions():
    arena, arm = Floor(), Arm()
    arena.attach(arm)
    physics = _compiled(arena)
    arm.configure_joints(physics, [0.3, -0.4])
    np.testing.assert_allclose(physics.named.data.qpos[["arm/shoulder", "arm/elbow"]], [0.3, -0.4])


def test_configure_joints_leaves_joints_of_attached_entities_alone():
    arena, arm, forearm = Floor(), Arm(), Arm()
    arena.attach(arm)
    arm.attach(forearm)
    physics = _compiled(arena)
    arm.configure_joints(physics, [0.3, -0.4])
    np.testing.assert_allclose(physics.data.qpos, [0.3, -0.4, 0.0, 0.0])
    assert [physics.model.joint(i).name for i in range(2)] == ["arm/shoulder", "arm/elbow"]


def test_configure_joints_includes_root_joints_of_attached_free_entities():
    arena, box = Floor(), Box()
    arena.add_free_entity(box)
    physics = _compiled(arena)
    arena.configure_joints(physics, [1, 2, 3, 0, 1, 0, 0])
    np.testing.assert_allclose(box.get_pose(physics)[0], [1, 2, 3])


def test_subclass_listing_abc_abc_before_entity_builds_and_stays_abstract():
    # MoMa declares its robot bases as `class RobotArm(abc.ABC, composer.Entity)`.
    class AbstractArm(abc.ABC, composer.Entity):
        @abc.abstractmethod
        def joint_count(self): ...

    class OneJointArm(AbstractArm):
        def _build(self):
            self._model = mjcf.RootElement(model="one_joint_arm")
            body = self._model.worldbody.add("body")
            body.add("joint", name="shoulder")
            body.add("geom", size=[0.05])

        @property
        def mjcf_model(self):
            return self._model

        def joint_count(self):
            return len(self._model.find_all("joint"))

    arm = OneJointArm()
    assert arm.joint_count() == 1
    assert arm.mjcf_model.model == "one_joint_arm"
    with pytest.raises(TypeError, match="joint_count"):

        class NoCount(AbstractArm):
            _build = OneJointArm._build
            mjcf_model = OneJointArm.mjcf_model

        NoCount()
