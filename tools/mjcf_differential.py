"""Differential testing of the MJCF pipeline against MuJoCo's own parser.

One *document* (MJCF text plus the files it names, in a directory) is compiled twice: by
MuJoCo (`mujoco.MjModel.from_xml_path`) and by this project (`mjcf.from_path` then
`mjcf.Physics.from_mjcf_model`). `compare` classifies the pair of outcomes as a `Verdict`.
Documents come from seed models mutated by one of `MUTATION_KINDS`, or are generated from
the schema. Used by tests/mjcf/test_differential_fuzz.py and `tools.fuzz`.

The deliberate differences from MuJoCo listed in docs/mujoco_differences.md are encoded
here: `IGNORED_SIZES`, `IGNORED_ARRAYS` and `_documented_difference`.
"""

from __future__ import annotations

import copy
import enum
import os
import random
import re
import shutil
import tempfile
from typing import NamedTuple

import mujoco
import numpy as np
from lxml import etree

import mjcf
from mjcf import attribute_types, schema
from mujoco_physics import field_layout

#: Exception types the MJCF layer documents for bad input (docs/mujoco_differences.md).
DOCUMENTED_ERRORS = (ValueError, OSError)

#: Model sizes that differ by design: generated names for unnamed elements, and file
#: assets handed to MuJoCo as bytes rather than paths (so no paths are stored), change the
#: sizes of the name and path buffers and so of the whole buffer.
IGNORED_SIZES = frozenset({"nnames", "nnames_map", "npaths", "nbuffer"})
#: Model arrays that differ by design, for the same reasons.
IGNORED_ARRAYS = frozenset({"names", "names_map", "paths"})
IGNORED_ARRAY_SUFFIXES = ("_pathadr",)


class Verdict(enum.Enum):
    """How our outcome on a document relates to MuJoCo's."""

    AGREE = "agree"
    FALSE_REJECTION = "false rejection"
    SILENT_ACCEPTANCE = "silent acceptance"
    MISMATCH = "compiled differently"
    CRASH = "crash"
    UNCLEAR = "unclear exception"
    DOCUMENTED = "documented difference"
    MUJOCO_CRASH = "MuJoCo itself crashed"


class Outcome(NamedTuple):
    """The result of compiling a document: a model, or the exception raised."""

    model: mujoco.MjModel | None
    error: BaseException | None


class Result(NamedTuple):
    """A verdict with the detail that explains it (field names, exception text)."""

    verdict: Verdict
    detail: str


class Document(NamedTuple):
    """MJCF text, its mutation kind and a description of the mutation."""

    kind: str
    text: str
    note: str


def mujoco_outcome(path: str | None, text: str | None = None) -> Outcome:
    """MuJoCo's compile of the file at `path`, or of `text` when `path` is None."""
    try:
        if path is None:
            return Outcome(mujoco.MjModel.from_xml_string(text), None)
        return Outcome(mujoco.MjModel.from_xml_path(path), None)
    except Exception as error:  # noqa: BLE001 - any MuJoCo error is a rejection
        return Outcome(None, error)


def our_outcome(path: str | None, text: str | None = None) -> Outcome:
    """Our parse and compile of the file at `path`, or of `text` when `path` is None."""
    try:
        root = mjcf.from_path(path) if path is not None else mjcf.from_xml_string(text)
        return Outcome(mjcf.Physics.from_mjcf_model(root).model.ptr, None)
    except Exception as error:  # noqa: BLE001 - classified by compare
        return Outcome(None, error)


# The model's sizes (`nq`, `ngeom`, ...) and arrays (of numbers and of characters) compared.
_SIZES = tuple(
    name
    for name in field_layout.MODEL_FIELDS.scalars
    if name.startswith("n") and name not in IGNORED_SIZES
)
_ARRAYS = tuple(
    name
    for name in field_layout.MODEL_FIELDS.arrays + field_layout.MODEL_FIELDS.texts
    if name not in IGNORED_ARRAYS
    and not name.startswith("name_")
    and not name.endswith(IGNORED_ARRAY_SUFFIXES)
)


