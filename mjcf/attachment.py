"""Attaching one model to another (`attach`), and the global options attached models share.

The attachment frame itself is `mjcf.element.AttachmentFrame`, re-exported here.
"""

from __future__ import annotations

import numpy as np

from mjcf import constants
from mjcf.element import AttachmentFrame, Element, RootElement
from mjcf.option_merging import MERGED_OPTIONS

# `AttachmentFrame` lives in `mjcf.element`, next to the `Element` methods it overrides.
__all__ = ["AttachmentFrame", "attach", "global_options"]

_ATTACHABLE_TAGS = ("site", "body", "worldbody")
_SITE_POSE_ATTRIBUTES = ("pos", "quat", "axisangle", "xyaxes", "zaxis", "euler")


def attach(site_or_body: Element, model: RootElement) -> AttachmentFrame:
    """Attaches `model` at `site_or_body` and returns the new attachment frame."""
    where = site_or_body
    if where._spec.name not in _ATTACHABLE_TAGS or isinstance(where, AttachmentFrame):
        raise ValueError(
            f"{where._describe()}: models can only be attached to a site, a body or the worldbody"
        )
    if where._removed:
        raise RuntimeError(f"{where._describe()} has been removed from its model")
    if not isinstance(model, RootElement):
        raise ValueError(
            f"{where._describe()}.attach: expected an mjcf.RootElement, got {type(model).__name__}"
        )
    parent_model = where._root
    if model._frame is not None:
        raise ValueError(
            f"model {model._namescope.name!r} is already attached to model "
            f"{model._frame._root._namescope.name!r}; detach it first or attach a copy "
            "(copy.deepcopy)"
        )
    ancestor = parent_model
    while ancestor is not None:
        if ancestor is model:
            raise ValueError(
                f"model {model._namescope.name!r} cannot be attached to itself or to a "
                "model attached below it"
            )
        ancestor = ancestor._frame._root if ancestor._frame is not None else None
    name = model._namescope.name
    if parent_model._attached_model(name) is not None:
        # As dm_control does: the newcomer is renamed 'name_1', 'name_2', ...
        suffix = 1
        while parent_model._attached_model(f"{name}_{suffix}") is not None:
            suffix += 1
        model._set_attribute("model", f"{name}_{suffix}")
    _check_global_options(parent_model.root_model, model)

    body = where._parent if where._spec.name == "site" else where
    frame = AttachmentFrame._create(body._spec.children["body"], body, parent_model)
    frame._attached = model
    if where._spec.name == "site":
        for attribute in _SITE_POSE_ATTRIBUTES:
            value = where._attributes.get(attribute)
            if value is not None:
                frame._set_attribute(attribute, value)
    body._children.append(frame)
    parent_model._frames.append(frame)
    model._frame = frame
    parent_model._namescope.naming_changed()
    _merge_options(parent_model, model)
    frame._changed()
    frame._files_changed()
    return frame


def _merge_options(parent: RootElement, child: RootElement) -> None:
    """Sets the options of `parent` that attached models may set differently (see
    `mjcf.option_merging`) to their values merged with those of `child`."""
    theirs = global_options(child)
    for key, merge in MERGED_OPTIONS.items():
        value = theirs.get(key)
        if value is None:
            continue
        path, name = key
        element = parent
        for tag in path:
            element = element._singleton(element._spec.children[tag])
        mine = element._attributes.get(name)
        merged = value if mine is None else merge(mine, value)
        if merged != mine:
            element._set_attribute(name, merged)


def global_options(model: RootElement) -> dict:
    """Explicitly set global options of `model` and everything attached below it.

    Returns (section path, attribute) -> value; the first model to set a value wins.
    """
    options: dict = {}
    stack = [model]
    while stack:
        current = stack.pop(0)
        for section in current._children:
            if section._spec.name in constants.GLOBAL_OPTION_SECTIONS:
                _collect_options(section, (section._spec.name,), options)
        stack.extend(frame._attached for frame in current._frames)
    return options


def _collect_options(element: Element, path: tuple, options: dict) -> None:
    skip = constants.ASSET_DIRECTORY_ATTRIBUTES if path == ("compiler",) else ()
    for name, value in element._attributes.items():
        if name not in skip:
            options.setdefault((path, name), value)
    for child in element._children:
        _collect_options(child, path + (child._spec.name,), options)


def _check_global_options(parent: RootElement, child: RootElement) -> None:
    mine = global_options(parent)
    for key, value in global_options(child).items():
        if key not in mine or key in MERGED_OPTIONS:
            continue
        other = mine[key]
        same = (
            np.array_equal(other, value)
            if isinstance(other, np.ndarray) or isinstance(value, np.ndarray)
            else other == value
        )
        if not same:
            path, name = key
            raise ValueError(
                f"cannot attach model {child._namescope.name!r} to model "
                f"{parent._namescope.name!r}: global option <{'/'.join(path)}> {name!r} is "
                f"{value!r} in the child but {other!r} in the parent"
            )
