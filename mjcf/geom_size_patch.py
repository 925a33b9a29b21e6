"""The field writes that patch a primitive geom's `size`, with what the compiler derives from it.

Besides `geom_size`, a geom's size feeds its bounding radius and box (`geom_rbound`,
`geom_aabb`), its body's bounding volume hierarchy (`bvh_*` over the body's
`body_bvhadr`/`body_bvhnum` rows) and, when the body's inertia comes from its geoms, the
body's mass, inertia and inertial frame (`body_mass`, `body_inertia`, `body_ipos`,
`body_iquat`). Nothing of that is computed here: MuJoCo's compiler computes it, on a model
holding copies of the changed bodies' geoms (their compiled type, size, frame, group,
contact bits and margin, their MJCF mass, density and `shellinertia`) under the same
`<compiler>` inertia settings, compiled with the new sizes. The copies (an `MjSpec`) are
built once per MJCF model and checked: compiled with the sizes the compiled model holds,
they must reproduce its values bit for bit (otherwise some input is not what the compiler
saw, and the patch declines). They are checked again wherever the compiled model no
longer holds what they last gave (it was recompiled in between), and built anew when that
fails. What follows from the written values (subtree masses, inverse weights, ...) is
left to `mj_setConst`, which the patch table requires after a size write, and the model
statistics to `mjcf.model_statistics`. That the result equals a recompile is proven by
`mjcf/patch_proof.py`, like every pair of the table.

Declined (the caller recompiles): geoms other than sphere, capsule, ellipsoid, cylinder and
box, in the changed geom's body too; geoms given by `fromto` (the compiled size is not the
attribute); geoms with fluid interaction (`fluidshape`); bodies whose geoms are not all
children of the one MJCF element (`<frame>`s, attached models); models with a joint
whose stiffness and damping come from `springdamper` (converted with the inertia it
moves); models with flexes; `settotalmass` and `alignfree`, which make one body's inertia
depend on the others or move its frame.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import mujoco
import numpy as np

from mjcf import binding, traversal_utils
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
# The compiled fields of a geom that its copy is given.
_GEOM_INPUTS = (
    "geom_type",
    "geom_pos",
    "geom_quat",
    "geom_group",
    "geom_contype",
    "geom_conaffinity",
    "geom_margin",
)
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
    geom_ids: range  # the geoms' compiled ids, consecutive
    inertia_from_geoms: bool

    @property
    def first(self) -> int:
        """The compiled id of the body's first geom."""
        return self.geom_ids.start


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
    if settings is None or model.nflex or _springdamper_anywhere(physics):
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
    body_writes = _bodies_writes(physics, list(bodies.values()), new_sizes, settings)
    if body_writes is None:
        return None
    writes = [FieldWrite(model.geom_size, geom_id, size) for geom_id, size in new_sizes.items()]
    return writes + body_writes


# Per Physics, what was looked up in its compiled model by element: geom ids, and bodies
# (by element and settings). A Physics' structure never changes (a patch is only tried on
# the structure it was compiled from), so neither do they.
_LOOKUPS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _geom_id(physics, geom) -> int | None:
    lookups = _LOOKUPS.setdefault(physics, {})
    if geom not in lookups:
        try:
            lookups[geom] = binding.object_id(physics._layout, physics._mjcf_model, geom)
        except ValueError:
            lookups[geom] = None
    return lookups[geom]


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
    inertiagrouprange: tuple[int, int]
    boundmass: float
    boundinertia: float
    balanceinertia: bool


