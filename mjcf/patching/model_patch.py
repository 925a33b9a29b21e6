"""Brings a compiled model up to date with attribute changes by writing its fields in place.

A change of an attribute value whose compiled field is the value itself (a colour, a
friction, a gain, ...) does not need MuJoCo's compiler: writing the value into the field
gives the same `MjModel` a recompile would. Which changes are like that is not decided
here but proven, for the installed MuJoCo: by the corpus proof `mjcf.patching.patch_proof`
(the checked-in table `mjcf/patching/patchable_attributes.py` on its release), or on the
model at hand at first use (`mjcf.patching.first_use_proof`, which calls this with what the
proofs say). Each proven pair comes with whether `mj_setConst` must run after the write
(for fields MuJoCo derives constants from, such as masses).

A change is patched when every changed (element, attribute) of
`RootElement.attribute_changes_since` is proven, compiled into the Physics and resolvable:
the value that compiles is set on the element itself or on one of its default classes (see
`traversal_utils.default_value_source`). A change of a default-class template reaches every
element of that model whose classes include the template's class. A geom's `size` feeds
more fields than its own (bounds, its body's BVH and inertia):
`mjcf.patching.geom_size_patch` computes those. Anything else returns False and the caller
recompiles.

After `mj_setConst`, the patch also brings up to date what the compiler computes at
`qpos0` and `mj_setConst` does not: the model statistics (`mjcf.patching.model_statistics`:
`stat.center` and `stat.extent`, the viewer's framing, and `stat.meaninertia`, which scales
the solver's tolerance), and the rest length of tendons whose `springlength` the compiler
derives (a spatial tendon through a moved site). So a patched model stays bit-identical to
a recompile, statistics included, where dm_control would recompile. A quaternion or a
light's direction is normalised as the compiler normalises it. Declined (recompiled): the
pose of a body with a free joint (its `qpos0` is that pose, which only a compile sets), of
a moving body in a model with `springdamper` joints (converted with its tree's inertia),
of a geom or site given by `fromto`, and a quaternion beside another orientation (the
compiler refuses the model).
"""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from mjcf import attribute_types, binding, traversal_utils
from mjcf.element import Element
from mjcf.patching import geom_size_patch, model_statistics
from mjcf.patching.geom_size_cache import ElementsUsing, FieldTarget, SizePatchCache
from mujoco_physics.field_layout import MODEL

__all__ = ["patch_model"]


_Write = geom_size_patch.FieldWrite

# Pairs whose compiled values feed fields besides their own: they patch through a module
# that computes those fields too.
_GEOM_SIZE = ("geom", "size")
# Attributes the compiler normalises to unit length: a quaternion, a light's direction.
_UNIT_VECTORS = ("quat", "dir")
# MuJoCo's compiler leaves alone a vector whose squared norm is below this, and (on releases
# that skip it, see `_kept_near_unit`) one whose norm is within this of 1, dividing any other
# by its norm: `mjEPS` of its model compiler, which the bindings do not export.
_COMPILER_EPS = 1e-14
# The other ways of giving an orientation, which the compiler turns into a quaternion (and
# refuses alongside one): the fields of MuJoCo's orientation spec but its type.
_ORIENTATIONS = tuple(
    name for name in dir(mujoco.MjsOrientation) if not name.startswith("_") and name != "type"
)
# Pose attributes: a free joint's qpos0 is its body's pose, which only a compile sets, and a
# segment (`fromto`) gives a geom's or site's pose in their place.
_POSE = ("pos", "quat")
_SEGMENT = "fromto"
# The attributes that decide which default classes an element takes.
_CLASS_ATTRIBUTES = ("class", "childclass")
# `SizePatchCache.field_targets` has no entry yet.
_UNKNOWN = object()


