"""Tests for physics.bind on real mjcf models, including attached models."""

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf.physics import Physics


class _Scene:
    """A scene built with the mjcf API: a free ball, a two-link arm, and an attached robot."""

    def __init__(self):
        root = mjcf.RootElement(model="scene")
        self.root = root
        worldbody = root.worldbody
        self.ball_body = worldbody.add("body", name="ball_body", pos=[0, 0, 1])
        self.free = self.ball_body.add("freejoint", name="free")
        self.ball = self.ball_body.add("geom", name="ball", size=[0.1], rgba=[1, 0, 0, 1])
        self.ball_site = self.ball_body.add("site", name="ball_site")
        self.arm = worldbody.add("body", name="arm", pos=[1, 0, 1])
        self.hinge = self.arm.add(
            "joint", name="hinge", type="hinge", axis=[0, 1, 0], range=[-45, 90], damping=0.25
        )
        self.upper = self.arm.add(
            "geom", name="upper", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.04]
        )
        self.forearm = self.arm.add("body", name="forearm", pos=[0.3, 0, 0])
        self.ball_joint = self.forearm.add("joint", name="ball_joint", type="ball")
        self.lower = self.forearm.add(
            "geom", name="lower", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.03]
        )
        self.tip = self.forearm.add("site", name="tip", pos=[0.3, 0, 0])
        self.target = worldbody.add("body", name="target", mocap=True, pos=[0, 1, 1])
        self.target.add("geom", name="target_geom", size=[0.05], contype=0, conaffinity=0)
        self.motor = root.actuator.add("motor", name="motor", joint=self.hinge, gear=[2])
        self.filtered = root.actuator.add(
            "general", name="filtered", joint=self.hinge, dyntype="filter", dynprm=[0.1]
        )
        self.tip_pos = root.sensor.add("framepos", name="tip_pos", objtype="site", objname=self.tip)
        self.hinge_pos = root.sensor.add("jointpos", name="hinge_pos", joint=self.hinge)
        self.tendon = root.tendon.add("fixed", name="coupling")
        self.tendon.add("joint", joint=self.hinge, coef=2)

        robot = mjcf.RootElement(model="robot")
        self.robot = robot
        self.robot_base = robot.worldbody.add("body", name="base", pos=[0, 0, 0.5])
        self.robot_geom = self.robot_base.add("geom", name="base_geom", size=[0.1])
        self.robot_site = self.robot_base.add("site", name="sensor_site", pos=[0.1, 0.2, 0.3])
        self.robot_joint = self.robot_base.add("joint", name="slide", type="slide")
        self.frame = worldbody.attach(robot)
        self.frame.pos = [2, 0, 0]
        self.physics = Physics.from_mjcf_model(root)

    def object_id(self, obj_type, name):
        return mujoco.mj_name2id(self.physics.model.ptr, obj_type, name)


@pytest.fixture
def scene():
    return _Scene()


def test_single_geom_position_is_a_3_vector(scene):
    xpos = scene.physics.bind(scene.ball).xpos
    assert xpos.shape == (3,)
    np.testing.assert_array_equal(xpos, [0, 0, 1])


def test_single_element_scalar_field_reads_as_a_scalar(scene):
    mass = scene.physics.bind(scene.ball_body).mass
    assert np.ndim(mass) == 0
    assert mass == pytest.approx(1000 * 4 / 3 * np.pi * 0.1**3)


def test_list_binding_has_one_row_per_element(scene):
    rgba = scene.physics.bind([scene.ball, scene.upper, scene.lower]).rgba
    assert rgba.shape == (3, 4)
    np.testing.assert_array_equal(rgba[0], [1, 0, 0, 1])


def test_list_of_one_element_keeps_the_list_dimension(scene):
    assert scene.physics.bind([scene.ball]).xpos.shape == (1, 3)


def test_attached_site_position_is_in_world_coordinates(scene):
    np.testing.assert_allclose(scene.physics.bind(scene.robot_site).xpos, [2.1, 0.2, 0.8])


def test_hinge_qpos_is_one_wide(scene):
    assert scene.physics.bind(scene.hinge).qpos.shape == (1,)


