"""mjcf.skin: reading and writing MuJoCo skin files."""

import numpy as np
import pytest
from mjcf_test_files import triangle_skin

import mjcf
from mjcf import skin


def test_parse_reads_geometry_and_bone():
    parsed = skin.parse(triangle_skin("torso"), body_getter=lambda name: f"<{name}>")
    np.testing.assert_allclose(parsed.vertices[1], [0.1, 0, 0], rtol=1e-6)
    np.testing.assert_array_equal(parsed.faces, [[0, 1, 2]])
    assert parsed.texcoords.shape == (0, 2)
    (bone,) = parsed.bones
    assert bone.body() == "<torso>"
    np.testing.assert_array_equal(bone.bindquat, [1, 0, 0, 0])
    np.testing.assert_array_equal(bone.vertex_ids, [0, 1, 2])


def test_serialize_names_bones_by_full_identifier_of_their_body():
    root = mjcf.RootElement(model="creature")
    torso = root.worldbody.add("body", name="torso")
    scene = mjcf.RootElement()
    scene.attach(root)
    parsed = skin.parse(triangle_skin("torso"), body_getter=lambda name: root.find("body", name))
    assert skin.serialize(parsed) == triangle_skin("creature/torso")
    assert parsed.bones[0].body() is torso


def test_parse_and_serialize_round_trip_bytes():
    contents = triangle_skin("torso")

    class Named:
        def __init__(self, name):
            self.full_identifier = name

    assert skin.serialize(skin.parse(contents, body_getter=Named)) == contents


def test_truncated_skin_is_value_error():
    with pytest.raises(ValueError, match="truncated"):
        skin.parse(triangle_skin("torso")[:30], body_getter=str)


def test_too_long_body_name_is_value_error():
    parsed = skin.parse(triangle_skin("torso"), body_getter=str)
    with pytest.raises(ValueError, match="longer"):
        skin.pack(parsed, lambda bone: "x" * 40)