def patch_model(physics, changes, *, proven: dict, cache: SizePatchCache | None = None) -> bool:
    """Writes the compiled values of changed attributes into `physics`'s model.

    Args:
      physics: an `mjcf.Physics` compiled from the model that `changes` come from, whose
        model is the compile of that model as it was before `changes`.
      changes: (element, XML attribute name) pairs, as `attribute_changes_since` gives them.
      cache: what earlier patches of `physics`'s compiled model looked up (see
        `mjcf.patching.geom_size_cache`); None looks everything up afresh.
      proven: (tag, attribute) -> whether `mj_setConst` must follow, for every pair a
        change may patch: what the proofs say of these changes
        (`mjcf.patching.first_use_proof`), or what a proof tries.

    Returns:
      True when the model now equals a fresh compile (the physics' data is left to the
      caller to reset: `mj_setConst` uses it as scratch space; the physics is marked dirty
      unless every change is a colour or material, as after a binding's write); False,
      having changed nothing, when some change cannot be patched (see the module
      docstring).
    """
    if cache is None:
        cache = SizePatchCache()
    writes = []
    sized_geoms = {}
    set_const = False
    for element, xml_name in changes:
        if traversal_utils.is_default_template(element):
            targets = _elements_using(element, xml_name, cache)
        else:
            targets = (element,)
        for target in targets:
            if type(target) is not Element:
                return False
            pair = (target._spec.name, xml_name)
            needs = proven.get(pair)
            if needs is None:
                return False
            set_const = set_const or needs
            if pair == _GEOM_SIZE:
                sized_geoms[id(target)] = target
                continue
            write = _write_for(physics, target, xml_name, cache)
            if write is None:
                return False
            writes.append(write)
    if sized_geoms:
        size_writes = geom_size_patch.size_writes(physics, list(sized_geoms.values()), cache)
        if size_writes is None:
            return False
        writes.extend(size_writes)
    for array, index, value in writes:
        array[index] = value
    if writes:
        model = physics.model.ptr
        if set_const:
            mujoco.mj_setConst(model, physics.data.ptr)
            _write_derived_spring_lengths(physics)
        if set_const or sized_geoms:
            # What moves a constant moves the statistics, which mj_setConst leaves alone.
            model_statistics.write_statistics(
                model,
                model_statistics.compiled_statistics(model, physics.data.ptr),
                keep=set(physics.mjcf_model.statistic._attributes),
            )
        # As a binding's write: a colour or material is not an input `mj_forward` reads.
        if set_const or sized_geoms or not physics.changes_are_forward_neutral(changes):
            physics.mark_as_dirty()
    return True


def _write_derived_spring_lengths(physics) -> None:
    """Sets the rest length of every tendon whose `springlength` the compiler derives to its
    length at `qpos0`, as `mj_setConst` has just recomputed it (`tendon_length0`).

    The compiler derives it where the resolved `springlength` is unset or all -1 (one -1
    stands for both ends of the range), and `mj_setConst` does not: a moved site that a
    spatial tendon passes through changes that tendon's spring, physics a recompile gives.
    """
    model = physics.model.ptr
    if not model.ntendon:
        return
    for tendon in physics.mjcf_model.find_all("tendon"):
        source = traversal_utils.default_value_source(tendon, "springlength")
        if source is not None and np.any(np.asarray(source._attributes["springlength"]) != -1):
            continue
        index = binding.object_id(physics.field_layout, physics.mjcf_model, tendon)
        model.tendon_lengthspring[index] = model.tendon_length0[index]


def _elements_using(template, xml_name: str, cache: SizePatchCache) -> list:
    """Elements of `template`'s tag that have attribute `xml_name`, in its model, whose
    default classes include the template's class.

    Kept in `cache.elements_using` with the model's `modification_count`, and found again
    only when the model's structure, or an attribute naming classes, changed since.
    """
    root = template._root
    cached = cache.elements_using.get((template, xml_name))
    if cached is not None:
        changes = root.attribute_changes_since(cached.modification_count)
        if changes is not None and not any(name in _CLASS_ATTRIBUTES for _, name in changes):
            return cached.elements
    tag = template._spec.name
    dclass = template._parent
    elements = [
        element
        for element in root._iter_own_tree()
        if element._spec.name == tag
        and xml_name in element._spec.attributes
        and not traversal_utils.is_default_template(element)
        and dclass in traversal_utils.default_classes(element)
    ]
    cache.elements_using[template, xml_name] = ElementsUsing(root.modification_count, elements)
    return elements


