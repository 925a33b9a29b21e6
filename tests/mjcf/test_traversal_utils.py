"""Traversal helpers: attachment frames, frame joints and committing defaults."""

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf import traversal_utils


def _model_with_defaults():
    root = mjcf.RootElement(model="defaults")
    root.default.geom.set_attributes(rgba=[1, 0, 0, 1], friction=[0.5, 0.01, 0.001])
    heavy = root.default.add("default", dclass="heavy")
    heavy.geom.density = 9000
    light = heavy.add("default", dclass="light")
    light.geom.rgba = [0, 0, 1, 1]
    root.default.joint.damping = 3
    body = root.worldbody.add("body", name="b", childclass="heavy")
    body.add("joint", name="j")
    body.add("geom", name="inherits", size=[0.1])
    body.add("geom", name="explicit", size=[0.1], dclass="light")
    root.worldbody.add("geom", name="plain", size=[0.2], rgba=[0, 1, 0, 1])
    return root


def test_commit_defaults_writes_inherited_values_onto_elements():
    root = _model_with_defaults()
    traversal_utils.commit_defaults(root)
    assert root.find("geom", "inherits").density == 9000
    np.testing.assert_array_equal(root.find("geom", "inherits").rgba, [1, 0, 0, 1])
    np.testing.assert_array_equal(root.find("geom", "explicit").rgba, [0, 0, 1, 1])
    assert root.find("geom", "explicit").density == 9000
    np.testing.assert_array_equal(root.find("geom", "plain").rgba, [0, 1, 0, 1])
    assert root.find("joint", "j").damping.tolist() == [3]


def test_commit_defaults_keeps_the_compiled_model_unchanged():
    root = _model_with_defaults()
    before = mujoco.MjModel.from_xml_string(root.to_xml_string())
    mjcf.commit_defaults(root)
    root.default.default["heavy"].remove()
    root.default.geom.remove()
    root.default.joint.remove()
    root.find("body", "b").childclass = None
    root.find("geom", "explicit").dclass = None
    after = mujoco.MjModel.from_xml_string(root.to_xml_string())
    for field in ("geom_rgba", "geom_friction", "body_mass", "dof_damping"):
        np.testing.assert_allclose(getattr(after, field), getattr(before, field), err_msg=field)


def test_commit_defaults_can_be_limited_to_some_attributes():
    root = _model_with_defaults()
    traversal_utils.commit_defaults(root, attributes=["rgba"])
    geom = root.find("geom", "inherits")
    np.testing.assert_array_equal(geom.rgba, [1, 0, 0, 1])
    assert geom.density is None


def test_commit_defaults_with_unknown_class_is_an_error():
    root = mjcf.RootElement()
    root.worldbody.add("geom", name="g", dclass="missing", size=[1])
    with pytest.raises(ValueError, match="default class 'missing' does not exist"):
        traversal_utils.commit_defaults(root)


def test_frame_joints_are_read_through_the_attached_model():
    parent = mjcf.RootElement()
    child = mjcf.RootElement(model="child")
    child.worldbody.add("geom", size=[0.1])
    frame = parent.attach(child)
    assert mjcf.get_frame_freejoint(child) is None
    assert mjcf.get_frame_joints(child) == []
    slide = frame.add("joint", type="slide", name="x")
    hinge = frame.add("joint", name="h")
    assert mjcf.get_frame_joints(child) == [slide, hinge]


def test_frame_freejoint_is_read_through_the_attached_model():
    parent = mjcf.RootElement()
    free = mjcf.RootElement(model="free")
    free.worldbody.add("geom", size=[0.1])
    free_frame = parent.attach(free)
    joint = free_frame.add("freejoint")
    assert mjcf.get_frame_freejoint(free) is joint
    assert mjcf.get_freejoint(free_frame) is joint
    assert mjcf.get_attachment_frame(free) is free_frame


def test_frame_helpers_of_an_unattached_model_return_none():
    loose = mjcf.RootElement(model="loose")
    assert mjcf.get_frame_freejoint(loose) is None
    assert mjcf.get_frame_joints(loose) is None


def test_asset_objects_can_be_assigned_directly():
    from mjcf_test_files import tetrahedron_stl

    root = mjcf.RootElement()
    asset = mjcf.Asset(tetrahedron_stl(), ".stl", "tetra")
    mesh = root.asset.add("mesh", name="m", file=asset)
    root.worldbody.add("geom", type="mesh", mesh=mesh)
    assert mesh.file is asset
    assert asset.get_vfs_filename().startswith("tetra-") and asset.get_vfs_filename().endswith(
        ".stl"
    )
    model = mujoco.MjModel.from_xml_string(root.to_xml_string(), root.get_assets())
    assert model.mesh_vertnum[0] == 4


def test_commit_defaults_on_element_uses_ancestor_childclass():
    root = mjcf.RootElement()
    soft = root.default.add("default", dclass="soft")
    soft.geom.pos = [0, 0, 1]
    body = root.worldbody.add("body", childclass="soft")
    geom = body.add("body").add("geom", size=[1])
    mjcf.commit_defaults(geom)
    np.testing.assert_array_equal(geom.pos, [0, 0, 1])


def test_commit_defaults_on_actuator_takes_every_actuator_kind_default():
    root = mjcf.RootElement()
    root.default.general.forcelimited = "true"
    root.default.motor.forcerange = [-2, 3]
    joint = root.worldbody.add("body").add("joint", name="j")
    motor = root.actuator.add("motor", joint=joint)
    mjcf.commit_defaults(motor)
    assert motor.forcelimited == "true"
    np.testing.assert_array_equal(motor.forcerange, [-2, 3])