def model_differences(theirs: mujoco.MjModel, ours: mujoco.MjModel) -> list[str]:
    """Names of the sizes and arrays (options included) in which two compiled models differ."""
    different = [n for n in _SIZES if getattr(theirs, n) != getattr(ours, n)]
    if different:
        return different
    for name in _ARRAYS:
        a, b = np.asarray(getattr(theirs, name)), np.asarray(getattr(ours, name))
        if a.shape != b.shape or not np.array_equal(a, b, equal_nan=a.dtype.kind == "f"):
            different.append(name)
    for struct in field_layout.MODEL_FIELDS.structs:
        if not _structs_equal(getattr(theirs, struct), getattr(ours, struct)):
            different.append(struct)
    return different


def _structs_equal(a, b) -> bool:
    for name in dir(a):
        if name.startswith("_"):
            continue
        x, y = getattr(a, name), getattr(b, name)
        if callable(x):
            continue
        if hasattr(x, "__dict__") or type(x).__module__.startswith("mujoco"):
            if not isinstance(x, (int, float, np.ndarray)) and not _structs_equal(x, y):
                return False
            continue
        if not np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True):
            return False
    return True


def _names_a_thing(message: str) -> bool:
    """Whether an error message points at an element, attribute or file."""
    return any(mark in message for mark in ("<", "Element", "element", "'", "file", "line"))


_DANGLING = re.compile(r"attribute '(\w+)' refers to '([^']*)', but model .* has no '(\w+)'")
_MUJOCO_ELEMENT = re.compile(r"Element '(\w+)'")


def documented_difference(text: str, theirs: Outcome, ours: Outcome) -> str | None:
    """Which documented difference (docs/mujoco_differences.md) explains a disagreement."""
    if _has_empty_reference(etree.fromstring(text.encode())):
        return "an empty reference is unset; MuJoCo may find an unnamed element by it"
    if theirs.model is not None and ours.error is not None:
        tree = etree.fromstring(text.encode())
        message = str(ours.error)
        match = _DANGLING.search(message)
        if match and (match.group(2), match.group(3)) != ("world", "body"):
            value, namespace = match.group(2), match.group(3)
            names = {
                e.get("name")
                for e in _elements(tree)
                if getattr(_spec_of(e), "namespace", None) == namespace
            }
            if value not in names:
                return "a reference to a missing element is an error, even one MuJoCo ignores"
        if isinstance(ours.error, FileNotFoundError) and "attribute" in message:
            return "a missing file is an error, even one MuJoCo does not read"
        unknown = "has no attribute" in message or "cannot have a child" in message
        if unknown and any(True for _ in tree.iter("frame")):
            return "an unknown attribute or child is an error, also inside <frame>"
        match = _MUJOCO_ELEMENT.search(message)
        if "required attribute missing: 'name'" in message and match:
            if any(e.get("name") == "" for e in tree.iter(match.group(1))):
                return "name='' is unset, also where MuJoCo keeps an empty name"
    if ours.model is not None:
        match = _MUJOCO_ELEMENT.search(str(theirs.error))
        tree = etree.fromstring(text.encode())
        if match and any(
            any(not value.strip() for value in e.attrib.values()) for e in tree.iter(match.group(1))
        ):
            # MuJoCo counts some blank attributes as given: a blank <freejoint group>
            # cannot be read, a blank quat next to euler is a second orientation.
            return "a blank number is unset, also where MuJoCo counts it as given"
        if match and any(_empty_single(e) for e in tree.iter(match.group(1))):
            return "an empty element is not written"
    return None


def _has_empty_reference(tree) -> bool:
    for node in _elements(tree):
        spec = _spec_of(node)
        for name, value in node.attrib.items():
            attribute = spec.attributes.get(name) if spec is not None else None
            if not value and attribute is not None:
                if attribute.type.kind == attribute_types.REFERENCE:
                    return True
    return False


def _empty_single(node) -> bool:
    spec = _spec_of(node)
    blank = all(not value.strip() for value in node.attrib.values())
    return len(node) == 0 and blank and spec is not None and not spec.repeated


