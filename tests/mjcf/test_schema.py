"""The schema comes from the installed MuJoCo, and every element/attribute in it is usable."""

import re

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf import attribute_types, schema
from mjcf.element import registry_namespace


def _element_paths():
    """(spec, tags from the root) for every distinct element spec, shortest path first."""
    root = schema.root_spec()
    paths = {id(root): (root, ())}
    queue = [root]
    while queue:
        spec = queue.pop(0)
        for tag, child in spec.children.items():
            if id(child) not in paths:
                paths[id(child)] = (child, paths[id(spec)][1] + (tag,))
                queue.append(child)
    return [value for key, value in paths.items() if key != id(root)]


_PATHS = _element_paths()


def _sample_value(attribute_type, serial):
    if isinstance(attribute_type, attribute_types.Array):
        low, high = attribute_type.lengths
        count = max(low, 1) if high is None else high
        if attribute_type.dtype is np.int64:
            return list(range(1, count + 1))
        return [0.25 * (i + 1) for i in range(count)]
    if isinstance(attribute_type, attribute_types.Number):
        return 3 if attribute_type.dtype is int else 0.75
    if isinstance(attribute_type, attribute_types.Keyword):
        return attribute_type.values[-1]
    if isinstance(attribute_type, attribute_types.File):
        return mjcf.Asset(b"contents", ".bin", "sample")
    return f"v{serial}"


def _add_path(root, tags):
    element = root
    for tag in tags:
        child_spec = element.spec.children[tag]
        child = None if child_spec.repeated else getattr(element, tag)
        element = element.add(tag) if child is None else child
    return element


def test_top_level_sections_come_from_mujoco():
    children = set(schema.root_spec().children)
    for section in (
        "compiler",
        "option",
        "size",
        "visual",
        "asset",
        "default",
        "worldbody",
        "actuator",
        "sensor",
        "contact",
        "equality",
        "tendon",
        "keyframe",
        "custom",
        "extension",
        "statistic",
        "deformable",
    ):
        assert section in children


def test_bodies_and_default_classes_nest_recursively():
    body = schema.root_spec().children["worldbody"].children["body"]
    default = schema.root_spec().children["default"]
    assert body.children["body"] is body
    nested = default.children["default"]
    assert nested.repeated and not default.repeated
    assert nested.children["default"] is nested


def test_worldbody_has_body_children_but_no_attributes():
    world = schema.root_spec().children["worldbody"]
    assert "geom" in world.children and "body" in world.children
    assert world.attributes == {}


def test_attribute_names_come_from_mujoco():
    text = mujoco.mj_printSchema(False, False)
    geom = schema.root_spec().children["worldbody"].children["geom"]
    for name in ("size", "pos", "rgba", "material", "class", "friction"):
        assert name in geom.attributes
        assert f" {name} " in f" {text} ".replace("\n", " ")
    assert "dclass" in geom.python_attributes


@pytest.mark.parametrize("spec,tags", _PATHS, ids=["/".join(t) for _, t in _PATHS])
def test_every_element_and_attribute_can_be_added_set_and_written(spec, tags):
    root = mjcf.RootElement(model="walk")
    element = _add_path(root, tags)
    assert element.tag == tags[-1]
    values = {}
    for serial, (name, attribute) in enumerate(spec.attributes.items()):
        value = _sample_value(attribute.type, serial)
        if tags == ("default",) and name == "class":
            value = "main"  # MuJoCo's top-level default class cannot be renamed
        if tags[-1] == "model" and name == "file":
            value = mjcf.Asset(b"<mujoco/>", ".xml", "sample")  # parsed back as MJCF
        setattr(element, attribute.python_name, value)
        values[name] = value
    xml = element.to_xml_string(pretty_print=False)
    for name in spec.attributes:
        assert element.get_attribute_xml_string(spec.attributes[name].python_name) is not None
        assert f" {name}=" in xml
    if tuple(tags) == ("default",):
        # The model's own default class is written as the whole <default> section, in
        # which it is named after the model's scope ('/').
        assert xml.startswith('<default><default class="/"')
        return
    # The written XML parses back into the same values.
    wrapped = xml
    for tag in reversed(tags[:-1]):
        wrapped = f"<{tag}>{wrapped}</{tag}>"
    parsed = mjcf.from_xml_string(
        f"<mujoco>{wrapped}</mujoco>", resolve_references=False, assets=root.get_assets()
    )
    again = _find_path(parsed, tags)
    for attribute in spec.attributes.values():
        expected = element.get_attribute_xml_string(attribute.python_name)
        assert again.get_attribute_xml_string(attribute.python_name) == expected


def _find_path(root, tags):
    element = root
    for tag in tags:
        child_spec = element.spec.children[tag]
        element = element.get_children(tag)[0] if child_spec.repeated else getattr(element, tag)
    return element


