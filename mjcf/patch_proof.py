"""Proves which MJCF attributes `mjcf.model_patch` may write into a compiled model in place.

Usage: `python -m mjcf.patch_proof [--write] [--extra-models DIR]` (about half a minute)

For every candidate (tag, attribute) pair (a float attribute of an element that compiles to
a MuJoCo object, whose binding field of the same name is an MjModel array) and every model
of the corpus that has it (the 25 manipulation tasks' models and the scenes below), it
changes the attribute's value, once on an element once on a default-class template, and once
where nothing set it before (MuJoCo's built-in default applied), as far as the model has
such elements, then patches a copy of the compiled model with `mjcf.model_patch`,
recompiles the changed model, and requires every MjModel array (and the `stat` struct) to be
bit-identical (and its sizes), and every MjData array after `mj_forward` from the same
state. A pair is
proven when every change of it in the corpus passed, by a plain write or, failing that, by a
write followed by `mj_setConst`.

Prints one line per pair: how it patches, or why it recompiles (the fields that differ).
On the MuJoCo release the checked-in table `mjcf/patchable_attributes.py` was proven on, it
exits 1 when the proof disagrees with the table, unless `--write`, which rewrites the table
(for the project's maintainers, in a source checkout). On any other release it saves the
proof in the user's cache directory (`mjcf.patch_table.cache_path`), where every later
process finds it: patching is then on there, for exactly the pairs proven.

The corpus includes the manipulation suite's models, which sit above `mjcf`: they are
imported when the proof runs, never by `import mjcf`.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import pprint
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

import mjcf
from mjcf import (
    attribute_types,
    model_patch,
    patch_table,
    patchable_attributes,
    schema,
    traversal_utils,
)
from mjcf.element import Element
from mjcf.physics import compile_mjcf_model
from mujoco_physics.field_layout import FAMILIES, MODEL

_NOT_IN_CORPUS = "no model of the corpus has it"
# How many forwards of copies of a model tell its scratch arrays (see `_scratch_arrays`).
_SCRATCH_RUNS = 6
_TABLE = Path(patchable_attributes.__file__)

# Scenes besides the manipulation tasks: degree and radian angles, a joint whose stiffness
# and damping come from `springdamper`, every primitive geom type, bodies
# whose mass comes from geoms and bodies with explicit inertia, tendons, actuators of
# several kinds, equality constraints, lights, cameras, materials and default classes.
_SCENES = {
    "creature (degree)": """
<mujoco>
  <default>
    <joint damping="0.1" range="-30 30"/>
    <default class="knee">
      <joint range="0 70" armature="0.02"/>
    </default>
  </default>
  <worldbody>
    <light pos="0 0 3" dir="0 0.3 -1"/>
    <geom name="floor" type="plane" size="3 3 0.1" friction="1 0.005 0.0001"/>
    <body name="torso" pos="0 0 0.5" euler="0 0 30">
      <freejoint/>
      <geom name="torso" type="sphere" size="0.1" rgba="0.8 0.6 0.4 1"/>
      <body name="tail" pos="-0.1 0 0">
        <joint name="tail" axis="0 1 0" springdamper="0.2 0.7" damping="0.3" stiffness="2"/>
        <geom type="capsule" fromto="0 0 0 -0.2 0 0" size="0.02"/>
      </body>
      <body name="thigh" pos="0.1 0 0">
        <joint name="hip" axis="0 0 1" range="-40 40" stiffness="1"/>
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.03"/>
        <body name="shin" pos="0.2 0 0">
          <joint name="knee" class="knee" axis="0 1 0" frictionloss="0.01"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 -0.3" size="0.03"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="hip" gear="10" ctrlrange="-1 1"/>
    <position joint="knee" kp="5" ctrlrange="0 1"/>
  </actuator>
</mujoco>
""",
    "primitives (radian)": """
