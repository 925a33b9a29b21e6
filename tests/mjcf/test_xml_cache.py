"""Repeated writes reuse cached text, yet every write reflects the model as it is now."""

import copy

import mujoco
import pytest

import mjcf


def _arm(name):
    arm = mjcf.RootElement(model=name)
    skin = arm.asset.add("material", name="skin")
    body = arm.worldbody.add("body", name="upper")
    body.add("joint", name="elbow")
    body.add("geom", size=[0.1], material=skin)
    body.add("site", name="tip")
    return arm


@pytest.fixture
def scene():
    top = mjcf.RootElement(model="top")
    top.worldbody.add("site", name="left")
    top.worldbody.add("site", name="right")
    return top


def test_renaming_a_joint_of_an_attached_model_updates_a_parent_reference_to_it(scene):
    arm = _arm("arm")
    scene.attach(arm)
    scene.actuator.add("motor", joint=arm.find("joint", "elbow"))
    scene.to_xml_string()
    arm.find("joint", "elbow").name = "knee"
    assert 'joint="arm/knee"' in scene.to_xml_string()


def test_renaming_a_material_updates_the_geoms_that_refer_to_it(scene):
    arm = _arm("arm")
    scene.attach(arm)
    scene.to_xml_string()
    arm.find("material", "skin").name = "hide"
    xml = scene.to_xml_string()
    assert 'material="arm/hide"' in xml
    assert 'material="arm/skin"' not in xml


def test_moving_an_attached_model_rescopes_its_names(scene):
    holder = _arm("holder")
    scene.attach(holder)
    arm = _arm("arm")
    scene.find("site", "left").attach(arm)
    assert 'name="arm/elbow"' in scene.to_xml_string()
    arm.detach()
    holder.find("site", "tip").attach(arm)
    assert 'name="holder/arm/elbow"' in scene.to_xml_string()


def test_building_other_models_between_writes_keeps_the_text(scene):
    scene.attach(_arm("arm"))
    first = scene.to_xml_string()
    _arm("other").worldbody.add("geom", name="extra", size=[1])
    scene.find("site", "right").pos = [1, 0, 0]
    second = scene.to_xml_string()
    assert second == first.replace(
        '<site name="right" class="/"', '<site name="right" class="/" pos="1 0 0"'
    )


def test_printing_an_element_between_writes_leaves_the_model_text_unchanged(scene):
    scene.attach(_arm("arm"))
    first = scene.to_xml_string()
    str(scene.find("geom", "arm//unnamed_geom_0"))
    scene.find("body", "arm/upper").to_xml_string()
    scene.find("site", "right").pos = [1, 0, 0]
    scene.find("site", "right").pos = None
    assert scene.to_xml_string() == first


def test_generated_name_finds_its_element_after_a_write_until_it_is_removed(scene):
    geom = scene.worldbody.add("geom", size=[0.1])
    scene.to_xml_string()
    assert scene.find("geom", "//unnamed_geom_0") is geom
    geom.remove()
    assert scene.find("geom", "//unnamed_geom_0") is None


def test_elements_named_after_a_lookup_by_generated_name_are_found_too(scene):
    scene.worldbody.add("geom", size=[0.1])
    scene.to_xml_string()
    scene.find("geom", "//unnamed_geom_0")
    later = scene.worldbody.add("geom", size=[0.2])
    scene.to_xml_string()
    assert scene.find("geom", "//unnamed_geom_1") is later


def test_cached_write_equals_the_write_of_a_fresh_copy_after_many_changes(scene):
    arm = _arm("arm")
    frame = scene.find("site", "left").attach(arm)
    scene.to_xml_string()
    frame.add("joint", type="hinge")
    arm.find("geom", "//unnamed_geom_0").rgba = [1, 0, 0, 1]
    arm.model = "limb"
    scene.to_xml_string(precision=4)
    arm.find("site", "tip").name = "end"
    scene.sensor.add("touch", site="limb/end")
    assert scene.to_xml_string() == copy.deepcopy(scene).to_xml_string()


