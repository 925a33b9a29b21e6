"""Copies of compiled bodies' geoms in a model of their own, whose compile gives the fields
that MuJoCo derives from the geoms' sizes.

A `BodyCopies` holds, in one `mujoco.MjSpec`, a copy of each geom of some bodies of a
compiled model: its compiled type, frame, group, contact bits and margin, and its MJCF
mass, density and `shellinertia`, under the model's `<compiler>` inertia settings. A body
whose inertia is explicit keeps it. Compiled with given sizes, the copy gives each body's
derived rows (`DerivedRows`): the geoms' bounding radius and box, the body's bounding
volume hierarchy and, when its inertia comes from its geoms, its mass, inertia and
inertial frame. `mjcf.patching.geom_size_patch` uses them; its module docstring says when a
copy is trusted.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from mjcf import traversal_utils

__all__ = ["BodyCopies", "CompiledBody", "DerivedRows", "InertiaSettings", "is_true"]

# Per-geom fields derived from a geom's size.
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

# Field name -> a body's rows of it: what the compiler derives from its geoms' sizes.
DerivedRows = dict[str, np.ndarray]


class InertiaSettings(NamedTuple):
    """The `<compiler>` settings that decide how bodies' inertias follow from geoms."""

    inertiafromgeom: mujoco.mjtInertiaFromGeom
    inertiagrouprange: tuple[int, int]
    boundmass: float
    boundinertia: float
    balanceinertia: bool


class CompiledBody(NamedTuple):
    """A compiled body whose geoms are the `<geom>` children of one MJCF element."""

    body_id: int
    geoms: list  # the `<geom>` elements, in compiled order
    geom_ids: range  # their compiled ids, consecutive
    inertia_from_geoms: bool


def is_true(value) -> bool:
    """Whether an MJCF boolean attribute's value (None when unset) is true."""
    return value is not None and str(value).lower() in ("true", "1")


def _bvh_rows(model, body_id: int) -> slice:
    start = int(model.body_bvhadr[body_id])
    return slice(start, start + int(model.body_bvhnum[body_id]))


def _geom_rows(body: CompiledBody) -> slice:
    return slice(body.geom_ids.start, body.geom_ids.stop)


def row_slices(model: mujoco.MjModel, body: CompiledBody) -> dict[str, int | slice]:
    """Field name -> where `body`'s derived rows lie in `model` (its inertia only where it
    comes from the geoms)."""
    slices = dict.fromkeys(_BVH_FIELDS, _bvh_rows(model, body.body_id))
    slices.update(dict.fromkeys(_GEOM_FIELDS, _geom_rows(body)))
    if body.inertia_from_geoms:
        slices.update(dict.fromkeys(_INERTIA_FIELDS, body.body_id))
    return slices


def model_rows(model: mujoco.MjModel, body: CompiledBody) -> DerivedRows:
    """`model`'s current derived rows of `body` (views), at `row_slices`."""
    return {name: getattr(model, name)[rows] for name, rows in row_slices(model, body).items()}


def geom_sizes(model: mujoco.MjModel, bodies: list[CompiledBody]) -> np.ndarray:
    """A copy of the compiled sizes of the bodies' geoms, in body order."""
    return model.geom_size[[i for body in bodies for i in body.geom_ids]]


def same_bytes(first: dict, second: dict) -> bool:
    """Whether every array of `first` has the bytes of `second`'s array of the same name."""
    return all(_raw_bytes(value) == _raw_bytes(second[name]) for name, value in first.items())


def _raw_bytes(array) -> bytes:
    return np.ascontiguousarray(array).tobytes()


class BodyCopies:
    """Copies of some compiled bodies' geoms, compiled as a model of their own.

    The bodies keep their order: a world body's geoms (body 0) are the copy's world's, the
    others become bodies 1, 2, ... of the copy. `compile(sizes)` sets the sizes and
    compiles; `last_sizes` and `last_rows` say what the last compile that a caller kept
    had and gave.

    Args (construction):
      model: the compiled model the bodies are from.
      bodies: the bodies to copy.
      settings: the model's inertia settings.
    """

    __slots__ = ("elements", "spec", "spec_geoms", "inputs", "last_sizes", "last_rows")

    def __init__(self, model, bodies: list[CompiledBody], settings: InertiaSettings):
        self.elements = [geom for body in bodies for geom in body.geoms]
        self.spec = _spec_of(model, bodies, settings)
        self.spec_geoms = [geom for body in self.spec.bodies for geom in body.geoms]
        self.inputs = _copied_inputs(model, bodies)
        self.last_sizes: np.ndarray | None = None
        self.last_rows: list[DerivedRows] | None = None

    def compile(self, bodies: list[CompiledBody], sizes: np.ndarray) -> list[DerivedRows] | None:
        """Each body's derived rows with its geoms sized `sizes` (all bodies' geoms, in body
        order), geom ids as in the compiled model; None when MuJoCo rejects the sizes."""
        for geom, size in zip(self.spec_geoms, sizes):
            geom.size = size
        try:
            copy = self.spec.compile()
        except ValueError:
            return None
        self.last_sizes = sizes
        return [
            _copy_rows(copy, copy_id, body) for copy_id, body in zip(_copy_body_ids(bodies), bodies)
        ]

    def built_from(self, model, bodies: list[CompiledBody]) -> bool:
        """Whether `bodies` hold the very geoms copied here, and `model` the values (other
        than sizes) they were copied with."""
        geoms = [geom for body in bodies for geom in body.geoms]
        return (
            len(geoms) == len(self.elements)
            and all(mine is theirs for mine, theirs in zip(self.elements, geoms))
            and same_bytes(self.inputs, _copied_inputs(model, bodies))
        )

    def model_holds_last_compile(self, model, bodies: list[CompiledBody]) -> bool:
        """Whether `model` holds the sizes and derived rows of the last kept compile."""
        return (
            self.last_rows is not None
            and _raw_bytes(self.last_sizes) == _raw_bytes(geom_sizes(model, bodies))
            and all(
                same_bytes(model_rows(model, body), rows)
                for body, rows in zip(bodies, self.last_rows)
            )
        )

    def reproduces(self, model, bodies: list[CompiledBody]) -> bool:
        """Compiles with `model`'s sizes; whether that gives `model`'s derived rows (they
        are then kept as the last compile's)."""
        rows = self.compile(bodies, geom_sizes(model, bodies))
        if rows is None or not all(
            same_bytes(model_rows(model, body), row) for body, row in zip(bodies, rows)
        ):
            return False
        self.last_rows = rows
        return True