<mujoco>
  <compiler angle="radian"/>
  <option timestep="0.002"/>
  <default>
    <geom friction="0.8 0.01 0.001" rgba="0.5 0.5 0.5 1" density="900" solref="0.02 1"/>
    <joint damping="0.3" armature="0.01" stiffness="0.5"/>
    <site size="0.02"/>
    <default class="limb">
      <geom size="0.04 0.2" type="capsule" margin="0.001"/>
      <joint range="-1 1" frictionloss="0.02"/>
    </default>
  </default>
  <asset>
    <material name="shiny" rgba="0.2 0.3 0.4 1" specular="0.4" shininess="0.6"/>
  </asset>
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1" diffuse="0.7 0.7 0.7"/>
    <camera name="side" pos="0 -3 1" xyaxes="1 0 0 0 0.3 1" fovy="50"/>
    <geom name="floor" type="plane" size="3 3 0.1" material="shiny"/>
    <body name="ball" pos="0 0 1">
      <freejoint/>
      <geom name="ball" type="sphere" size="0.1" mass="0.5"/>
      <site name="ball_top" pos="0 0 0.1"/>
    </body>
    <body name="crate" pos="0.5 0 0.5">
      <joint name="slide" type="slide" axis="1 0 0" range="-0.5 0.5"/>
      <geom name="crate" type="box" size="0.1 0.15 0.05"/>
      <geom name="lid" type="ellipsoid" pos="0 0 0.06" size="0.1 0.1 0.02"/>
    </body>
    <body name="arm" pos="-0.5 0 0.8" childclass="limb">
      <inertial pos="0 0 -0.1" mass="1.2" diaginertia="0.01 0.01 0.002"/>
      <joint name="shoulder" axis="0 1 0"/>
      <geom name="upper" fromto="0 0 0 0 0 -0.3"/>
      <body name="forearm" pos="0 0 -0.3">
        <joint name="elbow" axis="0 1 0" range="-2 0.5"/>
        <geom name="forearm" type="cylinder" size="0.03 0.12" pos="0 0 -0.12"/>
        <site name="hand" pos="0 0 -0.25"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="coupling" stiffness="2" damping="0.1">
      <joint joint="shoulder" coef="1"/>
      <joint joint="elbow" coef="-0.5"/>
    </fixed>
    <spatial name="cord" width="0.005" rgba="1 1 0 1">
      <site site="ball_top"/>
      <site site="hand"/>
    </spatial>
  </tendon>
  <equality>
    <joint joint1="shoulder" joint2="elbow" polycoef="0 0.5 0 0 0" solref="0.05 1"/>
  </equality>
  <actuator>
    <motor name="shoulder" joint="shoulder" gear="2" ctrlrange="-1 1"/>
    <position name="elbow" joint="elbow" kp="20" ctrlrange="-1 1"/>
    <general name="slide" joint="slide" gainprm="5" biasprm="0 -1 0" forcerange="-3 3"/>
  </actuator>
  <sensor>
    <jointpos joint="shoulder" noise="0.01"/>
    <framepos objtype="site" objname="hand"/>
  </sensor>
</mujoco>
""",
    # A toy building block whose mass and inertia come from its geoms: a hollow shell of
    # boxes, knobs on top from a default class (a cylinder size that several geoms use),
    # massless collision helpers and a tube of another density; then a body with an
    # explicit inertial. Shell inertia, inertia groups and a mass bound besides.
    "blocks (geom sizes)": """