def test_ball_joint_qpos_is_a_quaternion(scene):
    np.testing.assert_array_equal(scene.physics.bind(scene.ball_joint).qpos, [1, 0, 0, 0])


def test_free_joint_qpos_is_position_and_quaternion(scene):
    np.testing.assert_array_equal(scene.physics.bind(scene.free).qpos, [0, 0, 1, 1, 0, 0, 0])


def test_free_joint_qvel_is_six_wide(scene):
    assert scene.physics.bind(scene.free).qvel.shape == (6,)


def test_joint_list_qpos_concatenates_each_joint(scene):
    physics = scene.physics
    physics.data.qpos[:] = np.arange(physics.model.nq)
    hinge = scene.object_id(mujoco.mjtObj.mjOBJ_JOINT, "hinge")
    ball = scene.object_id(mujoco.mjtObj.mjOBJ_JOINT, "ball_joint")
    hinge_adr = physics.model.jnt_qposadr[hinge]
    ball_adr = physics.model.jnt_qposadr[ball]
    expected = np.concatenate(
        [physics.data.qpos[ball_adr : ball_adr + 4], physics.data.qpos[hinge_adr : hinge_adr + 1]]
    )
    np.testing.assert_array_equal(physics.bind([scene.ball_joint, scene.hinge]).qpos, expected)


def test_joint_dof_fields_drop_the_dof_prefix(scene):
    assert scene.physics.bind(scene.hinge).damping == pytest.approx([0.25])


def test_joint_range_reads_the_compiled_model_in_radians(scene):
    np.testing.assert_allclose(scene.physics.bind(scene.hinge).range, [-np.pi / 4, np.pi / 2])


def test_actuator_control_is_a_scalar_that_writes_ctrl(scene):
    physics = scene.physics
    physics.bind(scene.motor).ctrl = 0.75
    assert physics.bind(scene.motor).ctrl == 0.75
    assert physics.data.ctrl[scene.object_id(mujoco.mjtObj.mjOBJ_ACTUATOR, "motor")] == 0.75


def test_actuator_gear_is_six_wide(scene):
    np.testing.assert_array_equal(scene.physics.bind(scene.motor).gear, [2, 0, 0, 0, 0, 0])


def test_actuator_force_follows_the_control(scene):
    physics = scene.physics
    physics.bind(scene.motor).ctrl = 0.5
    physics.forward()
    assert physics.bind(scene.motor).force == pytest.approx(0.5)
    assert physics.bind(scene.hinge).qfrc_actuator == pytest.approx([1.0])


def test_actuator_activation_exists_only_for_stateful_actuators(scene):
    physics = scene.physics
    physics.data.act[:] = [0.125]
    assert physics.bind(scene.filtered).act == 0.125
    np.testing.assert_array_equal(physics.bind([scene.motor, scene.filtered]).act, [0.125])
    assert physics.bind(scene.motor).act.size == 0


def test_three_dimensional_sensor_reads_three_values(scene):
    sensordata = scene.physics.bind(scene.tip_pos).sensordata
    np.testing.assert_allclose(sensordata, [1.6, 0, 1])


def test_sensor_list_concatenates_readings(scene):
    physics = scene.physics
    values = physics.bind([scene.hinge_pos, scene.tip_pos]).sensordata
    assert values.shape == (4,)
    np.testing.assert_allclose(values, [0, 1.6, 0, 1])


def test_tendon_length_follows_the_joint(scene):
    physics = scene.physics
    physics.bind(scene.hinge).qpos = 0.25
    assert physics.bind(scene.tendon).length == pytest.approx(0.5)


def test_worldbody_binds_to_the_world_body(scene):
    np.testing.assert_array_equal(scene.physics.bind(scene.root.worldbody).xpos, [0, 0, 0])


def test_attachment_frame_binds_as_a_body(scene):
    np.testing.assert_array_equal(scene.physics.bind(scene.frame).xpos, [2, 0, 0])


def test_attribute_write_changes_the_model(scene):
    physics = scene.physics
    physics.bind(scene.ball).rgba = [0, 1, 0, 1]
    np.testing.assert_array_equal(
        physics.model.geom_rgba[scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, "ball")], [0, 1, 0, 1]
    )