def compare(theirs: Outcome, ours: Outcome, text: str | None = None) -> Result:
    """Classifies our outcome against MuJoCo's on the same document (`text`, if given, lets
    documented differences be recognised)."""
    both_compiled = theirs.model is not None and ours.model is not None
    if both_compiled:
        disagree = bool(model_differences(theirs.model, ours.model))
    else:
        disagree = (theirs.model is None) != (ours.model is None)
    if text is not None and disagree:
        reason = documented_difference(text, theirs, ours)
        if reason is not None:
            return Result(Verdict.DOCUMENTED, reason)
    if ours.error is not None and not isinstance(ours.error, DOCUMENTED_ERRORS):
        return Result(Verdict.CRASH, f"{type(ours.error).__name__}: {ours.error}")
    if ours.error is not None and not _names_a_thing(str(ours.error)):
        if theirs.error is not None and not _names_a_thing(str(theirs.error)):
            # MuJoCo's own message names nothing either (e.g. "could not allocate mjData
            # arena"); ours passes it on and cannot be clearer.
            return Result(Verdict.AGREE, "both reject, neither names the element")
        return Result(Verdict.UNCLEAR, f"{type(ours.error).__name__}: {ours.error}")
    if theirs.model is None and ours.model is None:
        return Result(Verdict.AGREE, "both reject")
    if theirs.model is None:
        return Result(Verdict.SILENT_ACCEPTANCE, f"MuJoCo: {theirs.error}")
    if ours.model is None:
        return Result(Verdict.FALSE_REJECTION, f"{type(ours.error).__name__}: {ours.error}")
    different = model_differences(theirs.model, ours.model)
    if different:
        return Result(Verdict.MISMATCH, ", ".join(different[:8]))
    return Result(Verdict.AGREE, "both accept, same model")


# ---------------------------------------------------------------------------------------
# Seed models.

_SEED_ARM = """
<mujoco model="arm">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="0.004" gravity="0 0 -9.81" integrator="implicitfast"/>
  <default>
    <joint damping="0.5" armature="0.01"/>
    <geom rgba="0.6 0.6 0.7 1" friction="0.8 0.01 0.001"/>
    <default class="finger">
      <geom type="box" size="0.01 0.01 0.03" condim="4"/>
      <joint range="0 0.04" type="slide"/>
    </default>
  </default>
  <worldbody>
    <light name="top" pos="0 0 2" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <camera name="front" pos="1.5 0 1" xyaxes="0 1 0 -0.5 0 1"/>
    <body name="base" pos="0 0 0.1">
      <geom name="base" type="cylinder" size="0.08 0.05" mass="2"/>
      <body name="upper" pos="0 0 0.05">
        <joint name="shoulder" axis="0 0 1" range="-3 3"/>
        <geom name="upper" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
        <body name="lower" pos="0.3 0 0">
          <joint name="elbow" axis="0 1 0" range="-2 2" stiffness="1"/>
          <geom name="lower" type="capsule" fromto="0 0 0 0.25 0 0" size="0.025" density="800"/>
          <site name="wrist" pos="0.25 0 0" size="0.01"/>
          <body name="hand" pos="0.27 0 0" euler="0 0.2 0">
            <inertial pos="0 0 0" mass="0.3" diaginertia="0.001 0.001 0.001"/>
            <body name="left" pos="0 0.03 0">
              <joint name="left" class="finger" axis="0 1 0"/>
              <geom name="left" class="finger"/>
            </body>
            <body name="right" pos="0 -0.03 0">
              <joint name="right" class="finger" axis="0 -1 0"/>
              <geom name="right" class="finger"/>
            </body>
          </body>
        </body>
      </body>
    </body>
    <body name="box" pos="0.5 0 0.05">
      <freejoint name="box"/>
      <geom name="box" type="box" size="0.03 0.03 0.03" mass="0.2"/>
    </body>
  </worldbody>
  <equality>
    <joint joint1="left" joint2="right" polycoef="0 1 0 0 0"/>
  </equality>
  <actuator>
    <motor name="shoulder" joint="shoulder" gear="20" ctrlrange="-1 1"/>
    <position name="elbow" joint="elbow" kp="30" ctrlrange="-2 2"/>
    <position name="grip" joint="left" kp="100" ctrlrange="0 0.04"/>
  </actuator>
  <sensor>
    <jointpos name="shoulder" joint="shoulder"/>
    <framepos name="wrist" objtype="site" objname="wrist"/>
    <touch name="touch" site="wrist"/>
  </sensor>
  <keyframe>
    <key name="home" qpos="0 0.5 0.01 0.01 0.5 0 0.03 1 0 0 0"/>
  </keyframe>
</mujoco>
"""

