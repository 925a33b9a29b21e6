"""Scoping of MuJoCo skin files (.skn): their bones name bodies, which attaching prefixes."""

from __future__ import annotations

import functools

from mjcf import skin
from mjcf.asset import Asset


@functools.lru_cache(maxsize=64)
def scoped(asset: Asset, prefix: str) -> Asset:
    """A copy of skin file `asset` whose bone body names start with `prefix`."""
    if not prefix:
        return asset
    try:
        parsed = skin.parse(asset.contents, body_getter=str)
        contents = skin.pack(parsed, lambda bone: prefix + bone.body())
    except ValueError as error:
        raise ValueError(f"skin file {asset.prefix!r}: {error}") from None
    return Asset(contents, asset.extension, asset.prefix)
