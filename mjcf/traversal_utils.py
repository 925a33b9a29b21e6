"""Helpers that walk models: attachment frames, free joints, and committing defaults."""

from __future__ import annotations

import functools

from mjcf import constants, schema
from mjcf.element import Element, RootElement, registry_namespace


def get_attachment_frame(mjcf_model: RootElement):
    """The attachment frame `mjcf_model` is attached at, or None when it is not attached."""
    return mjcf_model._frame


def get_freejoint(element: Element) -> Element | None:
    """The `<freejoint>` (or free `<joint>`) directly in a body or attachment frame, or None."""
    if element is None:
        return None
    for child in element._children:
        tag = child._spec.name
        if tag == "freejoint" or (tag == "joint" and child._attributes.get("type") == "free"):
            return child
    return None


def get_frame_freejoint(mjcf_model: RootElement) -> Element | None:
    """The free joint of the frame `mjcf_model` is attached at, or None."""
    return get_freejoint(get_attachment_frame(mjcf_model))


def get_frame_joints(mjcf_model: RootElement) -> list[Element] | None:
    """The non-free joints of the frame `mjcf_model` is attached at (None when not attached)."""
    frame = get_attachment_frame(mjcf_model)
    if frame is None:
        return None
    return [
        child
        for child in frame._children
        if child._spec.name == "joint" and child._attributes.get("type") != "free"
    ]


def _default_chain(element: Element, dclass) -> list[Element]:
    """Default classes that apply to `element`, most specific first."""
    root = element._root
    if dclass is None:
        return [root.default]
    if isinstance(dclass, str):
        found = root.find(constants.DEFAULT, dclass)
        if found is None:
            raise ValueError(
                f"{element._describe()}: default class {dclass!r} does not exist in model "
                f"{root._namescope.name!r}"
            )
        dclass = found
    chain = []
    current = dclass
    while current is not None and current is not root:
        chain.append(current)
        current = current._parent
    return chain


def commit_defaults(element: Element, attributes: list[str] | None = None) -> None:
    """Writes default-class values explicitly onto every element below `element`.

    For each element that takes defaults, every attribute it leaves unset but its default
    classes set (optionally only those named in `attributes`) is copied onto it; the model
    then compiles the same without relying on `<default>`.
    """
    _commit(element, _inherited_childclass(element), attributes)


def _inherited_childclass(element: Element):
    """The `childclass` of `element`'s nearest ancestor that sets one, or None."""
    parent = element._parent
    while parent is not None:
        childclass = parent._attributes.get("childclass")
        if childclass is not None:
            return childclass
        parent = parent._parent
    return None


def _commit(element: Element, inherited, attributes) -> None:
    spec = element._spec
    tag = spec.name
    if tag == constants.DEFAULT:
        return
    if spec.sets_childclass:
        inherited = element._attributes.get("childclass", inherited)
    if "class" in spec.attributes and registry_namespace(spec) != constants.DEFAULT:
        dclass = element._attributes.get("class", inherited)
        for default in _default_chain(element, dclass):
            for tag in _default_tags(element):
                _commit_template(element, default._singleton_if_present(tag), attributes)
    for child in element._children:
        _commit(child, inherited, attributes)
    element._changed()


def _commit_template(element: Element, template: Element | None, attributes) -> None:
    """Copies onto `element` the attributes default `template` sets and `element` does not."""
    if template is None:
        return
    spec = element._spec
    for name, value in template._attributes.items():
        if name not in spec.attributes:
            continue
        python_name = spec.attributes[name].python_name
        if attributes is not None and python_name not in attributes:
            continue
        if name not in element._attributes:
            element._set_attribute(python_name, value)


def _default_tags(element: Element) -> tuple[str, ...]:
    """Tags under `<default>` that configure `element`, in order of precedence: 'equality'
    for `<weld>`, and for an actuator every actuator kind (MuJoCo keeps one actuator
    default per class, which each kind's tag sets)."""
    parent = element._parent
    parent_tag = parent._spec.name if parent is not None else ""
    if parent_tag == "equality":
        return ("equality",)
    if parent_tag == "tendon":
        return ("tendon",)
    if parent_tag == constants.ACTUATOR:
        return _actuator_default_tags()
    return (element._spec.name,)


@functools.cache
def _actuator_default_tags() -> tuple[str, ...]:
    root = schema.root_spec()
    in_defaults = root.children[constants.DEFAULT].children
    return tuple(tag for tag in root.children[constants.ACTUATOR].children if tag in in_defaults)


def is_default_template(element: Element) -> bool:
    """Whether `element` is a template of a default class (a child of a `<default>`)."""
    parent = element._parent
    return parent is not None and parent._spec.name == constants.DEFAULT


def default_value_source(element: Element, xml_name: str) -> Element | None:
    """The element whose value of attribute `xml_name` compiles into `element`.

    `element` itself when it sets the attribute, else the template under the most specific
    of its default classes that sets it. None when neither does (MuJoCo's built-in default
    applies) or when `element` takes its defaults from more than one kind of template (an
    actuator, a `<weld>`, a tendon), which is not resolved here.
    """
    if xml_name in element._attributes:
        return element
    return class_value_source(element, xml_name)


def class_value_source(element: Element, xml_name: str) -> Element | None:
    """The template under the most specific of `element`'s default classes that sets
    attribute `xml_name`, whatever `element` sets itself; None as `default_value_source`
    gives it."""
    tags = _default_tags(element)
    if tags != (element._spec.name,):
        return None
    dclass = element._attributes.get("class", _inherited_childclass(element))
    for default in _default_chain(element, dclass):
        template = default._singleton_if_present(tags[0])
        if template is not None and xml_name in template._attributes:
            return template
    return None


def default_classes(element: Element) -> list[Element]:
    """The `<default>` elements whose templates apply to `element`, most specific first."""
    return _default_chain(element, element._attributes.get("class", _inherited_childclass(element)))