def test_item_write_on_a_consecutive_list_writes_through(scene):
    physics = scene.physics
    geoms = [scene.upper, scene.lower]
    physics.bind(geoms).rgba[:, 3] = 0.5
    for name in ("upper", "lower"):
        assert physics.model.geom_rgba[scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, name), 3] == 0.5


def test_item_write_on_a_scattered_list_writes_through(scene):
    physics = scene.physics
    geoms = [scene.lower, scene.ball, scene.robot_geom]
    physics.bind(geoms).rgba[:, 3] = 0.25
    for name in ("lower", "ball", "robot/base_geom"):
        assert physics.model.geom_rgba[scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, name), 3] == 0.25


def test_item_write_on_a_scattered_list_keeps_rows_updated_elsewhere(scene):
    physics = scene.physics
    bound = physics.bind([scene.lower, scene.ball])
    rgba = bound.rgba
    ball = scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, "ball")
    physics.model.geom_rgba[ball] = [0, 0, 1, 1]
    rgba[0, 0] = 0.5
    np.testing.assert_array_equal(physics.model.geom_rgba[ball], [0, 0, 1, 1])


def test_scattered_list_reads_fresh_values_after_a_step(scene):
    physics = scene.physics
    bound = physics.bind([scene.ball_body, scene.forearm])
    before = bound.xpos.copy()
    physics.step(20)
    assert bound.xpos[0, 2] < before[0, 2]


def test_qpos_write_is_seen_by_a_later_position_read(scene):
    physics = scene.physics
    physics.bind(scene.hinge).qpos = np.pi / 2
    # Rotating +90 degrees about y turns the arm's x axis into -z.
    np.testing.assert_allclose(physics.bind(scene.tip).xpos, [1, 0, 0.4], atol=1e-12)


def test_item_write_to_joint_list_is_seen_by_a_later_position_read(scene):
    physics = scene.physics
    physics.bind([scene.hinge, scene.robot_joint]).qpos[1] = 0.5  # slides along z
    np.testing.assert_allclose(physics.bind(scene.robot_site).xpos, [2.1, 0.2, 1.3])


def test_item_write_to_consecutive_joints_is_seen_by_a_later_position_read(scene):
    physics = scene.physics
    physics.bind([scene.hinge, scene.ball_joint]).qpos[0] = np.pi / 2
    np.testing.assert_allclose(physics.bind(scene.tip).xpos, [1, 0, 0.4], atol=1e-12)


def test_derived_read_after_write_refreshes_only_once(scene):
    physics = scene.physics
    physics.bind(scene.hinge).qpos = 0.1
    assert physics.is_dirty
    _ = physics.bind(scene.tip).xpos
    assert not physics.is_dirty


def test_geom_position_write_moves_a_geom_that_shared_its_body_frame(scene):
    physics = scene.physics
    ball = scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, "ball")
    assert physics.model.geom_sameframe[ball] != 0
    physics.bind(scene.ball).pos = [0.5, 0, 0]
    np.testing.assert_allclose(physics.bind(scene.ball).xpos, [0.5, 0, 1])


def test_mocap_position_moves_a_mocap_body(scene):
    physics = scene.physics
    physics.bind(scene.target).mocap_pos = [3, 2, 1]
    np.testing.assert_array_equal(physics.bind(scene.target).xpos, [3, 2, 1])


def test_mocap_position_of_a_regular_body_is_an_error(scene):
    with pytest.raises(AttributeError, match="mocap_pos"):
        _ = scene.physics.bind(scene.arm).mocap_pos


def test_column_names_index_a_binding(scene):
    physics = scene.physics
    bound = physics.bind([scene.ball_body, scene.forearm])
    np.testing.assert_allclose(bound["xpos", ["x", "z"]], [[0, 1], [1.3, 1]])
    np.testing.assert_array_equal(bound["xpos"], bound.xpos)


def test_column_write_through_a_binding(scene):
    physics = scene.physics
    physics.bind([scene.ball, scene.upper])["rgba", "g"] = 0.75
    np.testing.assert_array_equal(physics.bind([scene.ball, scene.upper]).rgba[:, 1], [0.75, 0.75])


