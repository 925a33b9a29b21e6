"""Generated XML: formatting options, scoping and compilability."""

import mujoco
import pytest

import mjcf


@pytest.fixture
def model():
    root = mjcf.RootElement(model="writer")
    body = root.worldbody.add("body", name="b", pos=[0.1, 1e-12, 2])
    body.add("geom", name="g", size=[1 / 3])
    return root


def test_precision_limits_significant_digits(model):
    xml = model.to_xml_string(precision=3)
    assert 'size="0.333"' in xml


def test_full_precision_round_trips_floats_exactly(model):
    root = mjcf.from_xml_string(model.to_xml_string(), escape_separators=True)
    assert root.find("geom", "g").size[0] == 1 / 3


def test_zero_threshold_writes_tiny_values_as_zero(model):
    assert 'pos="0.1 0 2"' in model.to_xml_string(zero_threshold=1e-9)
    assert "1e-12" in model.to_xml_string()


def test_pretty_print_indents_and_compact_does_not(model):
    pretty = model.to_xml_string()
    compact = model.to_xml_string(pretty_print=False)
    assert "\n    <body" in pretty
    assert "\n" not in compact


def test_self_close_false_writes_end_tags(model):
    xml = model.find("geom", "g").to_xml_string(self_close=False)
    assert xml == f'<geom name="g" class="/" size="{1 / 3!r}"></geom>\n'


def test_every_class_taking_element_names_its_class(model):
    xml = model.to_xml_string()
    assert f'<geom name="g" class="/" size="{1 / 3!r}"/>' in xml
    assert '<default class="/"/>' in xml


def test_childclass_applies_to_descendants(model):
    model.default.add("default", dclass="soft").geom.solref = [0.1, 1]
    body = model.find("body", "b")
    body.childclass = "soft"
    inner = body.add("geom", name="inner", size=[0.1])
    compiled = mujoco.MjModel.from_xml_string(model.to_xml_string())
    assert compiled.geom("inner").solref[0] == pytest.approx(0.1)
    assert compiled.geom("g").solref[0] == pytest.approx(0.1)
    assert inner.dclass is None


def test_to_xml_returns_an_lxml_element(model):
    element = model.to_xml()
    assert element.tag == "mujoco"
    assert element.find("worldbody/body").get("name") == "b"


def test_attribute_values_are_xml_escaped():
    root = mjcf.RootElement()
    root.custom.add("text", name="note", data='a "quoted" <tag> & more')
    compiled = mujoco.MjModel.from_xml_string(root.to_xml_string())
    start = compiled.text_adr[0]
    text = bytes(compiled.text_data[start : start + compiled.text_size[0] - 1]).decode()
    assert text == 'a "quoted" <tag> & more'


def test_changes_after_a_write_appear_in_the_next_write(model):
    first = model.to_xml_string()
    model.find("geom", "g").name = "renamed"
    second = model.to_xml_string()
    assert first != second and 'name="renamed"' in second


def test_prefix_root_scopes_names_relative_to_a_model():
    parent = mjcf.RootElement(model="parent")
    child = mjcf.RootElement(model="child")
    geom = child.worldbody.add("geom", name="g", size=[1])
    parent.attach(child)
    assert geom.to_xml_string() == '<geom name="g" class="/" size="1"/>\n'
    assert (
        geom.to_xml_string(prefix_root=parent) == '<geom name="child/g" class="child/" size="1"/>\n'
    )
    assert geom.prefixed_identifier(parent) == "child/g"
    assert geom.prefixed_identifier() == "g"
    assert geom.full_identifier == "child/g"


def test_attached_model_written_alone_is_a_standalone_model():
    parent = mjcf.RootElement(model="parent")
    child = mjcf.RootElement(model="child")
    child.worldbody.add("geom", name="g", size=[1])
    parent.attach(child)
    compiled = mujoco.MjModel.from_xml_string(child.to_xml_string())
    assert compiled.geom("g").id == 0


def test_unnamed_freejoint_without_attributes_is_written_and_compiles():
    root = mjcf.RootElement(model="m")
    body = root.worldbody.add("body")
    body.add("freejoint")
    body.add("geom", size=[0.1])
    compiled = mujoco.MjModel.from_xml_string(root.to_xml_string(), root.get_assets())
    assert compiled.njnt == 1
    assert compiled.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE


def test_element_text_names_its_inherited_class_after_its_name():
    root = mjcf.RootElement()
    body = root.worldbody.add("body", childclass="soft")
    root.default.add("default", dclass="soft")
    joint = body.add("joint", name="j", type="hinge")
    free_geom = root.worldbody.add("geom", size=[1])
    assert str(joint) == '<joint name="j" class="soft" type="hinge"/>'
    assert str(free_geom) == '<geom class="/" size="1"/>'


