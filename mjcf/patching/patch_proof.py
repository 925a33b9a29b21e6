"""Proves which attributes `mjcf.patching.model_patch` may write into a compiled model.

The proof takes its models: the command `python -m manipulation.patch_proof [--write]
[--extra-models DIR]` (about half a minute) runs it on the 25 manipulation tasks' models
besides the scenes shipped here (`mjcf/patching/patch_proof_scenes/`, `scene_models`), and
is the one that checks the checked-in table; `main` is that command's body for any other
corpus.

For every candidate (tag, attribute) pair (a float attribute of an element that compiles to
a MuJoCo object, whose binding field of the same name is an MjModel array) and every model
of the corpus that has it, it changes the attribute's value, once on an element once on a
default-class template, and once where nothing set it before (MuJoCo's built-in default
applied), as far as the model has such elements, then patches a copy of the compiled model
with `mjcf.patching.model_patch`, recompiles the changed model, and requires every MjModel
array (the name and text buffers too), size and struct (`opt`, `vis`, `stat`) to be
bit-identical, and every MjData array after `mj_forward` from the same state. A pair is
proven when every change of it in the corpus passed, by a plain write or, failing that, by a
write followed by `mj_setConst`.

Prints one line per pair: how it patches, or why it recompiles (the fields that differ).
On the MuJoCo release the checked-in table `mjcf/patching/patchable_attributes.py` was
proven on, it exits 1 when the proof disagrees with the table, unless `--write`, which
rewrites the table (for the project's maintainers, in a source checkout). On any other
release it saves its pair verdicts in the user's cache directory
(`mjcf.patching.patch_table.cache_path`), beside the proofs made at first use, where every
later process finds them. Nothing needs it there: a change no proof covers is proven at its
first use (`mjcf.patching.first_use_proof`); it only warms a release before its first reset.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import importlib.resources
import itertools
import pprint
import sys
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

import mujoco
import numpy as np

import mjcf
from mjcf import attribute_types, schema, traversal_utils
from mjcf.element import Element
from mjcf.patching import (
    model_comparison,
    model_patch,
    patch_context,
    patch_table,
    patchable_attributes,
)
from mjcf.physics import compile_mjcf_model
from mujoco_physics.field_layout import FAMILIES, MODEL

_NOT_IN_CORPUS = "no model of the corpus has it"
_TABLE = Path(patchable_attributes.__file__)

# Scenes besides the manipulation tasks, one MJCF file each (each says what it covers):
# degree and radian angles, every primitive geom type, masses from geoms and explicit
# inertia, tendons, actuators, equality constraints, lights, cameras, materials, classes.
_SCENE_FOLDER = "patch_proof_scenes"


def _scenes() -> dict[str, str]:
    """The proof's own scenes, shipped with the package: file name -> MJCF text."""
    folder = importlib.resources.files("mjcf.patching") / _SCENE_FOLDER
    files = sorted(
        (entry for entry in folder.iterdir() if entry.name.endswith(".xml")),
        key=lambda entry: entry.name,
    )
    return {entry.name: entry.read_text(encoding="utf-8") for entry in files}


@dataclasses.dataclass
class _Record:
    """What the corpus showed for one (tag, attribute) pair.

    A change that `mjcf.patching.model_patch` declines (a value with fewer numbers than the
    field, a value from MuJoCo's built-in default, an actuator's default class) is neither
    for nor against the pair: the patch refuses it at run time too, and the model
    recompiles.
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


def scene_models() -> Iterator[tuple[str, mjcf.RootElement]]:
    """Yields (file name, RootElement) for each of the proof's own scenes."""
    for label, xml in _scenes().items():
        yield label, mjcf.from_xml_string(xml)


def _folder_models(folder: Path) -> Iterator[tuple[str, mjcf.RootElement]]:
    """Yields (file name, RootElement) for each MJCF file of `folder` that parses."""
    for path in sorted(folder.glob("*.xml")):
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
    """What sets apart elements of one kind of change that are each worth a change: the
    context's variety (`mjcf.patching.patch_context.variety`), and for a geom's size every
    template."""
    if pair == ("geom", "size") and traversal_utils.is_default_template(element):
        return (id(element),)
    return patch_context.variety(element, pair[1])