<mujoco>
  <compiler boundmass="0.0001" inertiagrouprange="0 4"/>
  <default>
    <geom density="700"/>
    <default class="knob">
      <geom type="cylinder" size="0.006 0.003" density="450" margin="0.0002"/>
    </default>
    <default class="knob_helper">
      <geom type="capsule" size="0.004 0.002" mass="0" group="5"/>
    </default>
  </default>
  <worldbody>
    <geom name="ground" type="plane" size="1 1 0.1"/>
    <body name="block" pos="0 0 0.1">
      <freejoint/>
      <geom name="top" type="box" size="0.016 0.008 0.001" pos="0 0 0.009" mass="0"/>
      <geom name="side_a" type="box" size="0.016 0.001 0.009" pos="0 0.007 0"/>
      <geom name="side_b" type="box" size="0.016 0.001 0.009" pos="0 -0.007 0"/>
      <geom name="end_a" type="box" size="0.001 0.008 0.009" pos="0.015 0 0"/>
      <geom name="end_b" type="box" size="0.001 0.008 0.009" pos="-0.015 0 0"/>
      <geom name="knob_1" class="knob" pos="0.008 0.004 0.012"/>
      <geom name="knob_2" class="knob" pos="-0.008 0.004 0.012"/>
      <geom name="knob_3" class="knob" pos="0.008 -0.004 0.012"/>
      <geom name="knob_4" class="knob" pos="-0.008 -0.004 0.012"/>
      <geom name="helper_1" class="knob_helper" pos="0.008 0.004 0.013" euler="0 90 0"/>
      <geom name="helper_2" class="knob_helper" pos="-0.008 0.004 0.013" euler="0 90 0"/>
      <geom name="tube" type="cylinder" size="0.003 0.008" density="300"/>
      <geom name="bead" type="ellipsoid" size="0.002 0.003 0.004" pos="0 0 -0.004"/>
      <geom name="pip" type="sphere" size="0.002" pos="0.01 0 -0.004" shellinertia="true"/>
    </body>
    <body name="weighted" pos="0.1 0 0.1">
      <joint name="hinge" axis="0 1 0"/>
      <inertial pos="0 0 0.01" mass="0.3" diaginertia="0.001 0.001 0.0005"/>
      <geom name="weight_box" type="box" size="0.02 0.02 0.01"/>
      <geom name="weight_knob" class="knob" pos="0 0 0.012"/>
      <geom name="rod" type="capsule" fromto="0 0 0 0 0 0.05" size="0.004"/>
    </body>
  </worldbody>
