"""The field writes that patch a primitive geom's `size`, with what the compiler derives from it.

Besides `geom_size`, a geom's size feeds its bounding radius and box (`geom_rbound`,
`geom_aabb`), its body's bounding volume hierarchy (`bvh_*` over the body's
`body_bvhadr`/`body_bvhnum` rows) and, when the body's inertia comes from its geoms, the
body's mass, inertia and inertial frame (`body_mass`, `body_inertia`, `body_ipos`,
`body_iquat`). Nothing of that is computed here: MuJoCo's compiler computes it, on a model
of one body holding copies of the body's geoms (their compiled type, size, frame, group,
contact bits and margin, their MJCF mass, density and `shellinertia`) under the same
`<compiler>` inertia settings. That model is compiled twice: with the sizes the compiled
model holds, where it must reproduce the compiled model's values bit for bit (otherwise
some input is not what the compiler saw, and the patch declines), and with the new sizes,
which gives the values to write. What follows from those (subtree masses, inverse weights,
`stat`, ...) is left to `mj_setConst`, which the patch table requires after a size write.
That the result equals a recompile is proven by `tools/patch_proof.py`, like every pair of
the table.

Declined (the caller recompiles): geoms other than sphere, capsule, ellipsoid, cylinder and
box, in the changed geom's body too; geoms given by `fromto` (the compiled size is not the
attribute); geoms with fluid interaction (`fluidshape`); bodies whose geoms are not all
children of the one MJCF element (`<frame>`s, attached models); models with a joint
whose stiffness and damping come from `springdamper` (converted with the inertia it
moves); models with flexes; `settotalmass` and `alignfree`, which make one body's inertia
depend on the others or move its frame. The statistics (`stat`) that sizes move are
`mjcf.model_statistics`'s.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from mjcf import traversal_utils
from mjcf.element import Element

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

# Per-geom fields of the one-body model that the compiled model's rows must match.
_GEOM_FIELDS = ("geom_rbound", "geom_aabb")
# Per-body fields the compiler computes from the geoms when the inertia comes from them.
_INERTIA_FIELDS = ("body_mass", "body_inertia", "body_ipos", "body_iquat")
# Per-node fields of the body's bounding volume hierarchy (`bvh_nodeid` is a geom id).
_BVH_FIELDS = ("bvh_aabb", "bvh_child", "bvh_depth", "bvh_nodeid")


class FieldWrite(NamedTuple):
    """One field write of a patch: `array[index] = value`."""

    array: np.ndarray
    index: int | slice
    value: np.ndarray


class _Body(NamedTuple):
    """A compiled body and its geoms, the `<geom>` children of one MJCF element."""

    body_id: int
    geoms: list
    inertia_from_geoms: bool


def size_writes(physics, geoms: list) -> list[FieldWrite] | None:
    """The writes that give a recompile's fields after the `size` of `geoms` changed.

    Args:
      physics: an `mjcf.Physics` compiled from the model of `geoms` before the change.
      geoms: `<geom>` elements whose compiled `size` changed.

    Returns:
      The writes of `geom_size`, `geom_rbound`, `geom_aabb`, the affected bodies' BVH rows
      and, where a body's inertia comes from its geoms, its mass, inertia and inertial
      frame; `mj_setConst` must follow. None when some change is declined (see the module
      docstring).
    """
    model = physics.model.ptr
    settings = _compiler_settings(physics._mjcf_model)
    if settings is None or model.nflex or _springdamper_anywhere(physics._mjcf_model):
        return None
    new_sizes = {}
    bodies = {}
    for geom in geoms:
        geom_id = _geom_id(physics, geom)
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
            body = _body(physics, geom._parent, body_id, settings)
            if body is None:
                return None
            bodies[body_id] = body
    writes = [FieldWrite(model.geom_size, geom_id, size) for geom_id, size in new_sizes.items()]
    for body in bodies.values():
        body_writes = _body_writes(model, body, new_sizes, settings)
        if body_writes is None:
            return None
        writes.extend(body_writes)
    return writes


def _geom_id(physics, geom) -> int | None:
    try:
        return physics.bind(geom).element_id
    except ValueError:
        return None


def _compiled_size(geom) -> np.ndarray | None:
    """The 3 numbers MuJoCo compiles from `geom`'s size: each one from the most specific of
    the geom and its default classes' templates that gives that many numbers, else 0."""
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


