"""Reads the files a model names as MuJoCo finds them, and a sub-model with the files it names.

MuJoCo reads a mesh, skin, height field or flexcomp file from the compiler's `meshdir`, a
texture from its `texturedir` (each falling back to `assetdir`), and a sub-model
(`<asset><model file=...>`) from the model's own directory. A sub-model is an MJCF file of
its own: MuJoCo reads the files *it* names from *its* directory, through *its* compiler's
directories. Handed to MuJoCo as one file of a virtual file system (VFS), it would lose
that directory, so its text is rewritten to name each of its files by VFS filename (its
`<include>`s expanded, its directories dropped), and the files travel with it as the
asset's `dependencies`, which `get_assets` hands to MuJoCo and exports write out.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import NamedTuple

from lxml import etree

from mjcf import attribute_types, constants, parser, schema
from mjcf.asset import Asset

# Which compiler attribute names the directory of each file-bearing element's files (with
# `assetdir` where it is unset). Other files (sub-models) are read from the model's own
# directory, as MuJoCo reads them.
_ASSET_DIRECTORY = {
    "mesh": "meshdir",
    "skin": "meshdir",
    "hfield": "meshdir",
    "flexcomp": "meshdir",
    "texture": "texturedir",
}
_SUB_MODEL = "model"
_FILE = "file"


def load(
    tag: str,
    path: str,
    *,
    where: str,
    compiler: Mapping[str, object],
    model_dir: str,
    assets: Mapping[str, bytes],
) -> Asset:
    """Reads file `path` named by a `<tag>` element, as MuJoCo reads it.

    Args:
      tag: the element's tag ('mesh', 'texture', 'model', ...).
      path: the file name as the element gives it.
      where: the element and attribute, to begin error messages with.
      compiler: the model's compiler attributes (`meshdir`, `texturedir`, `assetdir`).
      model_dir: the model's directory, which relative paths resolve against.
      assets: filename -> contents, named relative to `model_dir`; looked up before the disk.

    Returns:
      The file as an Asset named after `path`. A sub-model's text names its files by VFS
      filename, and its `dependencies` hold them (those of nested sub-models too).

    Raises:
      FileNotFoundError: the file, or one that a sub-model names, is neither in `assets`
        nor on the disk; the message names it and every element on the way to it.
      MJCFSyntaxError: a sub-model, or a file it includes, is not well-formed XML.
      ValueError: a sub-model's root element is not `<mujoco>`, or a sub-model names
        itself, directly or through its sub-models.
    """
    return _load(tag, path, where, compiler, model_dir, assets, ())


def _load(tag, path, where, compiler, model_dir, assets, within: tuple[str, ...]) -> Asset:
    """`load`, inside the sub-models whose absolute paths are `within`."""
    key = _ASSET_DIRECTORY.get(tag)
    directory = (compiler.get(key) or compiler.get("assetdir") or "") if key else ""
    contents, name = _read(path, directory, where, model_dir, assets)
    stem, extension = os.path.splitext(os.path.basename(path))
    if tag == _SUB_MODEL:
        return _sub_model(contents, name, stem, where, model_dir, assets, within)
    return Asset(contents, extension, stem)


def _read(path, directory, where, model_dir, assets) -> tuple[bytes, str]:
    """The contents of file `path` in `directory`, and its name relative to `model_dir`."""
    joined = os.path.normpath(os.path.join(directory, path)) if directory else path
    for key in (path, joined):
        if key in assets:
            contents = assets[key]
            return (contents.encode("utf-8") if isinstance(contents, str) else contents), key
    full_path = os.path.join(model_dir, joined)
    try:
        with open(full_path, "rb") as handle:
            return handle.read(), joined
    except OSError as error:
        raise FileNotFoundError(
            f"{where}: cannot read file {path!r} (looked for {full_path!r}: {error.strerror})"
        ) from None


def _sub_model(contents: bytes, name: str, stem: str, where, model_dir, assets, within) -> Asset:
    """Sub-model `contents`, found at `name` relative to `model_dir`, as a self-contained
    Asset: its files named by VFS filename and carried as its dependencies."""
    identity = os.path.abspath(os.path.join(model_dir, name))
    if identity in within:
        # MuJoCo itself recurses until its stack overflows.
        raise ValueError(f"{where}: {name!r} is a sub-model of itself")
    within += (identity,)
    where = f"{where}: in sub-model {name!r}"
    directory = os.path.dirname(name)
    own_dir = os.path.join(model_dir, directory)
    own_assets = _relative_to(assets, directory)
    document = parser.read_document(contents, own_dir, own_assets, where)
    compilers = document.findall("compiler")
    compiler = {}
    for node in compilers:
        compiler.update(node.attrib)
    dependencies = {}
    files = _Files(compiler, own_dir, own_assets, within, dependencies)
    _read_files(document, schema.root_spec(), where, files)
    for node in compilers:
        for attribute in constants.ASSET_DIRECTORY_ATTRIBUTES:
            node.attrib.pop(attribute, None)
    return Asset(etree.tostring(document), ".xml", stem, dependencies=dependencies)


class _Files(NamedTuple):
    """What the files a sub-model names are read with, and where they are gathered."""

    compiler: Mapping[str, str]  # the sub-model's compiler attributes
    model_dir: str  # the sub-model's directory
    assets: Mapping[str, bytes]  # in-memory files, named relative to `model_dir`
    within: tuple[str, ...]  # absolute paths of the sub-models being read, outermost first
    dependencies: dict[str, bytes]  # VFS filename -> contents, filled in


def _read_files(node, spec, where: str, files: _Files) -> None:
    """Reads the files named below `node` (of schema `spec`) into `files.dependencies`, and
    names them in the text by VFS filename."""
    for attribute, value in node.items():
        attribute_spec = spec.attributes.get(attribute)
        if attribute_spec is None or attribute_spec.type.kind != attribute_types.FILE:
            continue  # an unknown attribute is left for MuJoCo to report
        asset = _load(
            node.tag,
            value,
            f"{where}: {_describe(node)} attribute {attribute!r}",
            files.compiler,
            files.model_dir,
            files.assets,
            files.within,
        )
        filename = asset.get_vfs_filename()
        if attribute == _FILE and node.tag in constants.ASSETS_NAMED_AFTER_FILE:
            if not node.get(constants.NAME):
                # MuJoCo names such an asset after its file, which is being renamed.
                node.set(constants.NAME, asset.prefix)
        node.set(attribute, filename)
        files.dependencies[filename] = asset.contents
        files.dependencies.update(asset.dependencies)
    for child in node:
        child_spec = spec.children.get(child.tag)
        if child_spec is not None and child_spec.holds_files:
            _read_files(child, child_spec, where, files)


def _relative_to(assets: Mapping[str, bytes], directory: str) -> Mapping[str, bytes]:
    """`assets`, their relative names made relative to `directory` (itself relative to the
    directory they are named against); absolute names stay, and relative ones cannot be
    placed against an absolute `directory`."""
    if not directory:
        return assets
    if os.path.isabs(directory):
        return {key: value for key, value in assets.items() if os.path.isabs(key)}
    return {
        key if os.path.isabs(key) else os.path.relpath(key, directory): value
        for key, value in assets.items()
    }


def _describe(node) -> str:
    name = node.get(constants.NAME)
    return f"<{node.tag} name={name!r}>" if name else f"<{node.tag}>"
