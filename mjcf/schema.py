"""MJCF element tree read from the installed MuJoCo (`mujoco.mj_printSchema`) at import.

Each element is described by an `ElementSpec`: its tag, whether it may repeat, its children
and its attributes (names from MuJoCo, types from `mjcf.attribute_table`). The world body is
MuJoCo's body element without attributes; bodies, frames and default classes nest
recursively. `<frame>`, which MuJoCo reads but does not list, is the one element added here.
"""

from __future__ import annotations

import functools

import mujoco

from mjcf import attribute_table, attribute_types

# Where a child tag appears under these parents, its namespace is the parent's tag.
_NAMESPACE_FROM_PARENT = ("actuator", "sensor", "equality", "tendon")
# Tags whose namespace is not their own tag.
_NAMESPACE_OF_TAG = {"freejoint": "joint", "key": "key", "instance": "plugin", "flexcomp": "flex"}
_SCHEMA_COLUMN = 30
# MuJoCo reads <frame> (a pose and default class for a group of a body's children) but
# mj_printSchema does not list it. It holds what a body holds; of the body's attributes, it
# takes these.
_FRAME_ATTRIBUTES = ("name", "childclass", "pos", "quat", "axisangle", "xyaxes", "zaxis", "euler")
# Children MuJoCo lists as repeatable that a body can meaningfully hold only once.
_SINGLE_CHILDREN = ("freejoint",)


class AttributeSpec:
    """One attribute of an element: its XML name, Python name and value type."""

    __slots__ = ("name", "python_name", "type")

    def __init__(self, name: str, attribute_type: attribute_types.AttributeType):
        self.name = name
        self.python_name = "dclass" if name == "class" else name
        self.type = attribute_type

    def __repr__(self) -> str:
        return f"AttributeSpec({self.name!r}, {type(self.type).__name__})"


class ElementSpec:
    """Schema of one element kind.

    Attributes:
      name: the XML tag.
      repeated: whether a parent may hold several of these (False: at most one, created on
        first access as an attribute of the parent).
      attributes: XML attribute name -> `AttributeSpec`, in MuJoCo's order.
      children: child tag -> `ElementSpec`.
      namespace: the MuJoCo object family this element compiles to, or None.
      identifier: the attribute that names this element uniquely in its namespace, or None.
      path: tags from the root, for error messages.
      takes_class: whether the element has a `class` attribute (takes a default class).
      sets_childclass: whether the element has a `childclass` attribute (sets the default
        class of the elements inside it: bodies and frames).
      holds_files: whether the element, or an element that may be nested in it, has file
        attributes (so searches for file assets can skip the rest).
    """

    __slots__ = (
        "name",
        "repeated",
        "attributes",
        "children",
        "namespace",
        "identifier",
        "path",
        "python_attributes",
        "takes_class",
        "sets_childclass",
        "holds_files",
    )

    def __init__(self, name: str, repeated: bool, path: str):
        self.name = name
        self.repeated = repeated
        self.attributes: dict[str, AttributeSpec] = {}
        self.children: dict[str, ElementSpec] = {}
        self.namespace: str | None = None
        self.identifier: str | None = None
        self.path = path
        self.python_attributes: dict[str, AttributeSpec] = {}
        self.takes_class = False
        self.sets_childclass = False
        self.holds_files = False

    @property
    def on_demand(self) -> bool:
        return not self.repeated

    def _set_attributes(self, names) -> None:
        for name in names:
            spec = AttributeSpec(name, attribute_table.attribute_type(self.name, name))
            self.attributes[name] = spec
            self.python_attributes[spec.python_name] = spec
            if name == "class":
                self.python_attributes[name] = spec
                self.takes_class = True
            elif name == "childclass":
                self.sets_childclass = True

    def __repr__(self) -> str:
        return f"ElementSpec({self.path!r})"