_SEED_ASSETS = """
<mujoco model="assets">
  <asset>
    <texture name="grid" type="2d" builtin="checker" width="64" height="64"
             rgb1="0.1 0.2 0.3" rgb2="0.2 0.3 0.4"/>
    <texture name="sky" type="skybox" builtin="gradient" width="32" height="32"/>
    <material name="grid" texture="grid" texrepeat="2 2" reflectance="0.1"/>
    <material name="red" rgba="1 0 0 1" specular="0.3"/>
    <mesh name="tetra" vertex="0 0 0  0.1 0 0  0 0.1 0  0 0 0.1" scale="1 1 2"/>
    <hfield name="bumps" nrow="3" ncol="4" size="1 1 0.2 0.1"
            elevation="0 1 0 1  1 0 1 0  0 1 0 1"/>
  </asset>
  <visual>
    <global offwidth="320" offheight="240"/>
    <quality shadowsize="1024"/>
  </visual>
  <statistic extent="2" center="0 0 0.5"/>
  <worldbody>
    <geom name="ground" type="hfield" hfield="bumps" material="grid"/>
    <body name="tetra" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="1 0 0"/>
      <joint name="ball" type="ball" pos="0 0 0.1"/>
      <geom name="tetra" type="mesh" mesh="tetra" material="red"/>
      <geom name="ellipsoid" type="ellipsoid" size="0.05 0.04 0.03" pos="0.1 0 0"/>
      <site name="tip" type="sphere" size="0.02"/>
    </body>
  </worldbody>
  <contact>
    <exclude body1="world" body2="tetra"/>
  </contact>
</mujoco>
"""

_SEED_TENDON = """
<mujoco model="tendons">
  <option timestep="0.002" cone="elliptic" impratio="2">
    <flag warmstart="disable"/>
  </option>
  <size memory="1M"/>
  <default>
    <default class="link">
      <geom type="capsule" size="0.02" density="500"/>
      <joint type="hinge" axis="0 1 0" limited="true" range="-90 90"/>
    </default>
  </default>
  <worldbody>
    <site name="anchor" pos="0 0 1"/>
    <body name="a" pos="0 0 1" childclass="link">
      <joint name="a"/>
      <geom fromto="0 0 0 0 0 -0.3"/>
      <site name="a" pos="0 0 -0.15"/>
      <body name="b" pos="0 0 -0.3">
        <joint name="b"/>
        <geom fromto="0 0 0 0 0 -0.3"/>
        <site name="b" pos="0 0 -0.3"/>
        <frame pos="0 0.1 0" euler="0 0 90">
          <geom name="framed" type="sphere" size="0.03"/>
        </frame>
      </body>
    </body>
  </worldbody>
  <tendon>
    <spatial name="cable" range="0 1" stiffness="10" width="0.005">
      <site site="anchor"/>
      <site site="a"/>
      <site site="b"/>
    </spatial>
    <fixed name="coupling">
      <joint joint="a" coef="1"/>
      <joint joint="b" coef="-0.5"/>
    </fixed>
  </tendon>
  <actuator>
    <general name="cable" tendon="cable" gainprm="5" ctrlrange="0 1" dyntype="filter"
             dynprm="0.1"/>
    <velocity name="b" joint="b" kv="2"/>
  </actuator>
  <sensor>
    <tendonpos tendon="cable"/>
    <actuatorfrc actuator="b"/>
    <subtreecom body="a"/>
  </sensor>
  <custom>
    <numeric name="gains" data="1 2 3"/>
    <text name="label" data="pendulum"/>
  </custom>
</mujoco>
"""

#: Seed name -> (MJCF text, {file name: path of a file the text refers to}).
SEEDS: dict[str, tuple[str, dict[str, str]]] = {
    "arm": (_SEED_ARM, {}),
    "assets": (_SEED_ASSETS, {}),
    "tendons": (_SEED_TENDON, {}),
}