def _keyword_cases():
    cases = []
    for spec, tags in _PATHS:
        if "default" in tags:
            continue
        for attribute in spec.attributes.values():
            if isinstance(attribute.type, attribute_types.Keyword):
                for value in attribute.type.values:
                    cases.append((tags, attribute.python_name, value))
    return cases


_KEYWORDS = _keyword_cases()


@pytest.mark.parametrize(
    "tags,name,value", _KEYWORDS, ids=[f"{'/'.join(t)}.{n}={v}" for t, n, v in _KEYWORDS]
)
def test_every_keyword_value_is_accepted_by_mujoco(tags, name, value):
    root = mjcf.RootElement()
    element = _add_complete(root, tags)
    without = _mujoco_error(root.to_xml_string())
    setattr(element, name, value)
    xml = root.to_xml_string()
    reason = _UNSUPPORTED_KEYWORDS.get((tags[-1], name, value))
    if reason is not None:
        assert reason in _mujoco_error(xml)
    else:
        assert _mujoco_error(xml) == without, xml


def _add_complete(root, tags):
    """Adds the element at `tags`, inside a body rather than the world body (which takes no
    inertia), named if it can be, so that MuJoCo may accept it as it is."""
    if tags[0] == "worldbody" and len(tags) > 1 and tags[1] != "body":
        tags = ("worldbody", "body") + tags[1:]
    element = _add_path(root, tags)
    if "name" in element.spec.attributes:
        element.name = "x"
    for name, value in _REQUIRED.get(element.tag, {}).items():
        setattr(element, name, value)
    return element


# What MuJoCo requires of these elements before it accepts them at all.
_REQUIRED = {
    "inertial": {"pos": [0, 0, 0], "mass": 1},
    "hfield": {"size": [1, 1, 1, 1]},
    "flexcomp": {"type": "grid", "count": [2, 2, 1], "spacing": [1, 1, 1]},
}
# Arrays whose all-ones value is degenerate: a valid value of the longest length instead.
_LONGEST_VALUES = {"xyaxes": [1, 0, 0, 0, 1, 0], "count": [2, 2, 1]}
# Keyword values MuJoCo lists but rejects, with the reason it gives.
_UNSUPPORTED_KEYWORDS = {("compiler", "coordinate", "global"): "no longer supported"}


def _mujoco_error(xml: str) -> str | None:
    """MuJoCo's parse error for `xml` without line numbers, or None if it parses.

    An element added on its own may lack what MuJoCo requires of it; comparing against the
    same model without the attribute keeps such an unrelated error from hiding (or
    passing for) a rejection of the value under test.
    """
    try:
        mujoco.MjSpec.from_string(xml)
    except ValueError as error:
        return re.sub(r"line \d+", "line", str(error))
    return None


def _array_cases():
    cases = []
    for spec, tags in _PATHS:
        if "default" in tags:
            continue
        for attribute in spec.attributes.values():
            value_type = attribute.type
            if isinstance(value_type, attribute_types.Array) and value_type.lengths[1]:
                cases.append((tags, attribute.python_name, value_type.lengths[1]))
    return cases


_ARRAYS = _array_cases()


@pytest.mark.parametrize(
    "tags,name,length", _ARRAYS, ids=[f"{'/'.join(t)}.{n}" for t, n, _ in _ARRAYS]
)
def test_longest_allowed_array_is_accepted_by_mujoco(tags, name, length):
    root = mjcf.RootElement()
    element = _add_complete(root, tags)
    without = _mujoco_error(root.to_xml_string())
    setattr(element, name, _LONGEST_VALUES.get(name, [1] * length))
    xml = root.to_xml_string()
    # Some releases require other arrays with this one (mujoco 3.3's camera `focal` needs
    # `sensorsize`, which needs `resolution`): give them too, as a user would.
    for _ in element.spec.attributes:
        error = _mujoco_error(xml)
        companion = re.match(r"XML Error: required attribute missing: '(\w+)'", error or "")
        if error == without or not companion or companion.group(1) not in element.spec.attributes:
            break
        companion_type = element.spec.attributes[companion.group(1)].type
        setattr(element, companion.group(1), [1] * companion_type.lengths[1])
        xml = root.to_xml_string()
    assert _mujoco_error(xml) == without, xml


def test_namespaces_follow_mujoco_object_families():
    root = schema.root_spec()
    body = root.children["worldbody"].children["body"]
    assert body.namespace == "body"
    assert body.children["freejoint"].namespace == "joint"
    assert root.children["actuator"].children["motor"].namespace == "actuator"
    assert root.children["sensor"].children["touch"].namespace == "sensor"
    assert root.children["equality"].children["weld"].namespace == "equality"
    assert root.children["tendon"].children["spatial"].namespace == "tendon"
    assert root.children["keyframe"].children["key"].namespace == "key"
    assert root.children["default"].children["geom"].namespace is None
    assert body.children["inertial"].namespace is None
    assert registry_namespace(root.children["default"]) == "default"