</mujoco>
""",
}


@dataclasses.dataclass
class _Record:
    """What the corpus showed for one (tag, attribute) pair.

    A change that `mjcf.model_patch` declines (a value with fewer numbers than the field, a
    value from MuJoCo's built-in default, an actuator's default class) is neither for nor
    against the pair: the patch refuses it at run time too, and the model recompiles.
    """

    changes: int = 0
    declined: int = 0
    plain_failures: int = 0
    failures: int = 0
    differing: set = dataclasses.field(default_factory=set)


def _candidates() -> set[tuple[str, str]]:
    """(tag, attribute) pairs whose attribute is a float and whose field is an MjModel array."""
    pairs = set()
    for spec in schema.all_specs():
        family = FAMILIES.get(spec.namespace or "")
        if family is None:
            continue
        for name, attribute in spec.attributes.items():
            value_type = attribute.type
            if value_type.kind != attribute_types.OTHER:
                continue
            if getattr(value_type, "dtype", None) not in (float, np.float64):
                continue
            ref = family.fields.get(attribute.python_name)
            if ref is not None and ref.struct == MODEL:
                pairs.add((spec.name, name))
    return pairs


def _corpus(extra_models: Path | None = None):
    """Yields (label, RootElement) for every model the proof changes."""
    from manipulation.tasks import registry

    seen = set()
    for name in registry.names():
        root = registry.build_task(name).root_entity.mjcf_model
        xml = root.to_xml_string()
        if xml not in seen:
            seen.add(xml)
            yield name, root
    for label, xml in _SCENES.items():
        yield label, mjcf.from_xml_string(xml)
    for path in sorted(extra_models.glob("*.xml")) if extra_models else ():
        try:
            yield path.name, mjcf.from_path(str(path))
        except (ValueError, OSError) as error:
            print(f"  {path.name}: skipped ({error})", file=sys.stderr)


def _all_elements(root) -> list[Element]:
    """Every element of `root` and of the models attached below it."""
    found = []
    models = [root]
    for model in models:
        found.extend(model._iter_own_tree())
        models.extend(frame._attached for frame in model._frames)
    return found


# The kinds of change the proof makes of each pair, where the model allows.
_ON_ELEMENT = "a value the element or its default classes set"
_ON_TEMPLATE = "a default-class template"
_FROM_UNSET = "a value nothing sets (MuJoCo's built-in default)"


def _variety(element, pair) -> tuple:
    """What sets apart elements of one kind of change that are each worth a change.

    For a geom's size (which feeds its bounds, its body's BVH and its body's inertia): the
    geom's type, whether it is given by `fromto`, and whether its body has an explicit
    inertial; every template. For any other pair, nothing: one element of a kind suffices.
    """
    if pair != ("geom", "size"):
        return ()
    if traversal_utils.is_default_template(element):
        return (id(element),)
    body = element._parent
    type_source = traversal_utils.default_value_source(element, "type")
    return (
        type_source._attributes["type"] if type_source is not None else "sphere",
        traversal_utils.default_value_source(element, "fromto") is not None,
        body._spec.name == "body" and bool(body.get_children("inertial")),
    )


def _sites(root, candidates) -> dict:
    """(tag, attribute) -> {kind: [element, ...]}: the first element of each kind of change
    and each variety (see `_variety`)."""
    sites = {}
    seen = set()
    for element in _all_elements(root):
        if type(element) is not Element:
            # Attachment frames and model roots are never patched (see mjcf.model_patch).
            continue
        tag = element._spec.name
        in_defaults = traversal_utils.is_default_template(element)
        for name in element._spec.attributes:
            if (tag, name) not in candidates:
                continue
            if in_defaults:
                if name not in element._attributes:
                    continue
                kind = _ON_TEMPLATE
            elif traversal_utils.default_value_source(element, name) is None:
                kind = _FROM_UNSET
            else:
                kind = _ON_ELEMENT
            key = (tag, name, kind, _variety(element, (tag, name)))
            if key not in seen:
                seen.add(key)
                sites.setdefault((tag, name), {}).setdefault(kind, []).append(element)
    return sites


def _perturbed(value) -> np.ndarray | float:
    """Another valid value: every component moved towards the middle of [0, 1] and past
    it, each a little further than the one before (so that a range stays a range)."""
    value = np.asarray(value, dtype=np.float64)
    changed = value * 0.75 + 0.125 + 0.05 * np.arange(value.size).reshape(value.shape)
    return float(changed) if changed.ndim == 0 else changed


def _current_value(root, base, element, name: str):
    """The value of attribute `name` that compiles into `element`, or None when it cannot
    be told (then the change is not made)."""
    source = traversal_utils.default_value_source(element, name)
    if source is not None:
        return source._attributes[name]
    python_name = element._spec.attributes[name].python_name
    try:
        binding = mjcf.Physics.from_compiled_mjcf_model(root, base).bind(element)
        return np.array(getattr(binding, python_name), dtype=np.float64)
    except (ValueError, AttributeError):
        return None


def _model_arrays(model: mujoco.MjModel) -> dict[str, bytes]:
    """Every array and size (`ngravcomp`, ...) of `model`, and its structs' fields, as bytes."""
    arrays = {}
    for name in dir(model):
        if name.startswith("_"):
            continue
        value = getattr(model, name)
        if isinstance(value, (np.ndarray, int)):
            arrays[name] = np.asarray(value).tobytes()
    for struct in ("opt", "stat", "vis"):
        arrays.update(_struct_bytes(struct, getattr(model, struct)))
    return arrays


def _struct_bytes(label: str, struct) -> dict[str, bytes]:
    """The fields of a MuJoCo struct (nested ones flattened) as bytes, keyed 'opt.timestep'."""
    found = {}
    for name in dir(struct):
        if name.startswith("_"):
            continue
        value = getattr(struct, name)
        if isinstance(value, (int, float, np.ndarray)):
            found[f"{label}.{name}"] = np.asarray(value).tobytes()
        elif not callable(value) and not isinstance(value, type):
            found.update(_struct_bytes(f"{label}.{name}", value))
    return found


def _data_arrays(model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, bytes]:
    """MjData arrays after a reset and `mj_forward`."""
    mujoco.mj_resetData(model, data)
    mujoco.mj_forward(model, data)
    return {
        name: value.tobytes()
        for name in dir(data)
        if not name.startswith("_") and isinstance(value := getattr(data, name), np.ndarray)
    }


