"""Element API: attributes, children, identifiers, search and removal."""

import copy

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf import mujoco_compat


@pytest.fixture
def model():
    root = mjcf.RootElement(model="test")
    body = root.worldbody.add("body", name="torso", pos=[0, 0, 1])
    body.add("joint", name="hip", type="hinge", axis=[0, 1, 0])
    body.add("geom", name="trunk", type="capsule", size=[0.1, 0.3])
    leg = body.add("body", name="leg")
    leg.add("joint", name="knee")
    leg.add("geom", name="shin", size=[0.05])
    return root


def test_top_level_sections_are_created_on_first_access():
    root = mjcf.RootElement()
    assert root.all_children() == []
    world = root.worldbody
    assert world.tag == "worldbody"
    assert root.worldbody is world
    assert root.all_children() == [world]


def test_array_attribute_reads_back_as_numpy_array():
    root = mjcf.RootElement()
    geom = root.worldbody.add("geom", pos=[1, 2, 3], size=[0.5])
    assert isinstance(geom.pos, np.ndarray)
    np.testing.assert_array_equal(geom.pos, [1.0, 2.0, 3.0])
    assert geom.size.shape == (1,)


def test_unset_attribute_reads_none():
    geom = mjcf.RootElement().worldbody.add("geom")
    assert geom.rgba is None
    assert geom.name is None


def test_setting_none_or_deleting_unsets_an_attribute():
    geom = mjcf.RootElement().worldbody.add("geom", rgba=[1, 0, 0, 1], pos=[0, 0, 1])
    geom.rgba = None
    del geom.pos
    assert geom.rgba is None and geom.pos is None
    assert "rgba" not in geom.to_xml_string() and "pos" not in geom.to_xml_string()


def test_scalar_attributes_read_back_as_python_numbers():
    root = mjcf.RootElement()
    geom = root.worldbody.add("geom", mass="2.5", condim=3)
    assert geom.mass == 2.5 and isinstance(geom.mass, float)
    assert geom.condim == 3 and isinstance(geom.condim, int)


def test_keyword_matches_without_case_and_is_stored_as_mujoco_spells_it():
    root = mjcf.RootElement()
    root.option.integrator = "rk4"
    geom = root.worldbody.add("geom", type="BOX")
    assert root.option.integrator == "RK4"
    assert geom.type == "box"


def test_bool_attribute_accepts_python_bools():
    body = mjcf.RootElement().worldbody.add("body", mocap=True)
    assert body.mocap == "true"


def test_class_attribute_is_dclass_in_python(model):
    model.default.add("default", dclass="red")
    geom = model.find("geom", "trunk")
    geom.dclass = "red"
    assert geom.dclass == "red"
    assert getattr(geom, "class") == "red"
    assert geom.get_attributes()["dclass"] == "red"
    assert 'class="red"' in geom.to_xml_string()


def test_get_and_set_attributes(model):
    geom = model.find("geom", "trunk")
    geom.set_attributes(rgba=[0, 1, 0, 1], size=[0.2, 0.4])
    attributes = geom.get_attributes()
    assert set(attributes) == {"name", "type", "size", "rgba"}
    np.testing.assert_array_equal(attributes["size"], [0.2, 0.4])


def test_get_attribute_xml_string_formats_as_written():
    geom = mjcf.RootElement().worldbody.add("geom", pos=[1, 0.5, 0])
    assert geom.get_attribute_xml_string("pos") == "1 0.5 0"
    assert geom.get_attribute_xml_string("rgba") is None


def test_wrong_array_length_names_attribute_expected_and_got():
    geom = mjcf.RootElement().worldbody.add("geom", name="torso")
    with pytest.raises(ValueError, match=r"<geom name='torso'> attribute 'size'.*1 to 3.*got 4"):
        geom.size = [1, 2, 3, 4]


def test_non_numeric_array_is_rejected():
    geom = mjcf.RootElement().worldbody.add("geom")
    with pytest.raises(ValueError, match="'pos': expected exactly 3 floats"):
        geom.pos = "invalid"


def test_bad_keyword_lists_allowed_values():
    geom = mjcf.RootElement().worldbody.add("geom")
    with pytest.raises(ValueError, match=r"'type': expected one of .*'sphere'.*'box'"):
        geom.type = "cube"