def _add_mujoco_testdata() -> None:
    """Adds the MJCF files the installed `mujoco` wheel ships as test data, if any."""
    directory = os.path.join(os.path.dirname(mujoco.__file__), "testdata")
    if not os.path.isdir(directory):
        return
    files = {
        name: os.path.join(directory, name)
        for name in os.listdir(directory)
        if not name.endswith(".xml") and os.path.isfile(os.path.join(directory, name))
    }
    for name in sorted(os.listdir(directory)):
        if not name.endswith(".xml"):
            continue
        with open(os.path.join(directory, name), encoding="utf-8") as handle:
            text = handle.read()
        try:
            mujoco.MjModel.from_xml_path(os.path.join(directory, name))
        except ValueError:
            continue  # a file this MuJoCo cannot read is no seed
        SEEDS["mujoco/" + name] = (text, files)


_add_mujoco_testdata()


# ---------------------------------------------------------------------------------------
# Mutations. Each takes the parsed seed and a random.Random, changes the tree and returns a
# note, or None when the seed offers nothing to mutate that way.

_VALUES = (
    "", " ", "0", "1", "-1", "0.5", "2", "-0.25", "1e308", "1e400", "-1e-300", "1e-12",
    "nan", "inf", "-inf", "abc", "1 2", "1 2 3", "1 2 3 4", "0 0 0 0", "1 0 0 0 0 0 0",
    "true", "false", "TRUE", "auto", "0x10", "1,2,3", "  1  2   3 ", "+1", ".5", "5.",
    "1e", "--1", "1 2 3 4 5 6 7 8 9 10", "-0", "3.14159", "world", "main", "unknown_name",
)  # fmt: skip

_TAGS_TO_ADD = ("geom", "site", "joint", "body", "camera", "light", "inertial", "frame")

#: (parent tag, child tag) pairs that make MuJoCo 4.0 itself crash or hang whoever parses
#: them (docs/mujoco_differences.md): a `<plugin>` inside a `<mesh>` segfaults, and a
#: `<model>` asset without a file raises RuntimeError and deadlocks the next compile.
#: `tools.fuzz` runs documents in a worker process and counts these; the in-process
#: test never generates them.
MUJOCO_CRASHERS = frozenset({("mesh", "plugin"), ("asset", "model")})


def _elements(tree) -> list:
    return [e for e in tree.iter() if isinstance(e.tag, str)]


def _spec_of(node):
    """Our schema's spec for an lxml node, or None when the path is not in the schema."""
    path = []
    while node is not None:
        path.append(node.tag)
        node = node.getparent()
    spec = schema.root_spec()
    for tag in reversed(path[:-1]):
        spec = spec.children.get(tag)
        if spec is None:
            return None
    return spec


def _value_for(rng: random.Random, spec, attribute: str, tree) -> str:
    attribute_spec = spec.attributes.get(attribute) if spec is not None else None
    kind = getattr(attribute_spec, "type", None)
    choice = rng.random()
    if isinstance(kind, attribute_types.Keyword) and choice < 0.5:
        word = rng.choice(kind.values)
        return word.upper() if rng.random() < 0.2 else word
    if isinstance(kind, attribute_types.Reference) and choice < 0.5:
        names = [e.get("name") for e in _elements(tree) if e.get("name")]
        if names:
            return rng.choice(names)
    if isinstance(kind, attribute_types.Array) and choice < 0.5:
        low, high = kind.lengths
        count = rng.randint(max(low - 1, 0), (high or low + 3) + 1)
        numbers = [rng.choice(("0", "1", "-1", "0.1", "2.5", "1e-3", "10")) for _ in range(count)]
        return " ".join(numbers)
    return rng.choice(_VALUES)


def _with_attributes(tree) -> list:
    return [e for e in _elements(tree) if e.attrib]


def _attr_remove(tree, rng):
    nodes = _with_attributes(tree)
    if not nodes:
        return None
    node = rng.choice(nodes)
    name = rng.choice(sorted(node.attrib))
    del node.attrib[name]
    return f"<{node.tag}> -{name}"


def _attr_empty(tree, rng):
    nodes = _with_attributes(tree)
    if not nodes:
        return None
    node = rng.choice(nodes)
    name = rng.choice(sorted(node.attrib))
    node.set(name, rng.choice(("", " ", "  ")))
    return f"<{node.tag}> {name}=''"