def _parse_lines(text: str):
    """Yields (depth, tag, marker, attribute names) per element of the printed schema."""
    current = None
    for line in text.splitlines():
        if not line.strip():
            continue
        head, tail = line[:_SCHEMA_COLUMN], line[_SCHEMA_COLUMN:].split()
        if head.strip():
            if current is not None:
                yield current
            depth = (len(head) - len(head.lstrip())) // 3
            tag, marker = head.split()
            current = (depth, tag, marker.strip("()"), list(tail))
        else:
            current[3].extend(tail)
    if current is not None:
        yield current


def _namespace(tag: str, parent_tag: str, attributes) -> str | None:
    if "name" not in attributes:
        return None
    if parent_tag in _NAMESPACE_FROM_PARENT:
        return parent_tag
    return _NAMESPACE_OF_TAG.get(tag, tag)


@functools.cache
def root_spec() -> ElementSpec:
    """Returns the spec of `<mujoco>`, parsed from the installed MuJoCo once."""
    text = mujoco.mj_printSchema(False, False)
    stack: list[ElementSpec] = []
    root = None
    for depth, tag, marker, names in _parse_lines(text):
        del stack[depth:]
        parent = stack[-1] if stack else None
        if tag == "(world)body":
            world = _make_spec("worldbody", parent, False, [])
            body = _make_spec("body", world, True, names)
            world.children = body.children
            body.children["body"] = body
            frame_attributes = [name for name in _FRAME_ATTRIBUTES if name in body.attributes]
            _make_spec("frame", body, True, frame_attributes).children = body.children
            stack.append(body)
            continue
        # Sections directly under <mujoco> are single containers in the object model.
        repeated = (
            marker in ("*", "R")
            and parent is not None
            and parent.name != "mujoco"
            and tag not in _SINGLE_CHILDREN
        )
        spec = _make_spec(tag, parent, repeated, names)
        if marker == "R":
            spec.children[tag] = spec if repeated else _nested_copy(spec)
        if parent is None:
            root = spec
        stack.append(spec)
    _mark_file_holders(root)
    return root


def _mark_file_holders(root: ElementSpec) -> None:
    """Sets `holds_files` on every spec (children may nest recursively, so iterate)."""
    specs = _reachable(root)
    for spec in specs:
        spec.holds_files = any(
            a.type.kind == attribute_types.FILE for a in spec.attributes.values()
        )
    changed = True
    while changed:
        changed = False
        for spec in specs:
            if not spec.holds_files and any(c.holds_files for c in spec.children.values()):
                spec.holds_files = changed = True


def _make_spec(tag, parent, repeated, names) -> ElementSpec:
    path = f"{parent.path}/{tag}" if parent is not None else tag
    spec = ElementSpec(tag, repeated, path)
    spec._set_attributes(names)
    if parent is not None:
        parent.children[tag] = spec
        if parent.name != "default":
            spec.namespace = _namespace(tag, parent.name, spec.attributes)
    if tag == "default":
        spec.identifier = "class"
    elif spec.namespace is not None:
        spec.identifier = "name"
    return spec


def _nested_copy(spec: ElementSpec) -> ElementSpec:
    """The repeatable form of a single section that nests in itself (`<default>`)."""
    nested = ElementSpec(spec.name, True, f"{spec.path}/{spec.name}")
    nested.attributes = spec.attributes
    nested.python_attributes = spec.python_attributes
    nested.children = spec.children
    nested.namespace = spec.namespace
    nested.identifier = spec.identifier
    nested.takes_class = spec.takes_class
    nested.sets_childclass = spec.sets_childclass
    return nested


def all_specs() -> list[ElementSpec]:
    """Every distinct element spec reachable from the root, parents before children."""
    return _reachable(root_spec())


def _reachable(root: ElementSpec) -> list[ElementSpec]:
    seen = {id(root)}
    order = [root]
    for spec in order:
        for child in spec.children.values():
            if id(child) not in seen:
                seen.add(id(child))
                order.append(child)
    return order


@functools.cache
def namespaces() -> frozenset[str]:
    """Every namespace `find` and `find_all` accept: the object families of the schema, plus
    'default' (classes), 'attachment_frame' and 'keyframe' (another spelling of 'key')."""
    found = {spec.namespace for spec in all_specs() if spec.namespace is not None}
    return frozenset(found | {"default", "attachment_frame", "keyframe"})
