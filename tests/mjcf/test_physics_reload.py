"""Reloading and copying a Physics: the new model is the one compiled, and elements of the
MJCF model the Physics was built from keep binding to their compiled objects."""

import mujoco
import numpy as np
import pytest

import mjcf

_INCLUDING_XML = '<mujoco model="outer"><include file="part.xml"/></mujoco>'
_PART = b'<mujoco><worldbody><geom name="from_asset" size="0.5"/></worldbody></mujoco>'


def _scene_with_arm_at(position):
    """A scene with an arm model attached at ``position``; returns (scene, arm)."""
    scene = mjcf.RootElement(model="scene")
    arm = mjcf.RootElement(model="arm")
    arm.worldbody.add("geom", name="link", size=[0.1])
    scene.worldbody.add("site", name="mount", pos=position).attach(arm)
    return scene, arm


def test_reload_from_xml_string_resolves_files_from_assets():
    physics = mjcf.Physics.from_xml_string("<mujoco/>")
    physics.reload_from_xml_string(_INCLUDING_XML, assets={"part.xml": _PART})
    geom = mujoco.mj_name2id(physics.model.ptr, mujoco.mjtObj.mjOBJ_GEOM, "from_asset")
    assert geom == 0
    assert physics.model.geom_size[0, 0] == 0.5


def test_reload_from_xml_path_compiles_the_file(tmp_path):
    path = tmp_path / "model.xml"
    path.write_text(
        '<mujoco><worldbody><body pos="0 0 2"><freejoint/><geom size="0.1"/></body>'
        "</worldbody></mujoco>"
    )
    physics = mjcf.Physics.from_xml_string("<mujoco/>")
    physics.reload_from_xml_path(path)
    assert physics.model.nq == 7
    np.testing.assert_array_equal(physics.data.xpos[1], [0, 0, 2])  # forward ran


def _reloaded_from_xml_string(scene, tmp_path):
    physics = mjcf.Physics.from_mjcf_model(scene)
    physics.reload_from_xml_string(scene.to_xml_string(), assets=scene.get_assets())
    return physics


def _reloaded_from_xml_path(scene, tmp_path):
    path = tmp_path / "scene.xml"
    path.write_text(scene.to_xml_string())
    physics = mjcf.Physics.from_mjcf_model(scene)
    physics.reload_from_xml_path(str(path))
    return physics


def _reloaded_from_mjcf_model(scene, tmp_path):
    physics = mjcf.Physics.from_xml_string("<mujoco/>")
    physics.reload_from_mjcf_model(scene)
    return physics


def _copied(scene, tmp_path):
    return mjcf.Physics.from_mjcf_model(scene).copy()


_RENEWALS = [_reloaded_from_xml_string, _reloaded_from_xml_path, _reloaded_from_mjcf_model, _copied]


@pytest.mark.parametrize("renewed", _RENEWALS)
def test_attached_worldbody_binds_its_attachment_frame_when(renewed, tmp_path):
    scene, arm = _scene_with_arm_at([0.5, 0, 1])
    physics = renewed(scene, tmp_path)
    np.testing.assert_array_equal(physics.bind(arm.worldbody).xpos, [0.5, 0, 1])
    assert physics.bind(scene.worldbody).element_id == 0


@pytest.mark.parametrize("renewed", _RENEWALS)
def test_elements_of_another_model_are_refused_when(renewed, tmp_path):
    scene, _ = _scene_with_arm_at([0, 0, 0])
    physics = renewed(scene, tmp_path)
    twin, _ = _scene_with_arm_at([0, 0, 0])
    with pytest.raises(ValueError, match="belongs to another model"):
        physics.bind(twin.find("site", "mount"))