def _attr_value(tree, rng):
    nodes = _with_attributes(tree)
    if not nodes:
        return None
    node = rng.choice(nodes)
    name = rng.choice(sorted(node.attrib))
    value = _value_for(rng, _spec_of(node), name, tree)
    node.set(name, value)
    return f"<{node.tag}> {name}={value!r}"


def _attr_add(tree, rng):
    candidates = []
    for node in _elements(tree):
        spec = _spec_of(node)
        if spec is not None:
            missing = [a for a in spec.attributes if a not in node.attrib]
            if missing:
                candidates.append((node, spec, missing))
    if not candidates:
        return None
    node, spec, missing = rng.choice(candidates)
    name = rng.choice(missing)
    value = _value_for(rng, spec, name, tree)
    node.set(name, value)
    return f"<{node.tag}> +{name}={value!r}"


def _attr_unknown(tree, rng):
    node = rng.choice(_elements(tree))
    name = rng.choice(("colour", "sizes", "mass2", "Name", "pos_", "xyz"))
    node.set(name, "1")
    return f"<{node.tag}> +{name}"


def _removable(tree) -> list:
    return [e for e in _elements(tree) if e.getparent() is not None]


def _elem_remove(tree, rng):
    nodes = _removable(tree)
    if not nodes:
        return None
    node = rng.choice(nodes)
    node.getparent().remove(node)
    return f"-<{node.tag}>"


def _elem_duplicate(tree, rng):
    nodes = _removable(tree)
    if not nodes:
        return None
    node = rng.choice(nodes)
    twin = copy.deepcopy(node)
    if rng.random() < 0.5 and twin.get("name"):
        twin.set("name", twin.get("name") + "_twin")
    node.addnext(twin)
    return f"2x<{node.tag} name={twin.get('name')!r}>"


def _elem_move(tree, rng):
    nodes = _removable(tree)
    if not nodes:
        return None
    node = rng.choice(nodes)
    targets = [e for e in _elements(tree) if node not in e.iterancestors() and e is not node]
    targets = [e for e in targets if e is not node.getparent() and not _inside(e, node)]
    if not targets:
        return None
    target = rng.choice(targets)
    target.append(node)
    return f"<{node.tag}> into <{target.tag}>"


def _inside(node, ancestor) -> bool:
    return any(a is ancestor for a in node.iterancestors())


def _elem_add(tree, rng):
    candidates = []
    for node in _elements(tree):
        spec = _spec_of(node)
        if spec is not None and spec.children:
            candidates.append((node, spec))
    node, spec = rng.choice(candidates)
    preferred = [t for t in _TAGS_TO_ADD if t in spec.children]
    allowed = [t for t in sorted(spec.children) if (node.tag, t) not in MUJOCO_CRASHERS]
    if not allowed:
        return None
    tag = rng.choice(preferred if preferred and rng.random() < 0.7 else allowed)
    child = etree.SubElement(node, tag)
    child_spec = spec.children[tag]
    names = list(child_spec.attributes)
    for name in rng.sample(names, min(len(names), rng.randint(0, 3))):
        child.set(name, _value_for(rng, child_spec, name, tree))
    return f"+<{tag} {dict(child.attrib)}> in <{node.tag}>"


def _elem_unknown(tree, rng):
    node = rng.choice(_elements(tree))
    tag = rng.choice(("geometry", "Body", "sensors", "blob", "joints"))
    etree.SubElement(node, tag)
    return f"+<{tag}> in <{node.tag}>"


def _name_clash(tree, rng):
    named = [e for e in _elements(tree) if e.get("name")]
    pairs = [(a, b) for a in named for b in named if a is not b and a.tag == b.tag]
    if not pairs:
        return None
    a, b = rng.choice(pairs)
    a.set("name", b.get("name"))
    return f"<{a.tag}> name={b.get('name')!r} twice"


def _ref_dangling(tree, rng):
    refs = []
    for node in _elements(tree):
        spec = _spec_of(node)
        if spec is None:
            continue
        for name in node.attrib:
            attribute = spec.attributes.get(name)
            if attribute is not None and attribute.type.kind == attribute_types.REFERENCE:
                refs.append((node, name))
    if not refs:
        return None
    node, name = rng.choice(refs)
    node.set(name, rng.choice(("missing", "world", "main", "")))
    return f"<{node.tag}> {name}={node.get(name)!r}"