def test_element_id_matches_mujoco_ids(scene):
    physics = scene.physics
    geom = mujoco.mjtObj.mjOBJ_GEOM
    assert physics.bind(scene.ball).element_id == scene.object_id(geom, "ball")
    np.testing.assert_array_equal(
        physics.bind([scene.lower, scene.robot_geom]).element_id,
        [scene.object_id(geom, "lower"), scene.object_id(geom, "robot/base_geom")],
    )


def test_binding_the_same_elements_again_returns_the_cached_binding(scene):
    physics = scene.physics
    assert physics.bind(scene.ball) is physics.bind(scene.ball)
    assert physics.bind([scene.ball, scene.upper]) is physics.bind([scene.ball, scene.upper])
    assert physics.bind([scene.ball, scene.upper]) is physics.bind((scene.ball, scene.upper))


def test_binding_a_generator_binds_its_elements(scene):
    physics = scene.physics
    bound = physics.bind(geom for geom in (scene.ball, scene.upper))
    assert bound is physics.bind([scene.ball, scene.upper])


def test_binding_none_is_value_error(scene):
    with pytest.raises(ValueError, match="None"):
        scene.physics.bind(None)


def test_empty_binding_reads_empty_arrays(scene):
    assert scene.physics.bind([]).xpos.shape == (0,)


def test_empty_binding_rejects_writes(scene):
    with pytest.raises(ValueError, match="no elements"):
        scene.physics.bind([]).qpos = 1


def test_element_of_another_model_is_an_error_naming_it(scene):
    other = mjcf.RootElement(model="other")
    stranger = other.worldbody.add("geom", name="ball", size=[1])
    with pytest.raises(ValueError, match=r"<geom name='ball'>.*another model"):
        scene.physics.bind(stranger)


def test_element_added_after_compiling_is_an_error(scene):
    late = scene.root.worldbody.add("geom", name="late", size=[1])
    with pytest.raises(ValueError, match="no geom named 'late'"):
        scene.physics.bind(late)


def test_element_without_a_compiled_object_is_an_error(scene):
    with pytest.raises(ValueError, match="<compiler>"):
        scene.physics.bind(scene.root.compiler)


def test_mixed_element_kinds_are_an_error(scene):
    with pytest.raises(ValueError, match=r"<geom name='ball'>.*<joint name='hinge'>"):
        scene.physics.bind([scene.ball, scene.hinge])


def test_unknown_attribute_suggests_close_names(scene):
    with pytest.raises(AttributeError, match="did you mean.*xpos"):
        _ = scene.physics.bind(scene.ball).xposs


def test_binding_lists_its_attributes(scene):
    attributes = dir(scene.physics.bind(scene.hinge))
    assert {"qpos", "qvel", "range", "damping", "armature", "qfrc_actuator"} <= set(attributes)


class _FakeSpec:
    def __init__(self, namespace):
        self.namespace = namespace


class _FakeElement:
    """The element interface bind relies on, without the mjcf model layer."""

    def __init__(self, tag, namespace, full_identifier):
        self.tag = tag
        self.spec = _FakeSpec(namespace)
        self.full_identifier = full_identifier
        self.root = None


def test_binds_any_element_with_the_mjcf_interface():
    physics = Physics.from_xml_string(
        '<mujoco><worldbody><body name="b" pos="1 2 3"><joint name="j"/>'
        '<geom name="g" size="1"/></body></worldbody></mujoco>'
    )
    body = _FakeElement("body", "body", "b")
    np.testing.assert_array_equal(physics.bind(body).xpos, [1, 2, 3])
    assert physics.bind(_FakeElement("joint", "joint", "j")).qpos.shape == (1,)


def test_element_of_a_detached_model_is_an_error(scene):
    scene.robot.detach()
    with pytest.raises(ValueError, match="<site name='sensor_site'>.*another model"):
        scene.physics.bind(scene.robot_site)


def test_non_element_in_a_list_is_an_error_naming_its_position(scene):
    with pytest.raises(ValueError, match="item 1 is a NoneType"):
        scene.physics.bind([scene.ball, None])