def _write_for(physics, element, xml_name: str, cache: SizePatchCache) -> _Write | None:
    """The field write that gives `element`'s compiled value of `xml_name`, or None; where
    it goes in the compiled model is looked up once per model (`cache.field_targets`)."""
    source = traversal_utils.default_value_source(element, xml_name)
    if source is None:
        return None
    model = physics.model.ptr
    key = (element, xml_name)
    target = cache.field_targets.get(key, _UNKNOWN)
    if target is _UNKNOWN or (target is not None and target.model is not model):
        target = cache.field_targets[key] = _field_target(physics, element, xml_name, cache)
    if target is None:
        return None
    object_id = cache.object_ids[element]
    value = np.asarray(source._attributes[xml_name], dtype=np.float64)
    # As many numbers as the field holds for the object: MuJoCo fills in missing ones.
    if value.size != target.size:
        return None
    if xml_name == "quat" and any(_resolves(element, name) for name in _ORIENTATIONS):
        return None  # the compiler refuses a second orientation
    if xml_name in _POSE and _pose_needs_a_compile(physics, element, object_id):
        return None
    if xml_name in _UNIT_VECTORS:
        value = _unit_vector(value)
        if value is None:
            return None
    return _Write(target.array, target.index, value.reshape(target.shape))


def _field_target(physics, element, xml_name: str, cache: SizePatchCache) -> FieldTarget | None:
    """Where `element`'s `xml_name` compiles to in `physics`'s model, or None where a patch
    cannot write it; the element's compiled id is kept in `cache.object_ids`."""
    if element._spec.attributes[xml_name].type.kind != attribute_types.OTHER:
        return None
    ref = binding.compiled_field(element, xml_name)
    if ref is None or ref.struct != MODEL:
        return None
    layout = physics.field_layout
    object_id = cache.object_id(physics, element)
    if object_id is None:
        return None
    model = physics.model.ptr
    array = getattr(model, ref.name)
    index = layout.single_index(ref.addressing, object_id)
    target = array[index]
    return FieldTarget(model, array, index, np.shape(target), np.size(target))


def _unit_vector(value: np.ndarray) -> np.ndarray | None:
    """`value` normalised as the compiler normalises it (the squares summed in its order,
    then divided by the norm unless the norm is within `_COMPILER_EPS` of 1 on a release
    that keeps such a vector); None for a vector the compiler does not normalise."""
    total = 0.0
    for number in value:
        total += float(number) * float(number)
    if total < _COMPILER_EPS:
        return None
    norm = np.sqrt(total)
    if abs(norm - 1.0) <= _COMPILER_EPS and _kept_near_unit():
        return value
    return value / norm


@functools.cache
def _kept_near_unit() -> bool:
    """Whether the installed MuJoCo's compiler keeps a quaternion whose norm is within
    `_COMPILER_EPS` of 1 as given (recent releases) instead of dividing it by its norm:
    asked of the compiler once, on a model of one body."""
    quat = np.full(4, 0.5) * (1 + _COMPILER_EPS / 2)
    text = " ".join(repr(float(number)) for number in quat)
    xml = f'<mujoco><worldbody><body quat="{text}"><geom size="1"/></body></worldbody></mujoco>'
    return bool(np.array_equal(mujoco.MjModel.from_xml_string(xml).body_quat[1], quat))


def _resolves(element, xml_name: str) -> bool:
    """Whether `element` has attribute `xml_name`, set on it or by a default class."""
    return (
        xml_name in element._spec.attributes
        and traversal_utils.default_value_source(element, xml_name) is not None
    )


def _pose_needs_a_compile(physics, element, object_id: int) -> bool:
    """Whether a change of `element`'s position or orientation is more than a write and
    `mj_setConst`: a segment (`fromto`) gives it, it is a body with a free joint, or a body
    that moves (not welded to the world) in a model with a joint whose stiffness and
    damping come from `springdamper`, which the compiler converts with the inertia of the
    joint's tree."""
    if _resolves(element, _SEGMENT):
        return True
    if element._spec.name != "body":
        return False
    if _has_free_joint(element):
        return True
    if physics.model.ptr.body_weldid[object_id] == 0:
        return False
    return any(
        traversal_utils.default_value_source(joint, "springdamper") is not None
        for joint in physics.mjcf_model.find_all("joint")
    )


def _has_free_joint(element) -> bool:
    """Whether the body `element` has a free joint of its own."""
    if element.get_children("freejoint"):
        return True
    for joint in element.get_children("joint"):
        source = traversal_utils.default_value_source(joint, "type")
        if source is not None and source._attributes["type"] == "free":
            return True
    return False
