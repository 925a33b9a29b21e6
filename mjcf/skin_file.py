"""Scoping of MuJoCo skin files (.skn): their bones name bodies, which attaching prefixes."""

from __future__ import annotations

import functools
import struct

from mjcf.asset import Asset

_BODY_NAME_BYTES = 40


@functools.lru_cache(maxsize=64)
def scoped(asset: Asset, prefix: str) -> Asset:
    """A copy of skin file `asset` whose bone body names start with `prefix`."""
    if not prefix:
        return asset
    data = asset.contents
    try:
        nvert, ntexcoord, nface, nbone = struct.unpack_from("<4i", data, 0)
        offset = 16 + 4 * (3 * nvert + 2 * ntexcoord + 3 * nface)
        out = bytearray(data[:offset])
        for _ in range(nbone):
            raw = data[offset : offset + _BODY_NAME_BYTES]
            name = raw.split(b"\0", 1)[0].decode()
            new_name = (prefix + name).encode()
            if len(new_name) >= _BODY_NAME_BYTES:
                raise ValueError(
                    f"skin file {asset.prefix!r}: scoped bone body name {prefix + name!r} is "
                    f"longer than MuJoCo's {_BODY_NAME_BYTES - 1} characters"
                )
            out += new_name.ljust(_BODY_NAME_BYTES, b"\0")
            offset += _BODY_NAME_BYTES
            (vcount,) = struct.unpack_from("<i", data, offset + 28)
            end = offset + 32 + 8 * vcount
            out += data[offset:end]
            offset = end
    except struct.error:
        raise ValueError(
            f"skin file {asset.prefix!r} is truncated or not a MuJoCo .skn file"
        ) from None
    return Asset(bytes(out) + data[offset:], asset.extension, asset.prefix)
