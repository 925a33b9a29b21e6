"""What a MuJoCo render context copies from its model, to tell when a change of the model in
place leaves a context stale and how to refresh it.

`mjr_makeContext` (MuJoCo's render_context.c) reads the model once, when the context is
made, for:

- the `vis` struct (off-screen buffer size and multisampling, shadow map size, the slices
  of the builtin shapes, fog, haze, line width) and the model's `stat.extent` (fog and
  shadow ranges, the grid of infinite planes);
- the sizes of plane geoms (their grids) and the texture mapping of materials;
- the uploaded assets: meshes, height fields, textures and skins.

Everything else (colours, poses, lights, ...) is read at every frame. `RenderInputs.of`
copies those inputs, without a list of MuJoCo fields: the `vis` struct attribute by
attribute, the arrays of each family by their name prefix. `stale_assets` and
`context_is_stale` compare two copies: an asset family that MuJoCo uploads into a live
context (`mjr_upload<Family>`) is refreshed in place, any other difference needs a new
context.
"""

from __future__ import annotations

import functools
import operator
from collections.abc import Callable
from typing import NamedTuple

import mujoco
import numpy as np

from mujoco_physics.field_layout import MODEL_FIELDS

__all__ = ["RenderInputs", "held_by_context", "upload_asset_family"]

# Array families the context copies, by name prefix, with the function that uploads one
# object of the family into a live context (None: only a new context refreshes it). The
# number of objects of family "mesh_" is `model.nmesh`, and so on.
_FAMILIES: dict[str, Callable | None] = {
    "mesh_": mujoco.mjr_uploadMesh,
    "hfield_": mujoco.mjr_uploadHField,
    "tex_": mujoco.mjr_uploadTexture,
    "skin_": None,
    "mat_tex": None,
}
_PLANE = int(mujoco.mjtGeom.mjGEOM_PLANE)


def _family_arrays(prefix: str) -> tuple[str, ...]:
    return tuple(name for name in MODEL_FIELDS.arrays if name.startswith(prefix))


_FAMILY_ARRAYS = {prefix: _family_arrays(prefix) for prefix in _FAMILIES}


def held_by_context(name: str) -> bool:
    """Whether a render context copies MjModel array `name` when it is made (an asset
    family's arrays, materials' texture mapping, or `geom_size`, of which planes' grids)."""
    return name == "geom_size" or name.startswith(tuple(_FAMILIES))


def _field_paths(struct, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """The attribute paths of every value of MuJoCo struct `struct`, nested ones included."""
    paths = []
    for name in sorted(dir(struct)):
        if name.startswith("_"):
            continue
        value = getattr(struct, name)
        if isinstance(value, type):
            continue
        if isinstance(value, (np.ndarray, int, float)):
            paths.append(prefix + (name,))
        else:
            paths.extend(_field_paths(value, prefix + (name,)))
    return paths


@functools.cache
def _vis_fields() -> tuple[Callable, ...]:
    """Getters of every value of `MjModel.vis`, read once from a model's struct."""
    vis = mujoco.MjModel.from_xml_string("<mujoco/>").vis
    return tuple(operator.attrgetter(".".join(path)) for path in _field_paths(vis))


def _vis_bytes(vis) -> bytes:
    return b"".join(np.asarray(field(vis)).tobytes() for field in _vis_fields())


def _context_bytes(model: mujoco.MjModel) -> bytes:
    """The inputs only a new context refreshes, as bytes."""
    parts = [_vis_bytes(model.vis), np.float64(model.stat.extent).tobytes()]
    parts.append(model.geom_size[model.geom_type == _PLANE].tobytes())
    for prefix, upload in _FAMILIES.items():
        if upload is None:
            parts.extend(getattr(model, name).tobytes() for name in _FAMILY_ARRAYS[prefix])
    return b"".join(parts)


class RenderInputs(NamedTuple):
    """A copy of what a render context read from a model (see the module docstring)."""

    context: bytes
    # Per uploadable family prefix: copies of its arrays.
    assets: dict[str, tuple[np.ndarray, ...]]

    @classmethod
    def of(cls, model: mujoco.MjModel) -> RenderInputs:
        """The render inputs of `model` now."""
        assets = {
            prefix: tuple(getattr(model, name).copy() for name in _FAMILY_ARRAYS[prefix])
            for prefix, upload in _FAMILIES.items()
            if upload is not None
        }
        return cls(_context_bytes(model), assets)

    def context_is_stale(self, model: mujoco.MjModel) -> bool:
        """Whether `model` differs from these inputs in what only a new context refreshes."""
        return _context_bytes(model) != self.context

    def stale_assets(self, model: mujoco.MjModel) -> tuple[str, ...]:
        """The uploadable families (prefixes) whose arrays in `model` differ from these."""
        return tuple(
            prefix
            for prefix, copies in self.assets.items()
            if not all(
                np.array_equal(copy, getattr(model, name), equal_nan=copy.dtype.kind == "f")
                for copy, name in zip(copies, _FAMILY_ARRAYS[prefix])
            )
        )


def upload_asset_family(model: mujoco.MjModel, context: mujoco.MjrContext, prefix: str) -> None:
    """Uploads every object of family `prefix` ('mesh_', 'hfield_', 'tex_') of `model` into
    `context`, whose OpenGL context must be current.

    Raises:
      ValueError: for a family MuJoCo cannot upload into a live context.
    """
    upload = _FAMILIES.get(prefix)
    if upload is None:
        uploadable = sorted(p for p, u in _FAMILIES.items() if u is not None)
        raise ValueError(f"prefix {prefix!r}: expected one of the uploadable families {uploadable}")
    for index in range(getattr(model, "n" + prefix.rstrip("_"))):
        upload(model, context, index)