def _scratch_arrays(model: mujoco.MjModel) -> frozenset[str]:
    """The MjData arrays that `mj_forward` leaves unwritten on `model`: those that differ
    between forwards of copies of it.

    Such an array holds what its memory held before, scratch of earlier work with addresses
    among it, which is no function of the model's values. On mujoco 3.3.0, where island
    discovery is off unless enabled, that is the island arrays (`dof_island`,
    `efc_island`, `island_dofind`, `island_efcind`) and `efc_AR_rowadr`/`efc_AR_rownnz`;
    compared as they were, they refused every pair there. Two forwards can leave the same
    scratch by chance, hence several.
    """
    data = mujoco.MjData(model)
    runs = [_data_arrays(copy.copy(model), data) for _ in range(_SCRATCH_RUNS)]
    return frozenset(
        name for name in runs[0] if any(run[name] != runs[0][name] for run in runs[1:])
    )


def _differences(patched: mujoco.MjModel, compiled: mujoco.MjModel) -> list[str]:
    """The MjModel arrays, then the MjData arrays after mj_forward other than the compiled
    model's scratch arrays (see `_scratch_arrays`), that are not identical."""
    model_patched, model_compiled = _model_arrays(patched), _model_arrays(compiled)
    differing = [name for name in model_compiled if model_patched[name] != model_compiled[name]]
    data = mujoco.MjData(compiled)
    data_patched = _data_arrays(patched, data)
    data_compiled = _data_arrays(compiled, data)
    suspects = [name for name in data_compiled if data_patched[name] != data_compiled[name]]
    if suspects:
        scratch = _scratch_arrays(compiled)
        differing += [f"data.{name}" for name in suspects if name not in scratch]
    return differing


def _prove_change(root, base, element, pair, record: _Record) -> None:
    """Changes `pair` on `element`, compares the patched and the compiled models, undoes it."""
    name = pair[1]
    if traversal_utils.is_default_template(element):
        current = element._attributes[name]
    else:
        current = _current_value(root, base, element, name)
        if current is None:
            return
    python_name = element._spec.attributes[name].python_name
    had_value = name in element._attributes
    old = element._attributes.get(name)
    count = root.modification_count
    try:
        setattr(element, python_name, _perturbed(current))
    except ValueError:
        # The compiled value does not fit the attribute (a scalar spread over several rows).
        return
    changes = root.attribute_changes_since(count)
    try:
        compiled = compile_mjcf_model(root)
    except ValueError:
        compiled = None
    record.changes += 1
    if compiled is None:
        record.failures += 1
        record.differing.add("(the changed model does not compile)")
    else:
        outcomes = []
        for set_const in (False, True):
            physics = mjcf.Physics.from_compiled_mjcf_model(root, copy.copy(base))
            if not model_patch.patch_model(
                physics, physics._layout, changes, proven={pair: set_const}
            ):
                record.declined += 1
                break
            outcomes.append(_differences(physics.model.ptr, compiled))
            if not outcomes[-1]:
                break
        if outcomes and outcomes[0]:
            record.plain_failures += 1
        if outcomes and outcomes[-1]:
            record.failures += 1
            record.differing.update(outcomes[-1])
    setattr(element, python_name, old if had_value else None)


def _prove_change_from_unset(root, element, pair, record: _Record) -> None:
    """Like `_prove_change` from a value nothing sets: `element` loses its own value of the
    pair's attribute for the change, if that leaves a value nothing sets."""
    name = pair[1]
    if name not in element._attributes:
        return
    python_name = element._spec.attributes[name].python_name
    old = element._attributes[name]
    setattr(element, python_name, None)
    try:
        if traversal_utils.default_value_source(element, name) is None:
            base = compile_mjcf_model(root)
            _prove_change(root, base, element, pair, record)
    except ValueError:
        pass  # the model needs the value to compile: no such change to make
    finally:
        setattr(element, python_name, old)