class _Settings(NamedTuple):
    """The `<compiler>` settings that the one-body model copies."""

    inertiafromgeom: mujoco.mjtInertiaFromGeom
    inertiagrouprange: np.ndarray
    boundmass: float
    boundinertia: float
    balanceinertia: bool


def _springdamper_anywhere(root) -> bool:
    """Whether a joint of `root` takes its stiffness and damping from `springdamper`, which
    the compiler converts with the inertia the joint moves (its whole tree's, not only the
    bodies below it)."""
    return any(
        traversal_utils.default_value_source(joint, "springdamper") is not None
        for joint in root.find_all("joint")
    )


def _children(element, tag: str) -> list:
    """`element`'s children of `tag`; none where the tag is not allowed there."""
    if tag not in element._allowed_children():
        return []
    children = element.get_children(tag)
    if children is None:
        return []
    return [children] if isinstance(children, Element) else list(children)


def _compiler_settings(root) -> _Settings | None:
    """`root`'s inertia settings, or None when it sets one that couples bodies."""
    compiler = root.compiler
    attributes = compiler._attributes
    if attributes.get("settotalmass", -1) > 0 or _true(attributes.get("alignfree")):
        return None
    spec_defaults = mujoco.MjSpec().compiler
    source = attributes.get("inertiafromgeom", "auto")
    inertiafromgeom = {
        "auto": mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_AUTO,
        "true": mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE,
        "false": mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE,
    }.get(str(source).lower())
    if inertiafromgeom is None:
        return None
    return _Settings(
        inertiafromgeom=inertiafromgeom,
        inertiagrouprange=np.asarray(
            attributes.get("inertiagrouprange", spec_defaults.inertiagrouprange)
        ),
        boundmass=float(attributes.get("boundmass", spec_defaults.boundmass)),
        boundinertia=float(attributes.get("boundinertia", spec_defaults.boundinertia)),
        balanceinertia=_true(attributes.get("balanceinertia")),
    )


def _true(value) -> bool:
    return value is not None and str(value).lower() in ("true", "1")


def _body(physics, element, body_id: int, settings: _Settings) -> _Body | None:
    """The body `body_id` as `element`'s geom children, or None when its compiled geoms
    are not exactly those, or one of them is not a primitive."""
    model = physics.model.ptr
    geoms = element.get_children("geom")
    ids = [_geom_id(physics, geom) for geom in geoms]
    first = int(model.body_geomadr[body_id])
    if ids != list(range(first, first + int(model.body_geomnum[body_id]))):
        return None
    if any(int(model.geom_type[i]) not in _PRIMITIVES for i in ids):
        return None
    has_inertial = bool(_children(element, "inertial"))
    if (
        body_id == 0
        or settings.inertiafromgeom == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    ):
        from_geoms = False
    elif settings.inertiafromgeom == mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE:
        from_geoms = True
    else:
        from_geoms = not has_inertial
    return _Body(body_id, list(geoms), from_geoms)


def _body_writes(model, body: _Body, new_sizes: dict, settings: _Settings) -> list | None:
    """The writes of `body`'s derived fields, or None when the one-body model does not
    reproduce the compiled model's values from the old sizes."""
    first = int(model.body_geomadr[body.body_id])
    ids = range(first, first + len(body.geoms))
    old = _compile_alone(model, body, [model.geom_size[i] for i in ids], settings)
    new = _compile_alone(model, body, [new_sizes.get(i, model.geom_size[i]) for i in ids], settings)
    if old is None or new is None:
        return None
    alone_id = min(body.body_id, 1)
    old_rows, new_rows = _rows(old, alone_id, first), _rows(new, alone_id, first)
    current = _current_rows(model, body, first)
    fields = _GEOM_FIELDS + _BVH_FIELDS + (_INERTIA_FIELDS if body.inertia_from_geoms else ())
    if any(_bytes(old_rows[name]) != _bytes(current[name]) for name in fields):
        return None
    # A body whose inertial frame stops (or starts) being its own frame is compiled as
    # simple or not accordingly; mj_setConst does not revisit that.
    if old.body_sameframe[alone_id] != new.body_sameframe[alone_id]:
        return None
    bvh = slice(
        int(model.body_bvhadr[body.body_id]),
        int(model.body_bvhadr[body.body_id] + model.body_bvhnum[body.body_id]),
    )
    geoms = slice(first, first + len(body.geoms))
    writes = [FieldWrite(getattr(model, name), geoms, new_rows[name]) for name in _GEOM_FIELDS]
    writes += [FieldWrite(getattr(model, name), bvh, new_rows[name]) for name in _BVH_FIELDS]
    if body.inertia_from_geoms:
        writes += [
            FieldWrite(getattr(model, name), body.body_id, new_rows[name])
            for name in _INERTIA_FIELDS
        ]
    return writes


