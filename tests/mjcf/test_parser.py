"""Parsing MJCF: strings, files, paths, includes, assets and bad input."""

import io

import mujoco
import pytest
from mjcf_test_files import tetrahedron_stl

import mjcf

_SIMPLE = """
<mujoco model="simple">
  <worldbody>
    <body name="box" pos="0 0 1">
      <freejoint name="free"/>
      <geom name="box_geom" type="box" size="0.1 0.1 0.1" material="red"/>
    </body>
  </worldbody>
  <asset>
    <material name="red" rgba="1 0 0 1"/>
  </asset>
</mujoco>
"""


def test_from_xml_string_builds_the_tree():
    root = mjcf.from_xml_string(_SIMPLE)
    assert root.model == "simple"
    body = root.find("body", "box")
    assert body.pos.tolist() == [0, 0, 1]
    assert body.freejoint.name == "free"


def test_references_resolve_to_elements_by_default():
    root = mjcf.from_xml_string(_SIMPLE)
    assert root.find("geom", "box_geom").material is root.find("material", "red")


def test_default_class_references_resolve_to_default_elements():
    xml = """<mujoco><default><default class="big"><geom size="1"/></default></default>
      <worldbody><geom name="g" class="big"/></worldbody></mujoco>"""
    root = mjcf.from_xml_string(xml)
    assert root.find("geom", "g").dclass is root.find("default", "big")


def test_references_stay_strings_without_resolution():
    root = mjcf.from_xml_string(_SIMPLE, resolve_references=False)
    assert root.find("geom", "box_geom").material == "red"


def test_parsing_does_not_count_as_modification():
    assert mjcf.from_xml_string(_SIMPLE).modification_count == 0


def test_from_file_reads_an_open_file():
    root = mjcf.from_file(io.StringIO(_SIMPLE))
    assert root.find("geom", "box_geom") is not None


def test_from_path_reads_relative_to_file(tmp_path):
    (tmp_path / "model.xml").write_text(
        '<mujoco><asset><mesh name="m" file="tetra.stl"/></asset></mujoco>'
    )
    (tmp_path / "tetra.stl").write_bytes(tetrahedron_stl())
    root = mjcf.from_path(str(tmp_path / "model.xml"))
    assert root.find("mesh", "m").file.contents == tetrahedron_stl()


def test_assetdir_applies_to_meshes(tmp_path):
    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "tetra.stl").write_bytes(tetrahedron_stl())
    xml = '<mujoco><compiler assetdir="assets"/><asset><mesh file="tetra.stl"/></asset></mujoco>'
    root = mjcf.from_xml_string(xml, model_dir=str(tmp_path))
    assert root.asset.mesh[0].file.contents == tetrahedron_stl()


def test_missing_file_names_element_attribute_and_path(tmp_path):
    xml = '<mujoco><asset><mesh name="m" file="nowhere.stl"/></asset></mujoco>'
    with pytest.raises(FileNotFoundError, match=r"<mesh name='m'> attribute 'file'.*nowhere"):
        mjcf.from_xml_string(xml, model_dir=str(tmp_path))


def test_missing_include_is_a_clear_error(tmp_path):
    xml = '<mujoco><include file="absent.xml"/></mujoco>'
    with pytest.raises(FileNotFoundError, match="include file='absent.xml'"):
        mjcf.from_xml_string(xml, model_dir=str(tmp_path))


def test_nested_includes_are_expanded(tmp_path):
    (tmp_path / "a.xml").write_text('<mujoco><include file="b.xml"/></mujoco>')
    (tmp_path / "b.xml").write_text('<mujoco><geom name="deep" size="1"/></mujoco>')
    xml = '<mujoco><worldbody><include file="a.xml"/></worldbody></mujoco>'
    root = mjcf.from_xml_string(xml, model_dir=str(tmp_path))
    assert root.find("geom", "deep").parent is root.worldbody


def test_unknown_element_in_xml_suggests_close_matches():
    with pytest.raises(ValueError, match=r"<body name='b'> cannot have a child <goem>.*'geom'"):
        mjcf.from_xml_string(
            '<mujoco><worldbody><body name="b"><goem/></body></worldbody></mujoco>'
        )


def test_unknown_attribute_in_xml_suggests_close_matches():
    with pytest.raises(ValueError, match=r"<geom> has no attribute 'szie'.*'size'"):
        mjcf.from_xml_string('<mujoco><worldbody><geom szie="1"/></worldbody></mujoco>')


def test_bad_value_in_xml_names_attribute():
    with pytest.raises(ValueError, match=r"<geom name='g'> attribute 'pos'"):
        mjcf.from_xml_string('<mujoco><worldbody><geom name="g" pos="1 2"/></worldbody></mujoco>')