def test_augmented_item_assignment_on_a_scattered_list_writes_through(scene):
    physics = scene.physics
    bound = physics.bind([scene.lower, scene.ball])
    bound.rgba[:, 3] *= 0.5
    ball = scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, "ball")
    assert physics.model.geom_rgba[ball, 3] == 0.5


def test_boolean_mask_assignment_on_a_scattered_list_writes_through(scene):
    physics = scene.physics
    rgba = physics.bind([scene.lower, scene.ball]).rgba
    rgba[rgba == 0] = 0.125
    ball = scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, "ball")
    np.testing.assert_array_equal(physics.model.geom_rgba[ball], [1, 0.125, 0.125, 1])


def test_mocap_and_other_bodies_cannot_be_bound_together(scene):
    with pytest.raises(ValueError, match="mocap"):
        scene.physics.bind([scene.ball_body, scene.target])


def test_binding_constructed_by_namespace_and_names(scene):
    from mjcf import physics as physics_module

    bound = physics_module.Binding(scene.physics, "geom", ["ball", "upper"])
    np.testing.assert_array_equal(bound.rgba[0], [1, 0, 0, 1])
    with pytest.raises(ValueError, match="invalid_namespace"):
        physics_module.Binding(scene.physics, "invalid_namespace", "x")


def test_writing_derived_field_while_dirty_keeps_written_value(scene):
    physics = scene.physics
    physics.bind(scene.motor).ctrl = 0.5
    assert physics.is_dirty
    physics.bind([scene.tip_pos]).sensordata = 7.0
    assert not physics.is_dirty
    np.testing.assert_array_equal(physics.bind([scene.tip_pos]).sensordata, [7.0, 7.0, 7.0])


def test_reload_from_xml_string_drops_earlier_bindings(scene):
    physics = scene.physics
    before = physics.bind(scene.ball)
    physics.reload_from_xml_string(scene.root.to_xml_string(), assets=scene.root.get_assets())
    after = physics.bind(scene.ball)
    assert after is not before
    np.testing.assert_array_equal(after.rgba, [1, 0, 0, 1])


def test_attached_models_worldbody_binds_its_attachment_frame():
    scene = mjcf.RootElement(model="scene")
    arm = mjcf.RootElement(model="arm")
    arm.worldbody.add("geom", size=[0.1], mass=2)
    frame = scene.attach(arm)
    frame.pos = [0, 0, 3]
    physics = mjcf.Physics.from_mjcf_model(scene)
    bound = physics.bind(arm.worldbody)
    assert bound.element_id == physics.bind(frame).element_id
    np.testing.assert_allclose(bound.xpos, [0, 0, 3])
    assert physics.bind(scene.worldbody).element_id == 0


def test_pickling_a_bound_array_is_refused_but_a_copy_pickles():
    import pickle

    model = mjcf.RootElement()
    for z in (0.3, 0.6):
        model.worldbody.add("body", pos=[0.1, 0.2, z]).add("geom", size=[0.1])
    physics = mjcf.Physics.from_mjcf_model(model)
    xpos = physics.bind(model.find_all("body")).xpos
    with pytest.raises(NotImplementedError, match="np.array"):
        pickle.dumps(xpos)
    np.testing.assert_allclose(
        pickle.loads(pickle.dumps(np.array(xpos))), [[0.1, 0.2, 0.3], [0.1, 0.2, 0.6]]
    )


def test_error_inside_a_childs_tag_surfaces_from_the_tag_property():
    import traceback

    model = mjcf.RootElement()
    object.__setattr__(model.worldbody, "_spec", None)
    with pytest.raises(AttributeError) as raised:
        model.worldbody  # noqa: B018
    assert traceback.extract_tb(raised.tb)[-1].name == "tag"


def test_item_write_with_row_and_column_on_a_scattered_list_writes_that_row(scene):
    physics = scene.physics
    rgba = physics.bind([scene.lower, scene.ball]).rgba
    rgba[1, 0] = 0.25
    ball = scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, "ball")
    np.testing.assert_array_equal(physics.model.geom_rgba[ball], [0.25, 0, 0, 1])


def test_bound_array_repr_is_that_of_its_values(scene):
    rgba = scene.physics.bind(scene.ball).rgba
    assert repr(rgba) == "array([1., 0., 0., 1.], dtype=float32)"