def _bytes(array) -> bytes:
    return np.ascontiguousarray(array).tobytes()


def _compile_alone(model, body: _Body, sizes: list, settings: _Settings) -> mujoco.MjModel | None:
    """A model of one body that holds `body`'s geoms with `sizes`, compiled."""
    spec = mujoco.MjSpec()
    compiler = spec.compiler
    compiler.inertiafromgeom = settings.inertiafromgeom
    compiler.inertiagrouprange = settings.inertiagrouprange
    compiler.boundmass = settings.boundmass
    compiler.boundinertia = settings.boundinertia
    compiler.balanceinertia = settings.balanceinertia
    b = body.body_id
    if b == 0:
        alone = spec.worldbody
    else:
        alone = spec.worldbody.add_body()
        if not body.inertia_from_geoms:
            # The BVH is expressed in the body's inertial frame.
            alone.explicitinertial = True
            alone.mass = float(model.body_mass[b])
            alone.inertia = model.body_inertia[b]
            alone.ipos = model.body_ipos[b]
            alone.iquat = model.body_iquat[b]
    first = int(model.body_geomadr[b])
    for offset, (geom, size) in enumerate(zip(body.geoms, sizes)):
        i = first + offset
        copy = alone.add_geom(
            type=mujoco.mjtGeom(model.geom_type[i]),
            size=size,
            pos=model.geom_pos[i],
            quat=model.geom_quat[i],
            group=int(model.geom_group[i]),
            contype=int(model.geom_contype[i]),
            conaffinity=int(model.geom_conaffinity[i]),
            margin=float(model.geom_margin[i]),
        )
        for xml_name, spec_name in (("mass", "mass"), ("density", "density")):
            source = traversal_utils.default_value_source(geom, xml_name)
            if source is not None:
                setattr(copy, spec_name, float(source._attributes[xml_name]))
        source = traversal_utils.default_value_source(geom, "shellinertia")
        if source is not None and _true(source._attributes["shellinertia"]):
            copy.typeinertia = mujoco.mjtGeomInertia.mjINERTIA_SHELL
    try:
        return spec.compile()
    except ValueError:
        return None


def _rows(alone: mujoco.MjModel, b: int, first: int) -> dict[str, np.ndarray]:
    """The one-body model's values of the copied fields of its body `b` (0 or 1), geom ids
    as in the compiled model, whose body has them from `first` on."""
    bvh = slice(int(alone.body_bvhadr[b]), int(alone.body_bvhadr[b] + alone.body_bvhnum[b]))
    rows = {name: getattr(alone, name)[bvh].copy() for name in _BVH_FIELDS}
    nodeid = rows["bvh_nodeid"]
    shift = first - int(alone.body_geomadr[b])
    rows["bvh_nodeid"] = np.where(nodeid >= 0, nodeid + shift, nodeid)
    geoms = slice(int(alone.body_geomadr[b]), int(alone.body_geomadr[b] + alone.body_geomnum[b]))
    rows.update({name: getattr(alone, name)[geoms].copy() for name in _GEOM_FIELDS})
    rows.update({name: getattr(alone, name)[b].copy() for name in _INERTIA_FIELDS})
    return rows


def _current_rows(model, body: _Body, first: int) -> dict[str, np.ndarray]:
    """The compiled model's values of the copied fields for `body`."""
    b = body.body_id
    bvh = slice(int(model.body_bvhadr[b]), int(model.body_bvhadr[b] + model.body_bvhnum[b]))
    rows = {name: getattr(model, name)[bvh] for name in _BVH_FIELDS}
    geoms = slice(first, first + len(body.geoms))
    rows.update({name: getattr(model, name)[geoms] for name in _GEOM_FIELDS})
    rows.update({name: getattr(model, name)[b] for name in _INERTIA_FIELDS})
    return rows