def prove(candidates, extra_models: Path | None = None) -> dict[tuple[str, str], _Record]:
    """Runs every change of the corpus (and of the models in `extra_models`); returns what
    each pair showed."""
    records = {pair: _Record() for pair in candidates}
    for label, root in _corpus(extra_models):
        started = time.perf_counter()
        base = compile_mjcf_model(root)
        sites = _sites(root, candidates)
        for pair, kinds in sorted(sites.items()):
            for elements in kinds.values():
                for element in elements:
                    _prove_change(root, base, element, pair, records[pair])
            if _ON_ELEMENT in kinds and _FROM_UNSET not in kinds:
                _prove_change_from_unset(root, kinds[_ON_ELEMENT][0], pair, records[pair])
        changes = sum(len(elements) for kinds in sites.values() for elements in kinds.values())
        print(
            f"  {label}: {changes} changes of {len(sites)} pairs "
            f"in {time.perf_counter() - started:.1f} s",
            file=sys.stderr,
        )
    return records


def _verdicts(records) -> tuple[dict, dict]:
    proven, refused = {}, {}
    for pair, record in sorted(records.items()):
        if record.changes == 0:
            refused[pair] = _NOT_IN_CORPUS
        elif record.changes == record.declined:
            refused[pair] = "declined by mjcf.model_patch wherever the corpus has it"
        elif record.failures:
            shown = sorted(record.differing)
            refused[pair] = ", ".join(shown[:6]) + (" ..." if len(shown) > 6 else "")
        else:
            proven[pair] = record.plain_failures > 0
    return proven, refused


def _table_text(proven: dict, refused: dict) -> str:
    return f'''"""Generated by `python -m mjcf.patch_proof --write`; do not edit by hand.

The (tag, XML attribute) pairs whose compiled fields `mjcf.model_patch` writes in place,
proven bit-identical to a recompile on mujoco {mujoco.__version__} (see `mjcf/patch_proof.py`).
"""

MUJOCO_VERSION = "{mujoco.__version__}"

# (tag, attribute) -> whether mj_setConst must run after the write.
PROVEN: dict[tuple[str, str], bool] = {pprint.pformat(proven, width=90, sort_dicts=True)}

# (tag, attribute) -> why it recompiles: the fields a write cannot make identical, or
# that no model of the proof's corpus has it.
REFUSED: dict[tuple[str, str], str] = {pprint.pformat(refused, width=90, sort_dicts=True)}
'''


def main(argv: list[str] | None = None) -> int:
    """Runs the command with `argv` (default: the process's); returns its exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--write",
        action="store_true",
        help="rewrite the checked-in table mjcf/patchable_attributes.py (maintainers)",
    )
    parser.add_argument(
        "--extra-models",
        type=Path,
        help="a folder of MJCF files to change as well (e.g. dm_control's suite/); a one-off "
        "check: the pairs the table that applies proves must still pass (nothing is written)",
    )
    args = parser.parse_args(argv)
    started = time.perf_counter()
    proven, refused = _verdicts(prove(_candidates(), args.extra_models))
    for pair, set_const in proven.items():
        how = "write, mj_setConst" if set_const else "write"
        print(f"patch      {pair[0]:>12} {pair[1]:<16} {how}")
    for pair, reason in refused.items():
        print(f"recompile  {pair[0]:>12} {pair[1]:<16} {reason}")
    seconds = time.perf_counter() - started
    print(f"{len(proven)} pairs patch, {len(refused)} recompile ({seconds:.0f} s)")
    if args.extra_models:
        table = patch_table.current()
        failing = sorted(set(table.proven if table else ()) - set(proven))
        for pair in failing:
            if refused[pair] != _NOT_IN_CORPUS:
                print(f"proven in the table but failing here: {pair}: {refused[pair]}")
        return 1 if any(refused[pair] != _NOT_IN_CORPUS for pair in failing) else 0
    if args.write:
        _TABLE.write_text(_table_text(proven, refused))
        print(f"wrote {_TABLE}")
        return 0
    if mujoco.__version__ != patchable_attributes.MUJOCO_VERSION:
        path = patch_table.write_cache(proven, refused)
        print(
            f"wrote {path}: the checked-in table is proven on mujoco "
            f"{patchable_attributes.MUJOCO_VERSION}; on this {mujoco.__version__}, later "
            f"processes patch the {len(proven)} pairs proven here"
        )
        return 0
    if proven != patchable_attributes.PROVEN or refused != patchable_attributes.REFUSED:
        print(
            "mjcf/patchable_attributes.py is stale: run `python -m mjcf.patch_proof --write`",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
