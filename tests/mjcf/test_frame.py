"""`<frame>`: MuJoCo reads it though `mj_printSchema` does not list it; the model layer too."""

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf import traversal_utils


def _arm(name="arm"):
    arm = mjcf.RootElement(model=name)
    arm.default.add("default", dclass="thick").geom.size = [0.3]
    frame = arm.worldbody.add("frame", name="mount", pos=[1, 0, 0], childclass="thick")
    frame.add("geom", name="plate")
    upper = frame.add("body", name="upper")
    upper.add("joint", name="shoulder")
    upper.add("geom", name="link", size=[0.1])
    tilt = upper.add("frame", name="tilt", euler=[0, 0, 90])
    tilt.add("site", name="tip", pos=[1, 0, 0])
    return arm


def test_frame_childclass_sets_the_class_of_what_it_holds():
    physics = mjcf.Physics.from_mjcf_model(_arm())
    assert physics.named.model.geom_size["plate", 0] == pytest.approx(0.3)
    assert physics.named.model.geom_size["link", 0] == pytest.approx(0.1)


def test_nested_frames_compose_their_poses():
    arm = _arm()
    physics = mjcf.Physics.from_mjcf_model(arm)
    np.testing.assert_allclose(physics.bind(arm.find("site", "tip")).xpos, [1, 1, 0], atol=1e-12)


def test_frame_names_are_scoped_in_attached_models_and_unique_among_frames():
    scene = mjcf.RootElement(model="scene")
    arm = _arm()
    scene.attach(arm)
    assert scene.find("frame", "arm/mount") is arm.find("frame", "mount")
    assert 'name="arm/tilt"' in scene.to_xml_string()
    with pytest.raises(ValueError, match="duplicate identifier 'mount'.*frame"):
        arm.worldbody.add("frame", name="mount")
    arm.worldbody.add("body", name="mount")  # Bodies are another namespace.


def test_frame_rejects_an_attribute_mujoco_does_not_read_on_frames():
    arm = _arm()
    with pytest.raises(AttributeError, match="mass"):
        arm.find("frame", "mount").mass = 1


def test_binding_a_frame_says_frames_have_no_fields():
    arm = _arm()
    physics = mjcf.Physics.from_mjcf_model(arm)
    with pytest.raises(ValueError, match="frame"):
        physics.bind(arm.find("frame", "mount"))


def test_mjcf_with_frames_written_by_mujoco_compiles_to_the_same_model():
    spec = mujoco.MjSpec()
    frame = spec.worldbody.add_frame(name="tilt", pos=[0.5, 0, 0], euler=[0, 0, 90])
    body = spec.worldbody.add_body(name="arm", pos=[1, 0, 0])
    body.set_frame(frame)
    body.add_joint(name="hinge")
    body.add_geom(size=[0.1, 0, 0])
    spec.worldbody.add_geom(size=[0.2, 0, 0]).set_frame(frame)
    expected = spec.compile()

    root = mjcf.from_xml_string(spec.to_xml())
    physics = mjcf.Physics.from_mjcf_model(root)
    assert root.find("frame", "tilt").find("body", "arm") is not None
    np.testing.assert_allclose(physics.model.body_pos, expected.body_pos, atol=1e-6)
    np.testing.assert_allclose(physics.model.body_quat, expected.body_quat, atol=1e-6)
    np.testing.assert_allclose(physics.model.geom_pos, expected.geom_pos, atol=1e-6)


def test_commit_defaults_follows_a_frame_childclass():
    arm = _arm()
    traversal_utils.commit_defaults(arm)
    assert arm.find("geom", "plate").size.tolist() == [0.3]
    arm.find("frame", "mount").childclass = None
    for default in arm.default.default:
        default.remove()
    physics = mjcf.Physics.from_mjcf_model(arm)
    assert physics.named.model.geom_size["plate", 0] == pytest.approx(0.3)