def test_duplicate_name_in_xml_is_an_error():
    xml = (
        '<mujoco><worldbody><geom name="a" size="1"/><geom name="a" size="1"/></worldbody></mujoco>'
    )
    with pytest.raises(ValueError, match="duplicate identifier 'a'"):
        mjcf.from_xml_string(xml)


def test_root_must_be_mujoco():
    with pytest.raises(ValueError, match="must be <mujoco>"):
        mjcf.from_xml_string("<model/>")


def test_invalid_xml_is_a_value_error():
    with pytest.raises(ValueError, match="invalid MJCF XML"):
        mjcf.from_xml_string("<mujoco><worldbody></mujoco>")


def test_names_with_separators_need_escaping():
    xml = '<mujoco><worldbody><body name="a/b"><geom size="1"/></body></worldbody></mujoco>'
    with pytest.raises(ValueError, match="escape_separators=True"):
        mjcf.from_xml_string(xml)
    root = mjcf.from_xml_string(xml, escape_separators=True)
    body = root.worldbody.body[0]
    assert body.name == "a\\/b"
    model = mujoco.MjModel.from_xml_string(root.to_xml_string())
    assert model.body(body.full_identifier).id == 1


def test_escaped_references_still_resolve():
    xml = """<mujoco><worldbody><body name="a/b"><joint name="j/1"/><geom size="1"/></body>
      </worldbody><actuator><motor joint="j/1"/></actuator></mujoco>"""
    root = mjcf.from_xml_string(xml, escape_separators=True)
    model = mujoco.MjModel.from_xml_string(root.to_xml_string())
    joint = root.find("joint", "j\\/1")
    assert model.actuator_trnid[0, 0] == model.joint(joint.full_identifier).id


def test_repeated_sections_are_merged():
    xml = """<mujoco><option timestep="0.01"/><option gravity="0 0 -1"/>
      <worldbody><geom name="a" size="1"/></worldbody>
      <worldbody><geom name="b" size="1"/></worldbody>
      </mujoco>"""
    root = mjcf.from_xml_string(xml)
    assert root.option.timestep == 0.01
    assert root.option.gravity.tolist() == [0, 0, -1]
    assert [g.name for g in root.worldbody.geom] == ["a", "b"]


def test_from_file_accepts_a_file_name(tmp_path):
    path = tmp_path / "model.xml"
    path.write_text('<mujoco model="named"><worldbody><geom size="1"/></worldbody></mujoco>')
    assert mjcf.from_file(str(path)).model == "named"


def _zip(tmp_path, files):
    import zipfile

    path = tmp_path / "model.zip"
    with zipfile.ZipFile(path, "w") as archive:
        for name, contents in files.items():
            archive.writestr(name, contents)
    return str(path)


_ZIPPED_XML = """<mujoco model="zipped"><compiler meshdir="meshes"/>
<asset><mesh name="tet" file="tet.stl"/><mesh name="up" file="../meshes/tet.stl"/></asset>
<worldbody><geom type="mesh" mesh="tet"/></worldbody></mujoco>"""


def test_from_zip_reads_model_and_assets_relative_to_it(tmp_path):
    path = _zip(tmp_path, {"model.xml": _ZIPPED_XML, "meshes/tet.stl": tetrahedron_stl()})
    model = mjcf.from_zip(path)
    assert model.model == "zipped"
    assert model.asset.mesh["up"].file.contents == tetrahedron_stl()
    physics = mjcf.Physics.from_mjcf_model(model)
    assert physics.model.nmesh == 2


def test_from_zip_with_several_models_needs_model_file(tmp_path):
    simple = "<mujoco/>"
    path = _zip(tmp_path, {"a.xml": simple, "b.xml": '<mujoco model="b"/>'})
    assert mjcf.from_zip(path, model_file="b.xml").model == "b"
    with pytest.raises(ValueError, match="model.xml"):
        mjcf.from_zip(path)


def test_from_zip_of_a_non_archive_is_value_error(tmp_path):
    path = tmp_path / "plain.xml"
    path.write_text("<mujoco/>")
    with pytest.raises(ValueError, match="not a zip"):
        mjcf.from_zip(str(path))


def test_malformed_xml_is_a_value_error_and_lxmls_syntax_error():
    from lxml import etree

    with pytest.raises(ValueError, match="invalid MJCF XML") as raised:
        mjcf.from_xml_string("<mujoco><worldbody>")
    # dm_control lets lxml's own error through; code that catches it keeps working.
    assert isinstance(raised.value, etree.XMLSyntaxError)
    assert raised.value.lineno == 1
