"""Element API details shared with dm_control: sameness, on-demand children, the world
body's name, namespace checks, emptying global sections and resolving references."""

import copy

import numpy as np
import pytest

import mjcf


def _body_with(root, first, second):
    body = root.worldbody.add("body", pos=[0, 1, 2])
    body.add(first, pos=[0, 0, 1])
    body.add(second, pos=[0, 0, 1])
    return body


def test_bodies_with_same_children_in_other_tag_order_are_same():
    root = mjcf.RootElement()
    assert _body_with(root, "geom", "site").is_same_as(_body_with(root, "site", "geom"))


def test_attribute_difference_in_grandchild_makes_bodies_differ():
    root = mjcf.RootElement()
    a = _body_with(root, "geom", "site")
    b = _body_with(root, "geom", "site")
    a.add("body").add("joint", type="hinge")
    b.add("body").add("joint", type="ball")
    assert not a.is_same_as(b)
    assert not b.is_same_as(a)


def test_tendon_path_order_matters_for_sameness():
    root = mjcf.RootElement()
    first = root.tendon.add("spatial")
    first.add("site", site="a")
    first.add("geom", geom="b")
    second = root.tendon.add("spatial")
    second.add("geom", geom="b")
    second.add("site", site="a")
    assert not first.is_same_as(second)


def test_renamed_copy_of_model_is_same():
    root = mjcf.RootElement(model="original")
    root.asset.add("material", name="red", rgba=[1, 0, 0, 1])
    root.worldbody.add("geom", size=[1], material=root.asset.material["red"])
    clone = copy.deepcopy(root)
    clone.model = "clone"
    assert clone.is_same_as(root)
    clone.worldbody.geom[0].size = [2]
    assert not clone.is_same_as(root)


def _frame_carrying_ball(radius):
    ball = mjcf.RootElement(model="ball")
    ball.worldbody.add("geom", type="sphere", size=[radius])
    return mjcf.RootElement().attach(ball)


def test_attachment_frames_are_same_only_when_their_attached_models_are():
    assert _frame_carrying_ball(0.1).is_same_as(_frame_carrying_ball(0.1))
    assert not _frame_carrying_ball(0.1).is_same_as(_frame_carrying_ball(0.2))


def test_on_demand_inertial_is_none_until_added_and_only_once():
    body = mjcf.RootElement().worldbody.add("body")
    assert body.inertial is None
    inertial = body.add("inertial", mass=1, pos=[0, 0, 0])
    assert body.inertial is inertial
    with pytest.raises(ValueError, match="already exists"):
        body.add("inertial", mass=2, pos=[0, 0, 0])


def test_adding_an_always_present_section_is_an_error():
    with pytest.raises(ValueError, match="already exists"):
        mjcf.RootElement().add("compiler")


def test_world_body_is_named_world_and_attached_world_by_its_frame():
    root = mjcf.RootElement(model="scene")
    arm = mjcf.RootElement(model="arm")
    root.attach(arm)
    assert root.worldbody.full_identifier == "world"
    assert arm.worldbody.full_identifier == "arm/"


def test_weld_to_world_by_name_compiles():
    root = mjcf.RootElement()
    body = root.worldbody.add("body", name="box", mocap=True)
    body.add("geom", size=[0.1])
    free = root.worldbody.add("body", name="free")
    free.add("freejoint")
    free.add("geom", size=[0.1])
    root.equality.add("weld", body1="world", body2="free")
    assert root.find("body", "world") is root.worldbody
    physics = mjcf.Physics.from_mjcf_model(root)
    assert physics.model.neq == 1
    assert physics.model.eq_obj1id[0] == 0


def test_find_with_unknown_namespace_is_value_error():
    root = mjcf.RootElement()
    with pytest.raises(ValueError, match="not a valid namespace"):
        root.find("jiont", "x")
    with pytest.raises(ValueError, match="not a valid namespace"):
        root.find_all("goem")


def test_namescope_get_of_missing_identifier_is_key_error():
    root = mjcf.RootElement()
    with pytest.raises(KeyError):
        root.namescope.get("body", "missing")


def test_emptying_global_section_with_attachments_needs_affect_attachments():
    root = mjcf.RootElement()
    child = mjcf.RootElement(model="child")
    root.option.timestep = 0.01
    child.option.timestep = 0.01
    child.option.flag.gravity = "disable"
    root.attach(child)
    with pytest.raises(ValueError, match="affect_attachments=True"):
        del root.option
    option = root.option
    option.remove(affect_attachments=True)
    assert root.option is option
    assert root.option.timestep is None
    assert child.option.timestep is None
    assert child.option.flag.gravity is None


def test_deleting_a_repeated_child_tag_is_attribute_error():
    body = mjcf.RootElement().worldbody.add("body")
    with pytest.raises(AttributeError, match="clear"):
        del body.geom


def test_resolve_references_turns_names_into_elements():
    xml = """<mujoco><asset><material name="m"/></asset>
    <worldbody><geom size="1" material="m"/></worldbody></mujoco>"""
    root = mjcf.from_xml_string(xml, resolve_references=False)
    geom = root.worldbody.geom[0]
    assert geom.material == "m"
    root.resolve_references()
    assert geom.material is root.asset.material["m"]
    np.testing.assert_array_equal(geom.size, [1])


def test_rejected_set_attributes_leaves_earlier_ones_unchanged():
    root = mjcf.RootElement()
    body = root.worldbody.add("body", name="foo", pos=[1, 2, 3])
    with pytest.raises(ValueError, match="pos"):
        body.set_attributes(name="bar", pos=[1, 2, 3, 4])
    assert body.name == "foo"
    assert root.find("body", "bar") is None
    assert root.find("body", "foo") is body
    np.testing.assert_array_equal(body.pos, [1, 2, 3])


def _three_geoms():
    body = mjcf.RootElement().worldbody.add("body")
    for name in ("a", "b", "c"):
        body.add("geom", name=name, size=[1])
    return body


def test_element_list_slices_and_deletes_like_a_list():
    body = _three_geoms()
    assert [g.name for g in body.geom[1:]] == ["b", "c"]
    assert body.geom[-1].name == "c"
    del body.geom[0]
    assert [g.name for g in body.geom] == ["b", "c"]
    del body.geom["c"]
    assert [g.name for g in body.geom] == ["b"]
    assert body.root.find("geom", "c") is None


def test_element_list_clear_removes_all_from_model():
    body = _three_geoms()
    body.geom.clear()
    assert len(body.geom) == 0
    assert not body.geom
    assert body.root.find_all("geom") == []
