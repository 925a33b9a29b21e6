"""Builds the object model from MJCF XML: strings, files and paths, with `<include>`."""

from __future__ import annotations

import math
import os
import re
import zipfile

import numpy as np
from lxml import etree

from mjcf import attribute_types, constants
from mjcf.element import Element, RootElement, _close_matches
from mjcf.scoped_lookup import lookup

_INCLUDE = "include"
_ESCAPED_SEP = constants.PREFIX_SEPARATOR_ESCAPE + constants.PREFIX_SEPARATOR
# MuJoCo reads XML ints as 32-bit decimal integers and floats as C's strtod does: decimal,
# hexadecimal ('0x1p3') or inf/infinity/nan, in any case; a finite number too large for a
# double is an error.
_XML_INT = re.compile(r"[+-]?[0-9]+\Z")
_XML_HEX_FLOAT = re.compile(r"[+-]?0[xX]")
_XML_NON_FINITE = re.compile(r"[+-]?(inf|infinity|nan)\Z", re.IGNORECASE)
_INT32 = 2**31
# How deep MuJoCo's XML reader (tinyxml2) lets elements nest, `<mujoco>` being level 1: a
# childless element may sit one level deeper than any element with children. (An empty
# element written with a closing tag counts as having children there; lxml cannot tell.)
_MAX_DEPTH = 499
# References whose empty value MuJoCo reads as a (missing) default class, not as unset.
_CLASS_REFERENCES = ("class", "childclass")


class MJCFSyntaxError(etree.XMLSyntaxError, ValueError):
    """Malformed XML: a `ValueError`, and lxml's `XMLSyntaxError`, which dm_control raises."""

    @classmethod
    def wrapping(cls, error: etree.XMLSyntaxError, context: str) -> MJCFSyntaxError:
        """The same error, its message prefixed with `context`."""
        return cls(
            f"{context}: {error.msg}", error.code, error.lineno, error.offset, error.filename
        )


def from_xml_string(
    xml_string: str | bytes,
    escape_separators: bool = False,
    model_dir: str = "",
    resolve_references: bool = True,
    assets: dict | None = None,
) -> RootElement:
    """Parses MJCF text into a RootElement.

    Args:
      xml_string: the MJCF document.
      escape_separators: accept identifiers containing '/' by escaping it as '\\/'.
      model_dir: directory that `<include>` files and file assets are resolved against.
      resolve_references: turn references written as identifiers into the elements they
        name (references to missing elements stay strings and fail when written out).
      assets: filename -> bytes, looked up before the disk for includes and file assets.
    """
    if isinstance(xml_string, str):
        xml_string = xml_string.encode("utf-8")
    try:
        document = _parse_xml(xml_string)
    except etree.XMLSyntaxError as error:
        raise MJCFSyntaxError.wrapping(error, "invalid MJCF XML") from None
    return _build(document, escape_separators, model_dir, resolve_references, assets)


def from_file(
    file_handle,
    escape_separators: bool = False,
    model_dir: str = "",
    resolve_references: bool = True,
    assets: dict | None = None,
) -> RootElement:
    """Parses MJCF from an open file object, or a file name (see `from_xml_string` for the
    arguments)."""
    if isinstance(file_handle, (str, os.PathLike)):
        with open(file_handle, "rb") as handle:
            text = handle.read()
    else:
        text = file_handle.read()
    return from_xml_string(text, escape_separators, model_dir, resolve_references, assets)


def from_path(
    path: str,
    escape_separators: bool = False,
    resolve_references: bool = True,
    assets: dict | None = None,
) -> RootElement:
    """Parses the MJCF file at `path`; relative includes and assets resolve next to it."""
    with open(path, "rb") as handle:
        text = handle.read()
    return from_xml_string(
        text, escape_separators, os.path.dirname(path), resolve_references, assets
    )


def from_zip(
    path,
    model_file: str = "model.xml",
    escape_separators: bool = False,
    resolve_references: bool = True,
) -> RootElement:
    """Parses a model stored in a zip archive together with its assets.

    The model is the archive's only `.xml` file, or the one named `model_file` when there
    are several; the other files are its assets, named relative to the model's directory
    (as `export_with_assets_as_zip` writes them).

    Raises:
      ValueError: `path` is not a zip archive, holds no XML file, or holds several and
        none named `model_file`.
    """
    if not zipfile.is_zipfile(path):
        raise ValueError(f"from_zip: {path!r} is not a zip archive")
    with zipfile.ZipFile(path) as archive:
        names = [n for n in archive.namelist() if not n.endswith("/")]
        xml_files = [n for n in names if n.endswith(".xml")]
        if not xml_files:
            raise ValueError(f"from_zip: {path!r} holds no .xml file")
        if len(xml_files) == 1:
            model_path = xml_files[0]
        elif model_file in xml_files:
            model_path = model_file
        else:
            raise ValueError(
                f"from_zip: {path!r} holds several .xml files ({', '.join(xml_files)}) and "
                f"none is named {model_file!r}"
            )
        model_dir = os.path.dirname(model_path)
        text = archive.read(model_path)
        assets = {
            os.path.relpath(name, model_dir): archive.read(name)
            for name in names
            if name != model_path
        }
    return from_xml_string(
        text, escape_separators, resolve_references=resolve_references, assets=assets
    )