def test_unknown_attribute_suggests_close_matches():
    geom = mjcf.RootElement().worldbody.add("geom")
    with pytest.raises(AttributeError, match=r"<geom> has no attribute or child 'rgb'.*'rgba'"):
        geom.rgb = [1, 0, 0, 1]


def test_unknown_attribute_in_add_is_rejected():
    with pytest.raises(AttributeError, match="'poss'.*did you mean 'pos'"):
        mjcf.RootElement().worldbody.add("geom", poss=[0, 0, 0])


def test_unknown_child_tag_suggests_close_matches():
    with pytest.raises(AttributeError, match=r"<worldbody> cannot have a child <bodi>.*'body'"):
        mjcf.RootElement().worldbody.add("bodi")


def test_duplicate_identifier_names_both_elements(model):
    with pytest.raises(ValueError, match=r"duplicate identifier 'trunk'.*<geom name='trunk'>"):
        model.worldbody.add("geom", name="trunk")


def test_failed_add_leaves_model_unchanged(model):
    count = len(model.worldbody.all_children())
    with pytest.raises(ValueError):
        model.worldbody.add("geom", name="trunk")
    assert len(model.worldbody.all_children()) == count
    assert model.find("geom", "trunk").parent.name == "torso"


def test_same_identifier_allowed_in_different_namespaces(model):
    model.worldbody.add("geom", name="torso")
    assert model.find("geom", "torso").tag == "geom"
    assert model.find("body", "torso").tag == "body"


def test_renaming_updates_lookup_and_rejects_duplicates(model):
    geom = model.find("geom", "trunk")
    geom.name = "chest"
    assert model.find("geom", "chest") is geom
    assert model.find("geom", "trunk") is None
    with pytest.raises(ValueError, match="duplicate identifier 'shin'"):
        geom.name = "shin"
    assert geom.name == "chest"


def test_identifier_with_separator_is_rejected():
    with pytest.raises(ValueError, match="contains '/'"):
        mjcf.RootElement().worldbody.add("body", name="a/b")


def test_insert_places_child_at_position(model):
    torso = model.find("body", "torso")
    site = torso.insert("site", 0, name="first")
    assert torso.all_children()[0] is site


def test_repeated_children_are_listed_by_tag_and_name(model):
    torso = model.find("body", "torso")
    assert len(torso.geom) == 1
    assert torso.geom[0] is torso.geom["trunk"]
    assert model.worldbody.body["torso"].body["leg"].geom["shin"].name == "shin"
    assert list(torso.get_children("joint")) == [model.find("joint", "hip")]


def test_single_children_are_attributes(model):
    torso = model.find("body", "torso")
    inertial = torso.add("inertial", mass=1.0, pos=[0, 0, 0])
    assert torso.inertial is inertial
    assert torso.get_children("inertial") is inertial


def test_remove_drops_subtree_and_identifiers(model):
    leg = model.find("body", "leg")
    leg.remove()
    assert model.find("body", "leg") is None
    assert model.find("joint", "knee") is None
    assert leg.is_removed
    model.find("body", "torso").add("geom", name="shin", size=[0.1])


def test_find_all_returns_elements_in_model_order(model):
    joints = model.find_all("joint")
    assert [j.name for j in joints] == ["hip", "knee"]
    torso = model.find("body", "torso")
    assert [b.name for b in torso.find_all("body", immediate_children_only=True)] == ["leg"]


def test_find_all_on_an_element_excludes_the_element_itself(model):
    torso = model.find("body", "torso")
    assert [b.name for b in torso.find_all("body")] == ["leg"]


def test_find_all_default_lists_the_root_default_class_first():
    root = mjcf.RootElement()
    root.default.add("default", dclass="big").add("default", dclass="bigger")
    assert [d.dclass for d in root.find_all("default")] == [None, "big", "bigger"]
    assert [d.dclass for d in root.default.find_all("default")] == ["big", "bigger"]


def test_freejoint_is_found_as_joint():
    root = mjcf.RootElement()
    body = root.worldbody.add("body")
    free = body.add("freejoint")
    assert free.spec.namespace == "joint"
    assert root.find_all("joint") == [free]


def test_find_within_element_only_searches_its_subtree(model):
    leg = model.find("body", "leg")
    assert leg.find("joint", "knee").name == "knee"
    assert leg.find("joint", "hip") is None