def test_pretty_element_text_ends_with_newline_and_self_only_elides_children():
    root = mjcf.RootElement()
    body = root.worldbody.add("body", name="b")
    body.add("geom", size=[1])
    assert body.to_xml_string(self_only=True) == '<body name="b">...</body>\n'
    assert body.to_xml_string(pretty_print=False).startswith('<body name="b"><geom name="//')


def test_attachment_frame_writes_its_name_after_its_pose():
    parent = mjcf.RootElement()
    frame = parent.attach(mjcf.RootElement(model="arm"))
    frame.pos = [1, 2, 3]
    assert str(frame) == '<body pos="1 2 3" name="arm/"/>'


def _checker_texture(model):
    return model.asset.add(
        "texture", type="2d", builtin="checker", width=8, height=8, rgb1=[0.2, 0.3, 0.4]
    )


def _written_tag(xml: str, tag: str) -> str:
    """The first `<tag .../>` line of `xml`."""
    return next(line.strip() for line in xml.splitlines() if line.strip().startswith(f"<{tag}"))


def test_unnamed_texture_used_by_a_material_is_named_and_compiles():
    root = mjcf.RootElement()
    texture = _checker_texture(root)
    grid = root.asset.add("material", name="grid", texture=texture, texrepeat=[5, 5])
    root.worldbody.add("geom", type="plane", size=[2, 2, 0.1], material=grid)
    xml = root.to_xml_string()
    assert _written_tag(xml, "texture").startswith('<texture name="//unnamed_texture_0"')
    physics = mjcf.Physics.from_mjcf_model(root)
    assert physics.model.ntex == 1
    assert physics.model.mat_texid[0][mujoco.mjtTextureRole.mjTEXROLE_RGB] == 0


def test_unnamed_material_used_by_a_geom_compiles_and_binds():
    root = mjcf.RootElement()
    material = root.asset.add("material", rgba=[1, 0, 0, 1])
    root.worldbody.add("geom", size=[1], material=material)
    physics = mjcf.Physics.from_mjcf_model(root)
    assert physics.model.geom_matid[0] == 0
    assert list(physics.bind(material).rgba) == [1, 0, 0, 1]


def test_unnamed_asset_nothing_uses_is_written_without_a_name():
    root = mjcf.RootElement()
    root.asset.add("texture", type="skybox", builtin="gradient", width=8, height=8)
    xml = root.to_xml_string()
    # Whether a texture takes a default class depends on the MuJoCo release; a name it never has.
    tag = _written_tag(xml, "texture")
    assert 'type="skybox"' in tag and "name=" not in tag
    assert mjcf.Physics.from_mjcf_model(root).model.ntex == 1


def test_unnamed_asset_asked_for_its_name_is_written_with_it():
    root = mjcf.RootElement()
    sky = root.asset.add("texture", type="skybox", builtin="gradient", width=8, height=8)
    root.to_xml_string()
    assert sky.full_identifier == "//unnamed_texture_0"
    assert 'name="//unnamed_texture_0"' in _written_tag(root.to_xml_string(), "texture")


def test_unnamed_assets_of_an_attached_model_get_scoped_names_and_compile():
    parent = mjcf.RootElement(model="parent")
    child = mjcf.RootElement(model="child")
    material = child.asset.add("material", texture=_checker_texture(child))
    child.worldbody.add("geom", size=[1], material=material)
    parent.attach(child)
    xml = parent.to_xml_string()
    assert _written_tag(xml, "texture").startswith('<texture name="child//unnamed_texture_0"')
    assert 'texture="child//unnamed_texture_0"' in _written_tag(xml, "material")
    compiled = mjcf.Physics.from_mjcf_model(parent).model
    assert compiled.texture("child//unnamed_texture_0").id == 0
    assert compiled.geom_matid[0] == 0


def test_unnamed_asset_first_referred_to_by_a_copy_is_named_in_the_same_write():
    # The copies are linked without setting attributes, so the destination's texture is
    # first named while the material that refers to it is written, after the texture.
    source = mjcf.RootElement(model="source")
    material = source.asset.add("material", name="m", texture=_checker_texture(source))
    source.worldbody.add("geom", size=[1], material=material)
    destination = mjcf.RootElement(model="destination")
    destination.include_copy(source)
    xml = destination.to_xml_string()
    assert _written_tag(xml, "texture").startswith('<texture name="//unnamed_texture_0"')
    assert mjcf.Physics.from_mjcf_model(destination).model.ntex == 1


def test_exported_model_with_unnamed_used_assets_compiles(tmp_path):
    root = mjcf.RootElement(model="exported")
    material = root.asset.add("material", texture=_checker_texture(root))
    root.worldbody.add("geom", size=[1], material=material)
    mjcf.export_with_assets(root, str(tmp_path))
    compiled = mujoco.MjModel.from_xml_path(str(tmp_path / "exported.xml"))
    assert compiled.ntex == 1 and compiled.geom_matid[0] == 0
