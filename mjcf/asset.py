"""File assets held in memory: `mjcf.Asset`."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping

from mjcf import constants


class Asset:
    """Contents of a file asset (mesh, texture, height field, skin, ...).

    Args:
      contents: the file's bytes (a str is encoded as UTF-8).
      extension: the file extension including the dot, e.g. '.stl'; MuJoCo picks the
        decoder from it.
      prefix: a readable stem for the file name the asset gets in generated XML.
      dependencies: VFS filename -> contents of the files that this file names and MuJoCo
        reads with it (a sub-model's meshes, textures and nested sub-models); they reach
        the compile, and exports, next to it. The contents name them by these filenames,
        which hold digests of the files, so equal contents have equal dependencies.
    """

    __slots__ = ("contents", "extension", "prefix", "dependencies", "_vfs_filename")

    def __init__(
        self,
        contents: bytes | str,
        extension: str,
        prefix: str = "",
        *,
        dependencies: Mapping[str, bytes] | None = None,
    ):
        if isinstance(contents, str):
            contents = contents.encode("utf-8")
        self.contents = contents
        self.extension = extension.lower() if extension else ""
        self.prefix = prefix
        self.dependencies = dict(dependencies) if dependencies else {}
        self._vfs_filename = None

    def get_vfs_filename(self) -> str:
        """Name under which the asset is handed to MuJoCo: '<prefix>-<sha1 of contents><ext>'."""
        if self._vfs_filename is None:
            digest = hashlib.sha1(self.contents).hexdigest()
            stem = self.prefix.replace(constants.PREFIX_SEPARATOR, "-")
            # A file that already carries its digest (e.g. exported earlier) keeps its name.
            if stem == digest or stem.endswith("-" + digest):
                stem = stem[: -len(digest)].rstrip("-")
            budget = constants.MAX_VFS_FILENAME_LENGTH - len(digest) - len(self.extension) - 1
            stem = stem[: max(budget, 0)]
            name = f"{stem}-{digest}" if stem else digest
            self._vfs_filename = name + self.extension
        return self._vfs_filename

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, Asset)
            and self.contents == other.contents
            and self.extension == other.extension
        )

    def __hash__(self) -> int:
        return hash((self.contents, self.extension))

    def __repr__(self) -> str:
        return f"Asset(<{len(self.contents)} bytes>, {self.extension!r}, prefix={self.prefix!r})"