# Per Physics: the model's modification count when its joints were last looked at, and
# whether one of them had `springdamper`.
_SPRINGDAMPER_SCANS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _springdamper_anywhere(physics) -> bool:
    """Whether a joint of `physics`'s MJCF model takes its stiffness and damping from
    `springdamper`, which the compiler converts with the inertia the joint moves (its whole
    tree's, not only the bodies below it).

    The joints are looked at again only when the model changed since the last look in
    more than attributes of geoms and geom defaults (a joint's attribute, or its
    structure), which patch after patch of sizes does not.
    """
    root = physics._mjcf_model
    scan = _SPRINGDAMPER_SCANS.get(physics)
    if scan is not None:
        count, found = scan
        changes = root.attribute_changes_since(count)
        if changes is not None and all(element.tag == "geom" for element, _ in changes):
            _SPRINGDAMPER_SCANS[physics] = (root.modification_count, found)
            return found
    found = any(
        traversal_utils.default_value_source(joint, "springdamper") is not None
        for joint in root.find_all("joint")
    )
    _SPRINGDAMPER_SCANS[physics] = (root.modification_count, found)
    return found


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
        inertiagrouprange=tuple(
            int(group)
            for group in attributes.get("inertiagrouprange", spec_defaults.inertiagrouprange)
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
    lookups = _LOOKUPS.setdefault(physics, {})
    key = (element, settings)
    if key not in lookups:
        lookups[key] = _look_up_body(physics, element, body_id, settings)
    return lookups[key]


def _look_up_body(physics, element, body_id: int, settings: _Settings) -> _Body | None:
    model = physics.model.ptr
    geoms = element.get_children("geom")
    ids = [_geom_id(physics, geom) for geom in geoms]
    first = int(model.body_geomadr[body_id])
    geom_ids = range(first, first + int(model.body_geomnum[body_id]))
    if ids != list(geom_ids):
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
    return _Body(body_id, list(geoms), geom_ids, from_geoms)


class _Copies:
    """Copies of some bodies' geoms, in one `MjSpec` compiled as a model of its own, kept
    between patches with the sizes and rows its last compile had and gave.

    The bodies keep their order; the world's geoms (body 0) are the copy's world's, the
    others' are bodies 1, 2, ... of it. A patch sets the new sizes on the spec's geoms and
    compiles it again. The spec is built once and serves every Physics compiled from the
    same MJCF model while the compiled values it was built from (all but the sizes) stay
    the same; where the compiled model holds other sizes than the copy last had (it was
    recompiled in between), the copy is first compiled with those and checked again.
    """

    __slots__ = ("geoms", "spec", "spec_geoms", "inputs", "sizes", "rows")

    def __init__(self, model, bodies: list[_Body], settings: _Settings):
        self.geoms = [geom for body in bodies for geom in body.geoms]
        self.spec = _spec_of(model, bodies, settings)
        self.spec_geoms = [geom for body in self.spec.bodies for geom in body.geoms]
        self.inputs = _inputs(model, bodies)
        self.sizes = None
        self.rows = None

    def compile(self, bodies: list[_Body], sizes: np.ndarray) -> list[dict] | None:
        """Each body's rows with the geoms of all bodies sized `sizes` (in body order),
        geom ids as in the compiled model of `bodies`."""
        for geom, size in zip(self.spec_geoms, sizes):
            geom.size = size
        try:
            alone = self.spec.compile()
        except ValueError:
            return None
        self.sizes = sizes
        return [
            _rows(alone, alone_id, int(alone.body_geomadr[alone_id]), body.first)
            for alone_id, body in zip(_alone_ids(bodies), bodies)
        ]

    def built_from(self, model, bodies: list[_Body]) -> bool:
        """Whether `bodies` are the ones this copy holds, and their compiled model holds
        the values (other than sizes) the copy was built from."""
        geoms = [geom for body in bodies for geom in body.geoms]
        return (
            len(geoms) == len(self.geoms)
            and all(mine is theirs for mine, theirs in zip(self.geoms, geoms))
            and _same(self.inputs, _inputs(model, bodies))
        )

    def gave(self, model, bodies: list[_Body]) -> bool:
        """Whether the compiled model holds the sizes and rows of the copy's last compile."""
        return (
            self.rows is not None
            and _bytes(self.sizes) == _bytes(_sizes(model, bodies))
            and all(
                _same(_current_rows(model, body), rows) for body, rows in zip(bodies, self.rows)
            )
        )


# Per MJCF model, the copies made for its Physics, by their bodies' geoms and the settings.
_COPIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _bodies_writes(physics, bodies: list[_Body], new_sizes: dict, settings: _Settings):
    """The writes of the bodies' derived fields, or None when the copy of the bodies does
    not reproduce the compiled model's values from the sizes it holds."""
    model = physics.model.ptr
    copies_of = _COPIES.setdefault(physics._mjcf_model, {})
    key = (
        tuple(
            (id(geom), body.body_id == 0, body.inertia_from_geoms)
            for body in bodies
            for geom in body.geoms
        ),
        settings,
    )
    copies = copies_of.get(key)
    if copies is None or not copies.built_from(model, bodies):
        copies = copies_of[key] = _Copies(model, bodies, settings)
    if not copies.gave(model, bodies) and not _check(copies, model, bodies):
        # What changed since may be an MJCF value the copy took (a density): build it anew.
        copies = copies_of[key] = _Copies(model, bodies, settings)
        if not _check(copies, model, bodies):
            del copies_of[key]
            return None
    sizes = _sizes(model, bodies)
    for row, i in enumerate(i for body in bodies for i in body.geom_ids):
        if i in new_sizes:
            sizes[row] = new_sizes[i]
    old_rows, new = copies.rows, copies.compile(bodies, sizes)
    if new is None:
        del copies_of[key]
        return None
    writes = []
    for body, before, after in zip(bodies, old_rows, new):
        # A body whose inertial frame stops (or starts) being its own frame is compiled as
        # simple or not accordingly; mj_setConst does not revisit that.
        if before["body_sameframe"] != after["body_sameframe"]:
            del copies_of[key]
            return None
        writes += _writes_of(model, body, after)
    copies.rows = new
    return writes


def _check(copies: _Copies, model, bodies: list[_Body]) -> bool:
    """Compiles `copies` with the compiled model's sizes; whether that gives the compiled
    model's rows (then they are the copy's last)."""
    rows = copies.compile(bodies, _sizes(model, bodies))
    if rows is None or not all(
        _same(_current_rows(model, body), row) for body, row in zip(bodies, rows)
    ):
        return False
    copies.rows = rows
    return True


def _sizes(model, bodies: list[_Body]) -> np.ndarray:
    """The compiled sizes of the bodies' geoms, in body order (a copy)."""
    return model.geom_size[[i for body in bodies for i in body.geom_ids]]


def _writes_of(model, body: _Body, rows: dict) -> list[FieldWrite]:
    b = body.body_id
    bvh = slice(int(model.body_bvhadr[b]), int(model.body_bvhadr[b] + model.body_bvhnum[b]))
    geoms = slice(body.first, body.first + len(body.geom_ids))
    writes = [FieldWrite(getattr(model, name), geoms, rows[name]) for name in _GEOM_FIELDS]
    writes += [FieldWrite(getattr(model, name), bvh, rows[name]) for name in _BVH_FIELDS]
    if body.inertia_from_geoms:
        writes += [FieldWrite(getattr(model, name), b, rows[name]) for name in _INERTIA_FIELDS]
    return writes


def _same(first: dict, second: dict) -> bool:
    """Whether every array of `first` has the bytes of `second`'s of the same name."""
    return all(_bytes(value) == _bytes(second[name]) for name, value in first.items())


def _bytes(array) -> bytes:
    return np.ascontiguousarray(array).tobytes()


def _alone_ids(bodies: list[_Body]) -> list[int]:
    """The ids the bodies have in their copy: 0 for the world, then 1, 2, ..."""
    ids, next_id = [], 1
    for body in bodies:
        if body.body_id == 0:
            ids.append(0)
        else:
            ids.append(next_id)
            next_id += 1
    return ids


def _inputs(model, bodies: list[_Body]) -> dict[str, np.ndarray]:
    """What the copy takes from the compiled model besides sizes: its geoms' fields, and
    the inertias of bodies that set theirs."""
    ids = [i for body in bodies for i in body.geom_ids]
    inputs = {name: getattr(model, name)[ids] for name in _GEOM_INPUTS}
    explicit = [body.body_id for body in bodies if not body.inertia_from_geoms]
    inputs.update({name: getattr(model, name)[explicit] for name in _INERTIA_FIELDS})
    return inputs


def _spec_of(model, bodies: list[_Body], settings: _Settings) -> mujoco.MjSpec:
    """An `MjSpec` holding copies of the bodies' geoms (in `_Copies`'s order) under the
    compiler's inertia settings; their sizes are set before each compile."""
    spec = mujoco.MjSpec()
    compiler = spec.compiler
    compiler.inertiafromgeom = settings.inertiafromgeom
    compiler.inertiagrouprange = settings.inertiagrouprange
    compiler.boundmass = settings.boundmass
    compiler.boundinertia = settings.boundinertia
    compiler.balanceinertia = settings.balanceinertia
    for body in bodies:
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
        for geom, i in zip(body.geoms, body.geom_ids):
            copy = alone.add_geom(
                type=mujoco.mjtGeom(model.geom_type[i]),
                pos=model.geom_pos[i],
                quat=model.geom_quat[i],
                group=int(model.geom_group[i]),
                contype=int(model.geom_contype[i]),
                conaffinity=int(model.geom_conaffinity[i]),
                margin=float(model.geom_margin[i]),
            )
            for name in ("mass", "density"):
                source = traversal_utils.default_value_source(geom, name)
                if source is not None:
                    setattr(copy, name, float(source._attributes[name]))
            source = traversal_utils.default_value_source(geom, "shellinertia")
            if source is not None and _true(source._attributes["shellinertia"]):
                copy.typeinertia = mujoco.mjtGeomInertia.mjINERTIA_SHELL
    return spec


def _rows(alone: mujoco.MjModel, b: int, alone_first: int, first: int) -> dict[str, np.ndarray]:
    """The copy's values of the derived fields of its body `b`, whose geoms start at
    `alone_first`, with geom ids as in the compiled model, where they start at `first`."""
    bvh = slice(int(alone.body_bvhadr[b]), int(alone.body_bvhadr[b] + alone.body_bvhnum[b]))
    rows = {name: getattr(alone, name)[bvh].copy() for name in _BVH_FIELDS}
    nodeid = rows["bvh_nodeid"]
    rows["bvh_nodeid"] = np.where(nodeid >= 0, nodeid + (first - alone_first), nodeid)
    geoms = slice(alone_first, alone_first + int(alone.body_geomnum[b]))
    rows.update({name: getattr(alone, name)[geoms].copy() for name in _GEOM_FIELDS})
    rows.update({name: getattr(alone, name)[b].copy() for name in _INERTIA_FIELDS})
    rows["body_sameframe"] = alone.body_sameframe[b].copy()
    return rows


def _current_rows(model, body: _Body) -> dict[str, np.ndarray]:
    """The compiled model's values of the derived fields for `body` (its inertia only
    where it comes from the geoms)."""
    b = body.body_id
    bvh = slice(int(model.body_bvhadr[b]), int(model.body_bvhadr[b] + model.body_bvhnum[b]))
    rows = {name: getattr(model, name)[bvh] for name in _BVH_FIELDS}
    geoms = slice(body.first, body.first + len(body.geom_ids))
    rows.update({name: getattr(model, name)[geoms] for name in _GEOM_FIELDS})
    if body.inertia_from_geoms:
        rows.update({name: getattr(model, name)[b] for name in _INERTIA_FIELDS})
    return rows
