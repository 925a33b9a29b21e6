"""Helpers that walk models: attachment frames, free joints, and committing defaults."""

from __future__ import annotations

from mjcf import constants
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
    _commit(element, None, attributes)


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
            template = default._singleton_if_present(_default_tag(element))
            if template is None:
                continue
            for name, value in template._attributes.items():
                if attributes is not None and spec.attributes[name].python_name not in attributes:
                    continue
                if name not in element._attributes and name in spec.attributes:
                    element._set_attribute(spec.attributes[name].python_name, value)
    for child in element._children:
        _commit(child, inherited, attributes)
    element._changed()


def _default_tag(element: Element) -> str:
    """Tag under `<default>` that configures `element` (e.g. 'equality' for `<weld>`)."""
    parent = element._parent
    parent_tag = parent._spec.name if parent is not None else ""
    if parent_tag in ("equality",):
        return "equality"
    if parent_tag == "tendon":
        return "tendon"
    return element._spec.name
