"""The field writes that patch a primitive geom's `size`, with what the compiler derives from it.

`size_writes` gives, for geoms whose compiled `size` changed, the writes that make a
compiled model equal to a recompile's in every field a size feeds besides `geom_size`:
the geoms' bounding radius and box (`geom_rbound`, `geom_aabb`), their bodies' bounding
volume hierarchy (`bvh_*` over `body_bvhadr`/`body_bvhnum`) and, where a body's inertia
comes from its geoms, its mass, inertia and inertial frame (`body_mass`, `body_inertia`,
`body_ipos`, `body_iquat`). What follows from those (subtree masses, inverse weights, ...)
is left to `mj_setConst`, which the patch table requires after a size write, and the
model statistics to `mjcf.patching.model_statistics`.

The derived values are not computed here but by MuJoCo's compiler, on `BodyCopies` of
the changed bodies (`mjcf.patching.geom_body_copies`). A copy is trusted only while it
reproduces the compiled model: before its rows are used, the compiled model must hold the
sizes and rows of the copy's last kept compile, or the copy, compiled with the compiled
model's sizes, must give its rows bit for bit; a copy that does neither is built anew once,
and if the new one does not either, the patch declines. That the result equals a recompile
is proven by `mjcf/patching/patch_proof.py`, like every pair of the patch table.

Declined (None; the caller recompiles): geoms other than sphere, capsule, ellipsoid,
cylinder and box, in the changed geom's body too; geoms given by `fromto` (the compiled
size is not the attribute); a size from MuJoCo's built-in default; geoms with fluid
interaction (`fluidshape`); bodies whose geoms are not all children of the one MJCF
element (`<frame>`s, attached models); a body whose inertial frame stops or starts being
its own frame; models with a joint whose stiffness and damping come from `springdamper`
(converted with the inertia it moves); models with flexes; `settotalmass` and
`alignfree`, which make one body's inertia depend on the others or move its frame.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from mjcf import traversal_utils
from mjcf.element import Element
from mjcf.patching.geom_body_copies import (
    BodyCopies,
    CompiledBody,
    InertiaSettings,
    geom_sizes,
    is_true,
    row_slices,
)
from mjcf.patching.geom_size_cache import SizePatchCache, SpringdamperScan

__all__ = ["FieldWrite", "size_writes"]

_PRIMITIVES = frozenset(
    int(geom_type)
    for geom_type in (
        mujoco.mjtGeom.mjGEOM_SPHERE,
        mujoco.mjtGeom.mjGEOM_CAPSULE,
        mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        mujoco.mjtGeom.mjGEOM_CYLINDER,
        mujoco.mjtGeom.mjGEOM_BOX,
    )
)
_INERTIA_FROM_GEOM = {
    "auto": mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_AUTO,
    "true": mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE,
    "false": mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE,
}


class FieldWrite(NamedTuple):
    """One field write of a patch: `array[index] = value`."""

    array: np.ndarray
    index: int | slice
    value: np.ndarray


def size_writes(physics, geoms: list, cache: SizePatchCache) -> list[FieldWrite] | None:
    """The writes that give a recompile's fields after the `size` of `geoms` changed.

    Args:
      physics: an `mjcf.Physics` compiled from the model of `geoms` before the change.
      geoms: `<geom>` elements whose compiled `size` changed.
      cache: what earlier patches of `physics`'s compiled model looked up; filled in.

    Returns:
      The writes of `geom_size`, `geom_rbound`, `geom_aabb`, the affected bodies' BVH rows
      and, where a body's inertia comes from its geoms, its mass, inertia and inertial
      frame; `mj_setConst` must follow. None when some change is declined (see the module
      docstring).
    """
    model = physics.model.ptr
    settings = _inertia_settings(physics.mjcf_model)
    if settings is None or model.nflex or _springdamper_anywhere(physics.mjcf_model, cache):
        return None
    new_sizes = {}
    bodies = {}
    for geom in geoms:
        geom_id = cache.object_id(physics, geom)
        if traversal_utils.default_value_source(geom, "size") is None:
            return None  # MuJoCo's built-in default: nothing in the model says which
        size = _compiled_size(geom)
        if geom_id is None or size is None or model.geom_fluid[geom_id, 0] != 0:
            return None
        if traversal_utils.default_value_source(geom, "fromto") is not None:
            return None
        new_sizes[geom_id] = size
        body_id = int(model.geom_bodyid[geom_id])
        if body_id not in bodies:
            body = _compiled_body(physics, geom._parent, body_id, settings, cache)
            if body is None:
                return None
            bodies[body_id] = body
    derived = _derived_writes(physics, list(bodies.values()), new_sizes, settings, cache)
    if derived is None:
        return None
    writes = [FieldWrite(model.geom_size, geom_id, size) for geom_id, size in new_sizes.items()]
    return writes + derived


def _compiled_size(geom) -> np.ndarray | None:
    """The 3 numbers MuJoCo compiles from `geom`'s size: each one from the most specific of
    the geom and its default classes' templates that gives that many numbers, else 0; None
    for more than 3 numbers."""
    size = np.zeros(3)
    given = np.zeros(3, dtype=bool)
    sources = [geom] + [
        template
        for default in traversal_utils.default_classes(geom)
        if (template := default._singleton_if_present("geom")) is not None
    ]
    for source in sources:
        value = source._attributes.get("size")
        if value is None:
            continue
        value = np.atleast_1d(np.asarray(value, dtype=np.float64))
        if value.size > 3:
            return None
        free = ~given[: value.size]
        size[: value.size][free] = value[free]
        given[: value.size] = True
    return size


def _springdamper_anywhere(root, cache: SizePatchCache) -> bool:
    """Whether a joint of `root` takes its stiffness and damping from `springdamper`,
    which the compiler converts with the inertia the joint moves (its whole tree's, not
    only the bodies below it).

    The joints are looked at again only when `root` changed, since the last look, in more
    than attributes of geoms and geom defaults (a joint's attribute, or its structure),
    which patch after patch of sizes does not.
    """
    scan = cache.springdamper
    if scan is not None:
        changes = root.attribute_changes_since(scan.modification_count)
        if changes is not None and all(element.tag == "geom" for element, _ in changes):
            cache.springdamper = SpringdamperScan(root.modification_count, scan.found)
            return scan.found
    found = any(
        traversal_utils.default_value_source(joint, "springdamper") is not None
        for joint in root.find_all("joint")
    )
    cache.springdamper = SpringdamperScan(root.modification_count, found)
    return found


def _children(element, tag: str) -> list:
    """`element`'s children of `tag`; none where the tag is not allowed there."""
    if tag not in element._allowed_children():
        return []
    children = element.get_children(tag)
    if children is None:
        return []
    return [children] if isinstance(children, Element) else list(children)


def _inertia_settings(root) -> InertiaSettings | None:
    """`root`'s inertia settings, or None when it sets one that couples bodies."""
    attributes = root.compiler._attributes
    if attributes.get("settotalmass", -1) > 0 or is_true(attributes.get("alignfree")):
        return None
    spec_defaults = mujoco.MjSpec().compiler
    inertiafromgeom = _INERTIA_FROM_GEOM.get(str(attributes.get("inertiafromgeom", "auto")).lower())
    if inertiafromgeom is None:
        return None
    return InertiaSettings(
        inertiafromgeom=inertiafromgeom,
        inertiagrouprange=tuple(
            int(group)
            for group in attributes.get("inertiagrouprange", spec_defaults.inertiagrouprange)
        ),
        boundmass=float(attributes.get("boundmass", spec_defaults.boundmass)),
        boundinertia=float(attributes.get("boundinertia", spec_defaults.boundinertia)),
        balanceinertia=is_true(attributes.get("balanceinertia")),
    )


def _compiled_body(
    physics, element, body_id: int, settings: InertiaSettings, cache: SizePatchCache
) -> CompiledBody | None:
    """Body `body_id` as `element`'s geom children, or None when its compiled geoms are
    not exactly those, or one of them is not a primitive."""
    key = (element, settings)
    if key not in cache.bodies:
        cache.bodies[key] = _look_up_body(physics, element, body_id, settings, cache)
    return cache.bodies[key]


def _look_up_body(
    physics, element, body_id: int, settings: InertiaSettings, cache: SizePatchCache
) -> CompiledBody | None:
    model = physics.model.ptr
    geoms = element.get_children("geom")
    ids = [cache.object_id(physics, geom) for geom in geoms]
    first = int(model.body_geomadr[body_id])
    geom_ids = range(first, first + int(model.body_geomnum[body_id]))
    if ids != list(geom_ids):
        return None
    if any(int(model.geom_type[i]) not in _PRIMITIVES for i in ids):
        return None
    if (
        body_id == 0
        or settings.inertiafromgeom == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    ):
        from_geoms = False
    elif settings.inertiafromgeom == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE:
        from_geoms = True
    else:
        from_geoms = not _children(element, "inertial")
    return CompiledBody(body_id, list(geoms), geom_ids, from_geoms)


def _copies_key(bodies: list[CompiledBody], settings: InertiaSettings) -> tuple:
    """What identifies copies of `bodies`: their geoms, which body is the world, where
    inertias come from, and the settings."""
    return (
        tuple(
            (id(geom), body.body_id == 0, body.inertia_from_geoms)
            for body in bodies
            for geom in body.geoms
        ),
        settings,
    )


def _trusted_copies(
    model, bodies: list[CompiledBody], settings: InertiaSettings, cache: SizePatchCache, key
) -> BodyCopies | None:
    """The copies of `bodies` cached under `key`, or new ones, once they reproduce `model`
    (see the module docstring); None, forgetting them, when new ones do not."""
    copies = cache.copies.get(key)
    if copies is None or not copies.built_from(model, bodies):
        copies = cache.copies[key] = BodyCopies(model, bodies, settings)
    if copies.model_holds_last_compile(model, bodies) or copies.reproduces(model, bodies):
        return copies
    # What changed since may be an MJCF value the copy took (a density): build it anew.
    copies = cache.copies[key] = BodyCopies(model, bodies, settings)
    if copies.reproduces(model, bodies):
        return copies
    del cache.copies[key]
    return None


def _derived_writes(
    physics,
    bodies: list[CompiledBody],
    new_sizes: dict[int, np.ndarray],
    settings: InertiaSettings,
    cache: SizePatchCache,
) -> list[FieldWrite] | None:
    """The writes of the bodies' derived rows with `new_sizes` (geom id -> size), or None
    when their copies are not trusted or the change is declined."""
    model = physics.model.ptr
    key = _copies_key(bodies, settings)
    copies = _trusted_copies(model, bodies, settings, cache, key)
    if copies is None:
        return None
    sizes = geom_sizes(model, bodies)
    for row, geom_id in enumerate(i for body in bodies for i in body.geom_ids):
        if geom_id in new_sizes:
            sizes[row] = new_sizes[geom_id]
    old_rows, new_rows = copies.last_rows, copies.compile(bodies, sizes)
    if new_rows is None:
        del cache.copies[key]
        return None
    writes = []
    for body, before, after in zip(bodies, old_rows, new_rows):
        # A body whose inertial frame stops (or starts) being its own frame is compiled as
        # simple or not accordingly; mj_setConst does not revisit that.
        if before["body_sameframe"] != after["body_sameframe"]:
            del cache.copies[key]
            return None
        writes += [
            FieldWrite(getattr(model, name), rows, after[name])
            for name, rows in row_slices(model, body).items()
        ]
    copies.last_rows = new_rows
    return writes