def _copy_body_ids(bodies: list[CompiledBody]) -> list[int]:
    """The ids the bodies have in their copy: 0 for the world, then 1, 2, ..."""
    ids, next_id = [], 1
    for body in bodies:
        if body.body_id == 0:
            ids.append(0)
        else:
            ids.append(next_id)
            next_id += 1
    return ids


def _copied_inputs(model, bodies: list[CompiledBody]) -> dict[str, np.ndarray]:
    """What a copy takes from the compiled model besides sizes: its geoms' fields, and
    the inertias of bodies that set theirs."""
    ids = [i for body in bodies for i in body.geom_ids]
    inputs = {name: getattr(model, name)[ids] for name in _GEOM_INPUTS}
    explicit = [body.body_id for body in bodies if not body.inertia_from_geoms]
    inputs.update({name: getattr(model, name)[explicit] for name in _INERTIA_FIELDS})
    return inputs


def _spec_of(model, bodies: list[CompiledBody], settings: InertiaSettings) -> mujoco.MjSpec:
    """An `MjSpec` holding copies of the bodies' geoms (in `BodyCopies`'s order) under
    `settings`; their sizes are set before each compile."""
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
            copy = spec.worldbody
        else:
            copy = spec.worldbody.add_body()
            if not body.inertia_from_geoms:
                # The BVH is expressed in the body's inertial frame.
                copy.explicitinertial = True
                copy.mass = float(model.body_mass[b])
                copy.inertia = model.body_inertia[b]
                copy.ipos = model.body_ipos[b]
                copy.iquat = model.body_iquat[b]
        for geom, i in zip(body.geoms, body.geom_ids):
            _add_geom_copy(copy, model, geom, i)
    return spec


def _add_geom_copy(body_spec, model, geom, geom_id: int) -> None:
    """Adds to `body_spec` a copy of compiled geom `geom_id`, with its element `geom`'s
    mass, density and shell inertia."""
    copy = body_spec.add_geom(
        type=mujoco.mjtGeom(model.geom_type[geom_id]),
        pos=model.geom_pos[geom_id],
        quat=model.geom_quat[geom_id],
        group=int(model.geom_group[geom_id]),
        contype=int(model.geom_contype[geom_id]),
        conaffinity=int(model.geom_conaffinity[geom_id]),
        margin=float(model.geom_margin[geom_id]),
    )
    for name in ("mass", "density"):
        source = traversal_utils.default_value_source(geom, name)
        if source is not None:
            setattr(copy, name, float(source._attributes[name]))
    source = traversal_utils.default_value_source(geom, "shellinertia")
    if source is not None and is_true(source._attributes["shellinertia"]):
        copy.typeinertia = mujoco.mjtGeomInertia.mjINERTIA_SHELL


def _copy_rows(copy: mujoco.MjModel, copy_id: int, body: CompiledBody) -> DerivedRows:
    """The copy's derived rows of its body `copy_id`, which stands for `body`, with geom
    ids as in the compiled model; also its `body_sameframe`."""
    copy_first = int(copy.body_geomadr[copy_id])
    rows = {name: getattr(copy, name)[_bvh_rows(copy, copy_id)].copy() for name in _BVH_FIELDS}
    node = rows["bvh_nodeid"]
    shift = body.geom_ids.start - copy_first
    rows["bvh_nodeid"] = np.where(node >= 0, node + shift, node)
    geoms = slice(copy_first, copy_first + int(copy.body_geomnum[copy_id]))
    rows.update({name: getattr(copy, name)[geoms].copy() for name in _GEOM_FIELDS})
    rows.update({name: getattr(copy, name)[copy_id].copy() for name in _INERTIA_FIELDS})
    rows["body_sameframe"] = copy.body_sameframe[copy_id].copy()
    return rows