def test_bound_array_copy_is_c_ordered_unless_asked_otherwise(scene):
    xpos = scene.physics.bind([scene.ball_body, scene.forearm]).xpos
    transposed = xpos.T.copy()
    assert type(transposed) is np.ndarray
    assert transposed.flags.c_contiguous
    np.testing.assert_allclose(transposed, [[0, 1.3], [0, 0], [1, 1]])
    fortran = xpos.copy(order="F")
    assert fortran.flags.f_contiguous and not fortran.flags.c_contiguous
    np.testing.assert_allclose(fortran, [[0, 0, 1], [1.3, 0, 1]])


def test_pickling_a_bound_array_names_its_type_in_the_error(scene):
    import pickle

    with pytest.raises(NotImplementedError) as raised:
        pickle.dumps(scene.physics.bind(scene.ball).rgba)
    assert str(raised.value) == (
        "a <class 'mjcf.binding._BoundArray'> cannot be pickled: it reads and writes the live "
        "simulation; pickle a copy instead (np.array(bound_array))"
    )


def test_binding_constructed_by_namespace_and_one_name(scene):
    from mjcf import physics as physics_module

    scene.physics.named.data.qpos["hinge"] = 0.5
    bound = physics_module.Binding(scene.physics, "joint", "hinge")
    assert bound.qpos.shape == (1,)
    assert bound.qpos[0] == 0.5
    assert bound.element_id == scene.object_id(mujoco.mjtObj.mjOBJ_JOINT, "hinge")
    assert type(bound.element_id) is int
    np.testing.assert_allclose(bound.range, np.radians([-45, 90]))
    assert bound.range.shape == (2,)
    assert repr(bound) == "Binding(<joint name='hinge'>)"


def test_binding_constructed_by_namespace_and_names_describes_them(scene):
    from mjcf import physics as physics_module

    bound = physics_module.Binding(scene.physics, "geom", ["ball", "upper"])
    assert repr(bound) == "Binding([2 geom])"


def test_binding_constructed_with_a_missing_name_says_which(scene):
    from mjcf import physics as physics_module

    with pytest.raises(ValueError) as raised:
        physics_module.Binding(scene.physics, "joint", ["hinge", "elbow"])
    assert str(raised.value) == "the model has no joint named 'elbow'"


def test_item_assignment_by_attribute_name_writes_the_field(scene):
    physics = scene.physics
    physics.bind(scene.hinge)["damping"] = 0.75
    physics.bind(scene.ball)["pos"] = [0.1, 0.2, 0.3]
    hinge_dof = physics.model.jnt_dofadr[scene.object_id(mujoco.mjtObj.mjOBJ_JOINT, "hinge")]
    assert physics.model.dof_damping[hinge_dof] == 0.75
    ball = scene.object_id(mujoco.mjtObj.mjOBJ_GEOM, "ball")
    np.testing.assert_array_equal(physics.model.geom_pos[ball], [0.1, 0.2, 0.3])


def test_binding_dir_lists_methods_and_fields(scene):
    assert {"element_id", "qpos", "range"} <= set(dir(scene.physics.bind(scene.hinge)))


def test_one_column_label_reads_a_scalar(scene):
    height = scene.physics.bind(scene.ball_body)["xpos", "z"]
    assert np.ndim(height) == 0
    assert height == 1.0


@pytest.mark.parametrize(
    "columns, expected",
    [(3, [1, 1]), ([0, 3], [[1, 1], [0.5, 1]]), (slice(2, None), [[0, 1], [0.5, 1]])],
)
def test_integer_and_slice_columns_index_a_binding(scene, columns, expected):
    physics = scene.physics
    physics.bind(scene.upper).rgba = [0.5, 0.5, 0.5, 1]
    np.testing.assert_array_equal(
        physics.bind([scene.ball, scene.upper])["rgba", columns], expected
    )


def test_unknown_column_label_is_a_key_error_listing_the_labels(scene):
    with pytest.raises(KeyError) as raised:
        _ = scene.physics.bind(scene.ball)["rgba", "w"]
    assert raised.value.args[0] == (
        "field 'geom_rgba' has no column 'w'; columns are ('r', 'g', 'b', 'a')"
    )