def test_references_accept_elements_and_identifiers(model):
    knee = model.find("joint", "knee")
    by_element = model.actuator.add("motor", name="m1", joint=knee)
    by_name = model.actuator.add("motor", name="m2", joint="hip")
    assert by_element.joint is knee
    assert by_name.joint == "hip"
    xml = model.to_xml_string()
    assert 'joint="knee"' in xml and 'joint="hip"' in xml
    mujoco.MjModel.from_xml_string(xml)


def test_reference_to_element_of_wrong_kind_is_rejected(model):
    with pytest.raises(ValueError, match="expected a reference to a 'joint' element"):
        model.actuator.add("motor", joint=model.find("geom", "trunk"))


def test_reference_follows_renamed_element(model):
    knee = model.find("joint", "knee")
    model.actuator.add("motor", joint=knee)
    knee.name = "renamed"
    assert 'joint="renamed"' in model.to_xml_string()


def test_dangling_reference_is_a_clear_error_when_written(model):
    model.actuator.add("motor", name="m", joint="nonexistent")
    with pytest.raises(ValueError, match=r"<motor name='m'> attribute 'joint'.*'nonexistent'"):
        model.to_xml_string()


def test_reference_to_removed_element_is_a_clear_error(model):
    knee = model.find("joint", "knee")
    model.actuator.add("motor", name="m", joint=knee)
    model.find("body", "leg").remove()
    with pytest.raises(ValueError, match="has been removed"):
        model.to_xml_string()


def test_element_repr_shows_its_xml(model):
    assert (
        repr(model.find("geom", "shin"))
        == 'MJCF Element: <geom name="shin" class="/" size="0.05"/>'
    )


def test_element_str_elides_children(model):
    assert str(model.find("body", "leg")) == '<body name="leg">...</body>'
    assert str(model) == '<mujoco model="test">...</mujoco>'


def test_unnamed_model_is_called_unnamed_model():
    root = mjcf.RootElement()
    assert root.model == "unnamed_model"
    root.model = None
    assert root.model == "unnamed_model"


def test_modification_count_grows_on_every_change(model):
    counts = [model.modification_count]
    model.find("geom", "trunk").rgba = [1, 0, 0, 1]
    counts.append(model.modification_count)
    model.worldbody.add("site")
    counts.append(model.modification_count)
    model.find("body", "leg").remove()
    counts.append(model.modification_count)
    assert counts == sorted(set(counts))


def test_reading_does_not_change_modification_count(model):
    before = model.modification_count
    assert model.find("geom", "trunk").size is not None
    assert model.find("body", "torso").inertial is None
    assert model.option.flag is not None
    model.to_xml_string()
    model.find_all("geom")
    assert model.modification_count == before


def test_deepcopy_is_independent_with_references_inside_the_copy(model):
    knee = model.find("joint", "knee")
    model.actuator.add("motor", name="m", joint=knee)
    clone = copy.deepcopy(model)
    assert clone.to_xml_string() == model.to_xml_string()
    clone_knee = clone.find("joint", "knee")
    assert clone.find("actuator", "m").joint is clone_knee
    clone_knee.name = "other"
    assert model.find("joint", "knee") is knee
    assert 'joint="knee"' in model.to_xml_string()


def test_copy_copy_of_a_model_is_a_full_copy(model):
    clone = copy.copy(model)
    assert clone is not model
    assert clone.find("geom", "trunk") is not model.find("geom", "trunk")


def test_elements_cannot_be_instantiated_directly():
    with pytest.raises(TypeError):
        mjcf.Element()


def test_root_element_cannot_be_removed():
    with pytest.raises(ValueError, match="cannot be removed"):
        mjcf.RootElement().remove()


_INTERVAL_MISSING = mujoco_compat.missing_mjcf("mujoco/sensor/touch", "interval")


@pytest.mark.skipif(bool(_INTERVAL_MISSING), reason=_INTERVAL_MISSING)
def test_new_attribute_unknown_to_type_table_passes_through_as_string():
    root = mjcf.RootElement()
    sensor = root.sensor.add("touch", site="s", interval=[0.5, 0])
    assert sensor.interval == "0.5 0"


def test_dir_lists_attributes_and_children(model):
    names = dir(model.find("body", "torso"))
    assert "pos" in names and "childclass" in names and "geom" in names and "add" in names