def test_file_of_a_flexcomp_deep_in_the_body_tree_is_among_the_assets(scene):
    body = scene.worldbody.add("body").add("body")
    body.add("flexcomp", name="cloth", type="mesh", file=mjcf.Asset(b"solid cloth", ".stl"))
    assert b"solid cloth" in scene.get_assets().values()


def test_assets_follow_a_new_file_in_an_attached_model(scene):
    arm = _arm("arm")
    mesh = arm.asset.add("mesh", name="shell", file=mjcf.Asset(b"solid first", ".stl"))
    scene.attach(arm)
    scene.get_assets()
    mesh.file = mjcf.Asset(b"solid second", ".stl")
    assert list(scene.get_assets().values()) == [b"solid second"]


def test_assets_of_a_detached_model_are_gone(scene):
    arm = _arm("arm")
    arm.asset.add("mesh", name="shell", file=mjcf.Asset(b"solid arm", ".stl"))
    scene.attach(arm)
    assert b"solid arm" in scene.get_assets().values()
    arm.detach()
    assert scene.get_assets() == {}


def _rich_scene():
    """Attached models with files, a skin, classes, a frame joint and cross-model references."""
    from mjcf_test_files import checker_png, tetrahedron_stl, triangle_skin

    scene = mjcf.RootElement(model="rich")
    scene.default.add("default", dclass="soft").geom.rgba = [0, 1, 0, 1]
    scene.worldbody.add("body", name="base", childclass="soft").add("geom", size=[0.1])
    creature = mjcf.RootElement(model="creature")
    creature.asset.add("mesh", name="shell", file=mjcf.Asset(tetrahedron_stl(), ".stl"))
    creature.asset.add("texture", name="grid", type="2d", file=mjcf.Asset(checker_png(), ".png"))
    creature.asset.add("material", name="hide", texture="grid")
    torso = creature.worldbody.add("body", name="torso")
    torso.add("geom", type="mesh", mesh="shell", material="hide")
    torso.add("joint", name="hinge")
    creature.deformable.add("skin", file=mjcf.Asset(triangle_skin("torso"), ".skn"))
    creature.sensor.add("framepos", objtype="body", objname="torso")
    frame = scene.find("body", "base").attach(creature)
    frame.add("joint", type="hinge")
    frame.add("inertial", pos=[0, 0, 0], mass=1, diaginertia=[0.1, 0.1, 0.1])
    scene.attach(_arm("arm"))
    scene.actuator.add("motor", joint="creature/hinge")
    return scene


def test_first_write_equals_later_writes_that_rebuild_from_cached_pieces():
    scene = _rich_scene()
    first = scene.to_xml_string()
    site = scene.find("site", "arm/tip")
    for _ in range(2):
        site.pos = [0, 0, 1]
        site.pos = None
        assert scene.to_xml_string() == first
    assert copy.deepcopy(scene).to_xml_string() == first


def test_assets_after_a_first_write_equal_those_of_an_unwritten_copy():
    scene = _rich_scene()
    unwritten = copy.deepcopy(scene)
    xml = scene.to_xml_string()
    assets = scene.get_assets()
    assert assets == unwritten.get_assets()
    assert len(assets) == 3
    model = mujoco.MjModel.from_xml_string(xml, assets)
    assert model.skin_bonebodyid[0] == model.body("creature/torso").id


def test_assets_of_a_model_written_under_another_prefix_root_stay_scoped_to_itself():
    scene = _rich_scene()
    creature = scene.find("body", "creature/torso").root
    creature.to_xml_string(prefix_root=scene)
    model = mujoco.MjModel.from_xml_string(creature.to_xml_string(), creature.get_assets())
    assert model.skin_bonebodyid[0] == model.body("torso").id