MUTATIONS = {
    "attr_remove": _attr_remove,
    "attr_empty": _attr_empty,
    "attr_value": _attr_value,
    "attr_add": _attr_add,
    "attr_unknown": _attr_unknown,
    "elem_remove": _elem_remove,
    "elem_duplicate": _elem_duplicate,
    "elem_move": _elem_move,
    "elem_add": _elem_add,
    "elem_unknown": _elem_unknown,
    "name_clash": _name_clash,
    "ref_dangling": _ref_dangling,
}

MUTATION_KINDS = ("seed", *MUTATIONS, "generated")


def mutate(seed: str, kind: str, rng: random.Random, steps: int = 1) -> Document:
    """The seed's text changed by `steps` mutations of `kind` ('seed': unchanged)."""
    text = SEEDS[seed][0]
    if kind == "seed":
        return Document(kind, text, seed)
    tree = etree.fromstring(text.encode())
    notes = []
    for _ in range(steps):
        note = MUTATIONS[kind](tree, rng)
        if note is not None:
            notes.append(note)
    return Document(kind, etree.tostring(tree, encoding="unicode"), f"{seed}: {'; '.join(notes)}")


# ---------------------------------------------------------------------------------------
# Generated documents: random body trees with random children and attributes.


def generate(rng: random.Random) -> Document:
    """A document built from scratch: nested bodies holding schema-chosen elements."""
    root = etree.Element("mujoco")
    world = etree.SubElement(root, "worldbody")
    bodies = [world]
    for _ in range(rng.randint(1, 6)):
        parent = rng.choice(bodies)
        body = etree.SubElement(parent, "body", pos=f"0 0 {rng.choice(('0.1', '1', '-0.5'))}")
        bodies.append(body)
        for _ in range(rng.randint(0, 3)):
            _elem_add(root, rng)
    for _ in range(rng.randint(0, 3)):
        for mutation in (_attr_value, _attr_add, _attr_remove):
            if rng.random() < 0.3:
                mutation(root, rng)
    if rng.random() < 0.5:
        actuators = etree.SubElement(root, "actuator")
        joints = [e.get("name") for e in root.iter("joint") if e.get("name")]
        for index in range(rng.randint(1, 2)):
            kind = rng.choice(("motor", "position", "velocity", "general"))
            actuator = etree.SubElement(actuators, kind, name=f"act{index}")
            if joints:
                actuator.set("joint", rng.choice(joints))
    text = etree.tostring(root, encoding="unicode")
    return Document("generated", text, "generated")


# ---------------------------------------------------------------------------------------
# Running a document.


class Workspace:
    """A temporary directory holding the files the seeds name; documents are written here."""

    def __init__(self):
        self.directory = tempfile.mkdtemp(prefix="mjcf_fuzz_")
        for _, files in SEEDS.values():
            for name, path in files.items():
                shutil.copy(path, os.path.join(self.directory, name))
        self.path = os.path.join(self.directory, "model.xml")

    def run(self, document: Document, mujoco_done=None) -> Result:
        """Compiles the document both ways and compares; `mujoco_done()` is called between.

        A document that names files is compiled from a file in the workspace (from_path,
        from_xml_path); any other from its text (from_xml_string on both sides).
        """
        path = None
        if "file=" in document.text:
            path = self.path
            with open(path, "w", encoding="utf-8") as handle:
                handle.write(document.text)
        theirs = mujoco_outcome(path, document.text)
        if theirs.error is not None and not isinstance(theirs.error, ValueError):
            # MuJoCo 4.0 raises RuntimeError('Caught an unknown exception!') on some inputs
            # and may then deadlock on the next compile in the process.
            return Result(Verdict.MUJOCO_CRASH, f"{type(theirs.error).__name__}: {theirs.error}")
        if mujoco_done is not None:
            mujoco_done()
        return compare(theirs, our_outcome(path, document.text), document.text)

    def close(self) -> None:
        shutil.rmtree(self.directory, ignore_errors=True)


def document_for(kind: str, rng: random.Random) -> Document:
    """A document of the given mutation kind from a random seed."""
    if kind == "generated":
        return generate(rng)
    seed = rng.choice(sorted(SEEDS))
    return mutate(seed, kind, rng, steps=1 if rng.random() < 0.8 else 2)
