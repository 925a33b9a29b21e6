"""Resolving identifiers that may be scoped into attached models ('arm/hand/site')."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import mujoco
from lxml import etree

from mjcf import constants
from mjcf.asset import Asset

if TYPE_CHECKING:
    from mjcf.element import Element, RootElement

_SEP = constants.PREFIX_SEPARATOR
_WORLD = "world"
_SUB_MODEL = "model"


def split_identifier(identifier: str) -> tuple[str, str | None]:
    """Splits 'scope/rest' at the first unescaped separator; ('name', None) if there is none."""
    start = 0
    while True:
        index = identifier.find(_SEP, start)
        if index < 0:
            return identifier, None
        if index > 0 and identifier[index - 1] == constants.PREFIX_SEPARATOR_ESCAPE:
            start = index + 1
            continue
        return identifier[:index], identifier[index + 1 :]


def lookup(root: RootElement, namespace: str, identifier: str) -> Element | None:
    """Resolves a possibly scoped identifier ('arm/hand/site', 'arm/', '//unnamed_geom_0')."""
    while True:
        head, rest = split_identifier(identifier)
        if rest is None:
            break
        if not head:
            # '//unnamed_x_0' at the top scope, 'scope//unnamed_x_0' below it.
            unnamed = rest if rest.startswith(_SEP) else _SEP + rest
            return root._namescope.get_unnamed(namespace, unnamed)
        model = root._attached_model(head)
        if model is None:
            if not rest and root._frame is not None:
                # 'arm/x/': joint 'x' of the frame that holds model 'arm'.
                return _frame_child(root._frame, namespace, head)
            return None
        if not rest and namespace in (constants.BODY, constants.ATTACHMENT_FRAME):
            return model._frame
        if not rest and namespace == constants.JOINT:
            return model._frame.unnamed_joint() if model._frame is not None else None
        root = model
        identifier = rest
    if namespace == constants.ATTACHMENT_FRAME:
        model = root._attached_model(identifier)
        return model._frame if model is not None else None
    if namespace == constants.DEFAULT and identifier == "main":
        return root.default
    found = root._namescope.find(namespace, identifier)
    if found is None and namespace == constants.BODY and identifier == _WORLD:
        return root.worldbody
    if found is None and namespace in constants.ASSETS_NAMED_AFTER_FILE:
        found = _unnamed_asset_by_file(root, namespace, identifier)
    if found is None and namespace == _SUB_MODEL:
        found = _unnamed_sub_model(root, identifier)
    return found


def _frame_child(frame: Element, namespace: str, name: str) -> Element | None:
    for child in frame._children:
        if child._spec.namespace == namespace and child._attributes.get("name") == name:
            return child
    return None


def _unnamed_asset_by_file(root: RootElement, namespace: str, stem: str) -> Element | None:
    """MuJoCo names an unnamed file asset after its file name without extension."""
    section = root._singleton_if_present("asset")
    if section is None:
        return None
    for child in section._children:
        if child._spec.name != namespace or "name" in child._attributes:
            continue
        asset = child._attributes.get("file")
        if isinstance(asset, Asset) and asset.prefix == stem:
            return child
    return None


def _unnamed_sub_model(root: RootElement, name: str) -> Element | None:
    """MuJoCo names an unnamed `<asset><model file>` after the model in the file: its
    `<mujoco model>`, or MuJoCo's default model name where that is unset."""
    section = root._singleton_if_present("asset")
    if section is None:
        return None
    for child in section._children:
        if child._spec.name != _SUB_MODEL or "name" in child._attributes:
            continue
        asset = child._attributes.get("file")
        if isinstance(asset, Asset) and _sub_model_name(asset.contents) == name:
            return child
    return None


@functools.lru_cache(maxsize=64)
def _sub_model_name(contents: bytes) -> str:
    """The name MuJoCo gives the model of MJCF text `contents`."""
    return etree.fromstring(contents).get("model") or _default_model_name()


@functools.cache
def _default_model_name() -> str:
    return mujoco.MjSpec().modelname