def _sites(root, candidates) -> dict:
    """(tag, attribute) -> {kind: [element, ...]}: the first element of each kind of change
    and each variety (see `_variety`)."""
    sites = {}
    seen = set()
    for element in _all_elements(root):
        if type(element) is not Element:
            # Attachment frames and model roots are never patched (see
            # mjcf.patching.model_patch).
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
        # Declining it is right (the recompile then raises the compiler's error); writing
        # it would hide a model the compiler refuses, such as a second orientation.
        physics = mjcf.Physics.from_compiled_mjcf_model(root, copy.copy(base))
        if model_patch.patch_model(physics, changes, proven={pair: True}):
            record.failures += 1
            record.differing.add("(the changed model does not compile)")
        else:
            record.declined += 1
    else:
        outcomes = []
        for set_const in (False, True):
            physics = mjcf.Physics.from_compiled_mjcf_model(root, copy.copy(base))
            if not model_patch.patch_model(physics, changes, proven={pair: set_const}):
                record.declined += 1
                break
            outcomes.append(model_comparison.differences(physics.model.ptr, compiled))
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


def prove(
    candidates, models: Iterable[tuple[str, mjcf.RootElement]]
) -> dict[tuple[str, str], _Record]:
    """Runs every change of `candidates` on each (label, RootElement) of `models`; returns
    what each pair showed."""
    records = {pair: _Record() for pair in candidates}
    for label, root in models:
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
            refused[pair] = "declined by mjcf.patching.model_patch wherever the corpus has it"
        elif record.failures:
            shown = sorted(record.differing)
            refused[pair] = ", ".join(shown[:6]) + (" ..." if len(shown) > 6 else "")
        else:
            proven[pair] = record.plain_failures > 0
    return proven, refused


def _table_text(proven: dict, refused: dict) -> str:
    return f'''"""Generated by `{patch_table.PROOF_COMMAND} --write`; do not edit by hand.

The (tag, XML attribute) pairs whose compiled fields `mjcf.patching.model_patch` writes in
place, proven bit-identical to a recompile on mujoco {mujoco.__version__} (see
`mjcf/patching/patch_proof.py`).
"""

MUJOCO_VERSION = "{mujoco.__version__}"

# (tag, attribute) -> whether mj_setConst must run after the write.
PROVEN: dict[tuple[str, str], bool] = {pprint.pformat(proven, width=90, sort_dicts=True)}

# (tag, attribute) -> why it recompiles: the fields a write cannot make identical, or
# that no model of the proof's corpus has it.
REFUSED: dict[tuple[str, str], str] = {pprint.pformat(refused, width=90, sort_dicts=True)}
'''


def main(corpus: Iterable[tuple[str, mjcf.RootElement]], argv: list[str] | None = None) -> int:
    """Runs the proof command on the shipped scenes and `corpus` (pairs of label and
    RootElement, read as the proof reaches them), with `argv` (default: the process's);
    returns its exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--write",
        action="store_true",
        help="rewrite the checked-in table mjcf/patching/patchable_attributes.py (maintainers)",
    )
    parser.add_argument(
        "--extra-models",
        type=Path,
        help="a folder of MJCF files to change as well (e.g. dm_control's suite/); a one-off "
        "check: the pairs the table that applies proves must still pass (nothing is written)",
    )
    args = parser.parse_args(argv)
    started = time.perf_counter()
    models = itertools.chain(
        corpus, scene_models(), _folder_models(args.extra_models) if args.extra_models else ()
    )
    proven, refused = _verdicts(prove(_candidates(), models))
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
            "mjcf/patching/patchable_attributes.py is stale: "
            f"run `{patch_table.PROOF_COMMAND} --write`",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    # The library holds the proof; the corpus that proves the table lives above it.
    sys.exit(f"the patch proof runs as `{patch_table.PROOF_COMMAND}`, on the task suite's models")
