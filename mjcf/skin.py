"""Reading and writing MuJoCo skin files (.skn), whose bones are tied to bodies by name.

The format (MuJoCo's XML reference, `<skin file>`): four int32 counts (vertices, texture
coordinates, faces, bones); float32 vertex positions, float32 texture coordinates, int32
vertex indices of the faces; then per bone a 40-byte NUL-padded body name, float32 bind
position (3) and quaternion (4), an int32 vertex count, int32 vertex ids and float32 weights.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

#: Bytes a bone's body name occupies in the file, NUL padding included.
MAX_BODY_NAME_LENGTH = 40


class Bone(NamedTuple):
    """One bone: `body()` returns the body it follows (looked up when called)."""

    body: Callable
    bindpos: np.ndarray
    bindquat: np.ndarray
    vertex_ids: np.ndarray
    vertex_weights: np.ndarray


class Skin(NamedTuple):
    """The contents of a skin file: (n, 3) vertices, (n, 2) texcoords, (n, 3) faces."""

    vertices: np.ndarray
    texcoords: np.ndarray
    faces: np.ndarray
    bones: list[Bone]


class _Reader:
    __slots__ = ("data", "offset")

    def __init__(self, data: bytes):
        self.data = data
        self.offset = 0

    def take(self, size: int) -> bytes:
        end = self.offset + size
        if end > len(self.data):
            raise ValueError(
                f"skin file is truncated: needs {end} bytes, has {len(self.data)} (not a "
                "MuJoCo .skn file?)"
            )
        chunk = self.data[self.offset : end]
        self.offset = end
        return chunk

    def array(self, dtype: str, count: int) -> np.ndarray:
        return np.frombuffer(self.take(4 * count), dtype=dtype)


def parse(contents: bytes, body_getter: Callable[[str], object]) -> Skin:
    """Reads a skin file; each bone's `body()` calls `body_getter(body name in the file)`.

    Raises:
      ValueError: the contents are shorter than their counts say.
    """
    reader = _Reader(bytes(contents))
    nvertex, ntexcoord, nface, nbone = struct.unpack("<4i", reader.take(16))
    vertices = reader.array("<f4", 3 * nvertex).reshape(-1, 3)
    texcoords = reader.array("<f4", 2 * ntexcoord).reshape(-1, 2)
    faces = reader.array("<i4", 3 * nface).reshape(-1, 3)
    bones = []
    for _ in range(nbone):
        name = reader.take(MAX_BODY_NAME_LENGTH).split(b"\0", 1)[0].decode()
        bindpos = reader.array("<f4", 3).astype(float)
        bindquat = reader.array("<f4", 4).astype(float)
        (count,) = struct.unpack("<i", reader.take(4))
        bones.append(
            Bone(
                body=lambda name=name: body_getter(name),
                bindpos=bindpos,
                bindquat=bindquat,
                vertex_ids=reader.array("<i4", count),
                vertex_weights=reader.array("<f4", count),
            )
        )
    return Skin(vertices, texcoords, faces, bones)


def serialize(skin: Skin) -> bytes:
    """The skin file for `skin`; bones name their bodies by `bone.body().full_identifier`.

    Raises:
      ValueError: a body name does not fit the format, or a bone has different numbers
        of vertex ids and weights.
    """
    return pack(skin, lambda bone: bone.body().full_identifier)


def pack(skin: Skin, body_name: Callable[[Bone], str]) -> bytes:
    """The skin file for `skin`, naming each bone's body `body_name(bone)`."""
    counts = (len(skin.vertices), len(skin.texcoords), len(skin.faces), len(skin.bones))
    parts = [
        struct.pack("<4i", *counts),
        np.asarray(skin.vertices, "<f4").tobytes(),
        np.asarray(skin.texcoords, "<f4").tobytes(),
        np.asarray(skin.faces, "<i4").tobytes(),
    ]
    for bone in skin.bones:
        name = body_name(bone).encode()
        if len(name) >= MAX_BODY_NAME_LENGTH:
            raise ValueError(
                f"skin bone body name {name.decode()!r} is longer than the "
                f"{MAX_BODY_NAME_LENGTH - 1} characters a skin file can hold"
            )
        if len(bone.vertex_ids) != len(bone.vertex_weights):
            raise ValueError(
                f"skin bone of body {name.decode()!r}: {len(bone.vertex_ids)} vertex ids "
                f"but {len(bone.vertex_weights)} weights"
            )
        parts += [
            name.ljust(MAX_BODY_NAME_LENGTH, b"\0"),
            np.asarray(bone.bindpos, "<f4").tobytes(),
            np.asarray(bone.bindquat, "<f4").tobytes(),
            struct.pack("<i", len(bone.vertex_ids)),
            np.asarray(bone.vertex_ids, "<i4").tobytes(),
            np.asarray(bone.vertex_weights, "<f4").tobytes(),
        ]
    return b"".join(parts)