def read_document(text: bytes, model_dir: str, assets: dict | None, context: str) -> etree._Element:
    """The `<mujoco>` root of MJCF document `text`, its `<include>`s expanded.

    Args:
      text: the document.
      model_dir: directory that `<include>` files are resolved against.
      assets: filename -> bytes, looked up before the disk for includes.
      context: what the document is, to begin error messages with.

    Returns:
      The lxml element of `<mujoco>`, comments and blank text removed.

    Raises:
      MJCFSyntaxError: the document, or a file it includes, is not well-formed XML.
      ValueError: the root element is not `<mujoco>`.
    """
    try:
        document = _parse_xml(text)
    except etree.XMLSyntaxError as error:
        raise MJCFSyntaxError.wrapping(error, f"{context}: invalid MJCF XML") from None
    if document.tag != constants.MUJOCO:
        raise ValueError(f"{context}: the root element must be <mujoco>, got <{document.tag}>")
    _expand_includes(document, model_dir, assets, ())
    return document


def _read_include(file_name: str, model_dir: str, assets: dict | None):
    if assets and file_name in assets:
        text = assets[file_name]
    else:
        path = file_name if os.path.isabs(file_name) else os.path.join(model_dir, file_name)
        try:
            with open(path, "rb") as handle:
                text = handle.read()
        except OSError as error:
            raise FileNotFoundError(
                f"<include file={file_name!r}>: cannot read {path!r} ({error.strerror})"
            ) from None
    if isinstance(text, str):
        text = text.encode("utf-8")
    try:
        return _parse_xml(text)
    except etree.XMLSyntaxError as error:
        raise MJCFSyntaxError.wrapping(
            error, f"<include file={file_name!r}>: invalid XML"
        ) from None


def _parse_xml(text: bytes):
    """The document's root; raises XMLSyntaxError, also when it nests deeper than MuJoCo reads.

    lxml's own limit (256 levels) is below MuJoCo's, so it is lifted (`huge_tree`) and
    MuJoCo's applied instead; libxml2 still stops at 2048 levels, before Python recursion
    could.
    """
    parser = etree.XMLParser(remove_comments=True, remove_blank_text=True, huge_tree=True)
    document = etree.fromstring(text, parser)
    deepest = max(
        (node for node in document.iter() if len(node) == 0),
        key=lambda node: sum(1 for _ in node.iterancestors()),
    )
    depth = sum(1 for _ in deepest.iterancestors()) + 1
    if depth > _MAX_DEPTH:
        raise etree.XMLSyntaxError(
            f"elements nest {depth} levels deep; MuJoCo reads at most {_MAX_DEPTH}", None, 0, 0
        )
    return document


def _expand_includes(node, model_dir: str, assets, seen: tuple) -> None:
    """Replaces every `<include>` below `node` by the children of the included file's root."""
    for include in list(node.iter(_INCLUDE)):
        file_name = include.get("file")
        if file_name is None:
            raise ValueError("<include> needs a 'file' attribute")
        if file_name in seen:
            raise ValueError(f"<include file={file_name!r}> includes itself")
        included = _read_include(file_name, model_dir, assets)
        _expand_includes(included, model_dir, assets, seen + (file_name,))
        parent = include.getparent()
        position = parent.index(include)
        parent.remove(include)
        for offset, child in enumerate(list(included)):
            parent.insert(position + offset, child)


def _build(document, escape_separators, model_dir, resolve_references, assets) -> RootElement:
    if document.tag != constants.MUJOCO:
        raise ValueError(
            f"the root element of an MJCF model must be <mujoco>, got <{document.tag}>"
        )
    _expand_includes(document, model_dir, assets, ())
    root = RootElement(model_dir=model_dir, assets=assets)
    model_name = document.get("model")
    for name in document.keys():
        if name != "model":
            raise ValueError(f"<mujoco> has no attribute {name!r}")
    # Compiler settings decide where file assets live, so they are read first.
    sections = sorted(document, key=lambda child: child.tag != "compiler")
    for child in sections:
        _add_element(root, child, escape_separators)
    if model_name:  # MuJoCo reads an empty model name as unset
        root.model = model_name
    if resolve_references:
        resolve_reference_strings(root)
    root._start_counting()
    return root