def test_column_label_of_a_one_dimensional_field_is_a_key_error():
    # Three hinges make qpos three long: its length must not pass for x, y, z columns.
    root = mjcf.RootElement()
    body = root.worldbody
    for name in ("a", "b", "c"):
        body = body.add("body", name=name)
        body.add("joint", name=name)
        body.add("geom", size=[0.1])
    physics = Physics.from_mjcf_model(root)
    with pytest.raises(KeyError) as raised:
        _ = physics.bind(root.find("joint", "a"))["qpos", "x"]
    assert raised.value.args[0] == "field 'qpos' has no column labels; got 'x'"


def test_missing_mocap_row_error_names_the_attribute_and_body(scene):
    with pytest.raises(AttributeError) as raised:
        _ = scene.physics.bind(scene.arm).mocap_pos
    assert str(raised.value) == (
        "<body name='arm'> has no attribute 'mocap_pos': body 'arm' has no row in mocap_pos"
    )


def test_empty_binding_repr(scene):
    assert repr(scene.physics.bind([])) == "Binding()"


def test_empty_binding_can_be_copied(scene):
    import copy

    copied = copy.deepcopy(scene.physics.bind([]))
    assert copied.xpos.shape == (0,)
    assert copy.copy(scene.physics.bind([])).qpos.shape == (0,)


def test_worldbody_binds_together_with_other_bodies(scene):
    bound = scene.physics.bind([scene.root.worldbody, scene.arm])
    np.testing.assert_array_equal(bound.xpos, [[0, 0, 0], [1, 0, 1]])


@pytest.mark.parametrize("mocap_first", [True, False])
def test_mixing_mocap_and_other_bodies_error_says_which_is_mocap(scene, mocap_first):
    bodies = [scene.target, scene.arm] if mocap_first else [scene.arm, scene.target]
    with pytest.raises(ValueError) as raised:
        scene.physics.bind(bodies)
    assert str(raised.value) == (
        "cannot bind mocap and other bodies together: <body name='target'> is a mocap body, "
        "<body name='arm'> is not"
    )


def _stranger(model_name):
    return mjcf.RootElement(model=model_name).worldbody.add("geom", name="ball", size=[1])


@pytest.mark.parametrize(
    ("make_element", "message"),
    [
        (
            lambda scene: _stranger("other"),
            "cannot bind <geom name='ball'>: it belongs to another model ('other'), not to the "
            "model compiled into this Physics ('scene')",
        ),
        (
            lambda scene: _stranger("scene"),
            "cannot bind <geom name='ball'>: it belongs to another model ('scene'), not to the "
            "model compiled into this Physics ('scene'); they are different objects of the "
            "same name (a copy made by pickling or copy.deepcopy binds its own elements, not "
            "the original's)",
        ),
        (
            # The mjcf interface, but no root.
            lambda scene: _FakeElement("geom", "geom", "ball"),
            "cannot bind <geom name='ball'>: it belongs to another model ('unnamed model'), not "
            "to the model compiled into this Physics ('scene')",
        ),
        (
            lambda scene: scene.root.worldbody.add("geom", name="late", size=[1]),
            "cannot bind <geom name='late'>: the model compiled into this Physics has no geom "
            "named 'late'",
        ),
        (
            lambda scene: scene.root.compiler,
            "cannot bind <compiler>: <compiler> elements are not compiled into a MuJoCo object",
        ),
    ],
    ids=["other_model", "same_named_model", "no_model", "added_after_compiling", "compiler"],
)
def test_element_that_cannot_be_bound_error_in_full(scene, make_element, message):
    element = make_element(scene)
    with pytest.raises(ValueError) as raised:
        scene.physics.bind(element)
    assert str(raised.value) == message


def test_frame_element_error_says_it_has_no_fields():
    root = mjcf.RootElement()
    frame = root.worldbody.add("frame", name="offset")
    frame.add("geom", size=[1])
    physics = Physics.from_mjcf_model(root)
    with pytest.raises(ValueError) as raised:
        physics.bind(frame)
    assert str(raised.value) == "cannot bind <frame name='offset'>: no MuJoCo fields for 'frame'"