def _add_element(parent: Element, node, escape_separators: bool) -> None:
    tag = node.tag
    if not isinstance(tag, str):
        return
    allowed = parent._allowed_children()
    spec = allowed.get(tag)
    if spec is None:
        raise ValueError(
            f"{parent._describe()} cannot have a child <{tag}>{_close_matches(tag, allowed)}"
        )
    if tag == constants.DEFAULT and parent is parent._root and "class" in node.attrib:
        if node.get("class") not in ("", "main"):
            raise ValueError(
                f"the top-level <default> is class 'main' and cannot be renamed, got "
                f"class={node.get('class')!r}"
            )
        del node.attrib["class"]  # '' and 'main' both name the top-level class
    if spec.repeated:
        element = Element._create(spec, None, parent._root)
        _set_attributes(element, node, escape_separators)
        element._parent = parent
        entry = element._identifier_entry()
        if entry is not None:
            element._root._namescope.add(entry[0], entry[1], element)
        parent._children.append(element)
    else:
        element = parent._singleton(spec)
        _set_attributes(element, node, escape_separators)
        entry = element._identifier_entry()
        if entry is not None:
            element._root._namescope.add(entry[0], entry[1], element)
    single = set()
    for child in node:
        child_spec = element._allowed_children().get(child.tag)
        if child_spec is not None and not child_spec.repeated and element is not element._root:
            if child.tag in single:
                raise ValueError(f"{element._describe()} may hold only one <{child.tag}>")
            single.add(child.tag)
        _add_element(element, child, escape_separators)


def _set_attributes(element: Element, node, escape_separators: bool) -> None:
    attributes = element._spec.attributes
    for name, value in node.items():
        spec = attributes.get(name)
        if spec is None:
            raise ValueError(
                f"{element._describe()} has no attribute {name!r}{_close_matches(name, attributes)}"
            )
        value_type = spec.type
        kind = value_type.kind
        if not value and (name == "name" or kind == attribute_types.REFERENCE):
            if name not in _CLASS_REFERENCES:
                continue  # MuJoCo reads an empty name or reference as unset
        if escape_separators and kind in (attribute_types.IDENTIFIER, attribute_types.REFERENCE):
            value = value.replace(constants.PREFIX_SEPARATOR, _ESCAPED_SEP)
        if kind == attribute_types.IDENTIFIER:
            element._attributes[name] = _checked_identifier(element, name, value)
        elif isinstance(value_type, attribute_types.Keyword) and value not in value_type.values:
            # The Python API matches keywords without regard to case; MuJoCo's XML does not.
            raise ValueError(
                f"{element._describe()} attribute {name!r}: expected {value_type.description}, "
                f"got {value!r}"
            )
        elif isinstance(value_type, (attribute_types.Number, attribute_types.Array)):
            integral = value_type.dtype in (int, np.int64)
            numbers = _xml_numbers(element, name, value, integral)
            if numbers:  # MuJoCo reads a blank number as unset
                element._set_attribute(spec.python_name, numbers)
        else:
            element._set_attribute(spec.python_name, value)


def _xml_numbers(element: Element, name: str, text: str, integral: bool) -> list:
    """The numbers in an attribute's text, read as MuJoCo reads them."""
    numbers = []
    for token in text.split():
        if integral:
            number = int(token) if _XML_INT.match(token) else None
            if number is not None and not -_INT32 <= number < _INT32:
                raise ValueError(
                    f"{element._describe()} attribute {name!r}: {token!r} is too large "
                    "for a 32-bit int"
                )
        else:
            number = _xml_float(token)
            if number is not None and math.isinf(number) and not _XML_NON_FINITE.match(token):
                raise ValueError(
                    f"{element._describe()} attribute {name!r}: {token!r} is too large for a double"
                )
        if number is None:
            kind = "an int" if integral else "a float"
            raise ValueError(
                f"{element._describe()} attribute {name!r}: expected {kind}, got {token!r}"
            )
        numbers.append(number)
    return numbers


def _xml_float(token: str) -> float | None:
    if "_" in token:
        return None  # Python's float() accepts digit separators; strtod does not
    try:
        if _XML_HEX_FLOAT.match(token):
            return float.fromhex(token)
        return float(token)
    except ValueError:
        return None


def _checked_identifier(element: Element, name: str, value: str) -> str:
    if not value:
        raise ValueError(f"{element._describe()} attribute {name!r}: must not be empty")
    if constants.PREFIX_SEPARATOR in value.replace(_ESCAPED_SEP, ""):
        raise ValueError(
            f"<{element._spec.name}> attribute {name!r}: {value!r} contains "
            f"{constants.PREFIX_SEPARATOR!r}, which separates model scopes (parse with "
            "escape_separators=True to keep such names)"
        )
    return value


def resolve_reference_strings(root: RootElement) -> None:
    """Replaces identifier strings in reference attributes by the elements they name."""
    for element in root._iter_own_tree():
        attributes = element._spec.attributes
        for name, value in list(element._attributes.items()):
            if not isinstance(value, str):
                continue
            value_type = attributes[name].type
            if value_type.kind != attribute_types.REFERENCE:
                continue
            namespace = value_type.target_namespace(element._attributes)
            if namespace is None:
                continue
            target = lookup(root, namespace, value)
            if target is not None:
                element._attributes[name] = target
                element._xml_cache = None