def test_non_element_in_a_list_error_names_its_type(scene):
    with pytest.raises(ValueError) as raised:
        scene.physics.bind([scene.ball, 5])
    assert str(raised.value) == "bind expects mjcf elements; item 1 is a int"


def test_describe_names_a_non_element_by_its_type():
    from mjcf.binding import describe

    assert describe(object()) == "<object>"


@pytest.mark.parametrize(
    "elements, expected",
    [
        (lambda scene: scene.ball, "Binding(<geom name='ball'>)"),
        (lambda scene: [scene.ball], "Binding([<geom name='ball'>])"),
        (lambda scene: [scene.ball, scene.upper], "Binding([2 geom elements])"),
    ],
)
def test_binding_repr_describes_its_elements(scene, elements, expected):
    assert repr(scene.physics.bind(elements(scene))) == expected


def test_unknown_attribute_without_close_names_says_only_that(scene):
    with pytest.raises(AttributeError) as raised:
        _ = scene.physics.bind(scene.ball).zzzz
    assert str(raised.value) == "<geom name='ball'> has no attribute 'zzzz'"


def test_unknown_attribute_suggests_at_most_three_names(scene):
    with pytest.raises(AttributeError) as raised:
        _ = scene.physics.bind(scene.arm).poss  # pos, xpos, ipos and xipos are all close
    assert str(raised.value) == (
        "<body name='arm'> has no attribute 'poss'; did you mean pos, xpos, ipos?"
    )


def test_attribute_of_a_newer_mujoco_names_the_release(scene, monkeypatch):
    from mjcf import mujoco_compat

    monkeypatch.setitem(mujoco_compat.BINDING_SINCE, "geom.sparkle", "99.0.0")
    with pytest.raises(AttributeError) as raised:
        _ = scene.physics.bind(scene.ball).sparkle
    assert str(raised.value) == (
        "<geom name='ball'> has no attribute 'sparkle': geom attribute 'sparkle' needs "
        f"mujoco>=99.0.0 (installed: mujoco {mujoco.__version__})"
    )


def test_item_write_to_a_scattered_derived_field_is_kept_until_forward(scene):
    physics = scene.physics
    bodies = [scene.forearm, scene.ball_body]
    physics.bind(bodies).xpos[1, 2] = 7.0
    assert not physics.is_dirty
    assert physics.bind(bodies).xpos[1, 2] == 7.0
    physics.forward()
    assert physics.bind(bodies).xpos[1, 2] == 1.0


def test_scattered_model_field_reads_see_writes_made_elsewhere(scene):
    physics = scene.physics
    geoms = [scene.lower, scene.ball]
    np.testing.assert_array_equal(physics.bind(geoms).rgba[1], [1, 0, 0, 1])
    physics.named.model.geom_rgba["ball"] = [0, 0, 1, 1]
    np.testing.assert_array_equal(physics.bind(geoms).rgba[1], [0, 0, 1, 1])


def test_two_mocap_bodies_bind_together():
    root = mjcf.RootElement()
    targets = [
        root.worldbody.add("body", name=name, mocap=True, pos=[index, 0, 0])
        for index, name in enumerate(["first", "second"])
    ]
    physics = Physics.from_mjcf_model(root)
    bound = physics.bind(targets)
    np.testing.assert_array_equal(bound.mocap_pos, [[0, 0, 0], [1, 0, 0]])
    bound.mocap_pos[1] = [1, 2, 3]
    physics.forward()
    np.testing.assert_array_equal(physics.data.xpos[2], [1, 2, 3])


def test_worldbody_of_an_attached_model_binds_the_world_in_a_physics_of_its_own_xml():
    scene = mjcf.RootElement(model="scene")
    arm = mjcf.RootElement(model="arm")
    arm.worldbody.add("body", name="link", pos=[0, 0, 1]).add("geom", size=[0.1])
    scene.worldbody.add("site", name="mount", pos=[3, 0, 0]).attach(arm)
    physics = Physics.from_xml_string(arm.to_xml_string())  # knows no MJCF model
    assert physics.bind(arm.worldbody).element_id == 0
