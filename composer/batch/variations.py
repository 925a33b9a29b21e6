"""Per-world variation: composer's variators in a batch, each world's values in its own row.

A CPU `composer.Environment` brings its model up to date at every reset: the
`initialize_episode_mjcf` hooks (an `MJCFVariator`) change MJCF attributes, and the changes
proven patchable (`mjcf.patching.model_patch`, with the proofs `mjcf.patching.patch_table`
keeps for the installed MuJoCo, or one made on the model at first use) are written into the
compiled model, followed by `mj_setConst` where the proof says so; the `initialize_episode` hooks (a
`PhysicsVariator`) then write model fields through `physics.bind`. A batch compiles once and
does the same for each world: the initial-state producer that makes a world's episode runs
both hooks on its host physics with that world's generator (`EpisodeModel` for the first),
and the model fields they changed travel with the initial state as the world's rows of
per-world model fields, written at its reset (`composer.batch.state_slots`). `mj_setConst`
therefore runs on the producer, in float64 as on the CPU, for the episodes whose changes
need it, and a reset touches no world but the ones it starts.

Which fields get a row per world is measured once, before the model goes on the device
(`measure`): two probe episodes, with generators of their own, run the hooks on the host
physics, which is then put back as compiled. The compiled fields of the MJCF attributes that
changed, and every field whose values differ between the two probes (derived constants,
`PhysicsVariator` writes), are per-world; fields MuJoCo Warp does not have are left to the
host (`per_world_fields`).

Refused, with NotImplementedError naming the element and attribute (at construction, or
where a producer first meets it): a change of the MJCF model's structure; an attribute whose
change cannot be written in place, with the proof's reason (a change no proof covers is
proven on the host model first, as a CPU environment's reset proves it:
`mjcf.patching.first_use_proof`); a field that varies per world but that MuJoCo Warp shares
between worlds. A refused attribute's message says how to draw it per world instead (a
write of its compiled field in `initialize_episode`; `REFUSAL_DOCS`).

The rule for producers: one producer's MJCF tree serves every world whose episodes it makes,
so each episode must set every attribute that any episode varies (as `MJCFVariator` does: it
draws all its attributes every time); an episode that sets fewer is refused. A variation
that reads the attribute's current value (cumulative noise) would read another world's, and
is not reproduced.
"""

from collections.abc import Mapping
from typing import NamedTuple

import mujoco
import numpy as np

import mjcf
from composer.hooks import EnvironmentHooks
from mjcf import binding
from mjcf.patching import first_use_proof, patch_table
from mjcf.patching.patch_context import context_of
from mujoco_physics import field_layout

__all__ = ["EpisodeModel", "PerWorldFields", "measure", "model_arrays", "per_world_fields"]

#: The seeds of the two probe episodes of `measure`.
PROBE_SEEDS = (0, 1)

_RECOMPILE = "needs a recompile, and a batch compiles its model once"


def model_arrays(model: mujoco.MjModel) -> dict[str, np.ndarray]:
    """A copy of every array of numbers of `model` (`field_layout.MODEL_FIELDS.arrays`),
    by field name."""
    return {name: getattr(model, name).copy() for name in field_layout.MODEL_FIELDS.arrays}


def _unpatchable_reason(changes) -> tuple[object, str, str]:
    """The change of `changes` that recompiles, and why (after the patch said False)."""
    table = patch_table.current()
    for change in changes:
        element, attribute = change
        why = table.pair_verdict((element.tag, attribute))
        if isinstance(why, str):
            if " " not in why.split(",")[0]:
                # The fields the proof found a write in place cannot make equal to a
                # recompile's.
                why = f"what the compiler derives from it differs from a write in place: {why}"
            return element, attribute, f"the proof refuses it: {why}"
    group_reason = first_use_proof.refusal_reason(changes)
    if group_reason is not None:
        refused = set().union(*table.refused_together)
        for change in changes:
            if context_of(change, changes) in refused:
                return change.element, change.attribute, f"the proof refuses it: {group_reason}"
    element, attribute = changes[0]
    described = ", ".join(f"{binding.describe(e)} {a!r}" for e, a in changes)
    return (
        element,
        attribute,
        "the proof does not cover it: mjcf.patching.model_patch cannot write these changes "
        f"in place (a compiled value that is not the attribute's alone): {described}",
    )


#: Where the docs say what to do about a refused variation.
REFUSAL_DOCS = "docs/concepts/batch.md#what-to-do-about-a-refused-variation"


def _refusal(element, attribute: str, reason: str) -> NotImplementedError:
    return NotImplementedError(
        f"{binding.describe(element)} attribute {attribute!r}, changed by "
        f"initialize_episode_mjcf: {_RECOMPILE}; {reason}. {_what_to_do(element, attribute)}"
    )


def _what_to_do(element, attribute: str) -> str:
    """The documented way to draw `attribute` per world without a recompile."""
    spec = element.spec.attributes.get(attribute)
    if spec is None or binding.compiled_field(element, attribute) is None:
        return f"Vary what it compiles into instead (see {REFUSAL_DOCS})"
    return (
        f"To draw it per world, write its compiled value in initialize_episode instead, "
        f"which runs for every world with that world's generator, e.g. "
        f"`physics.bind(element).{spec.python_name} = random_state.uniform(low, high)` or a "
        f"PhysicsVariator bound to the element; what the compiler derives from it then "
        f"stays as compiled, in the CPU environment as in the batch (see {REFUSAL_DOCS})"
    )


class EpisodeModel:
    """Runs the `initialize_episode_mjcf` hooks on a producer and writes what they changed
    into its host physics, as a CPU environment's reset patches its compiled model.

    Args:
      hooks: the `EnvironmentHooks` of the producer's task.
      physics: the host `mjcf.Physics` compiled from `root`, as compiled: changes are
        counted from the moment this is made.
      root: the task's root MJCF model.

    Attributes:
      changes: the (element, XML attribute) pairs written into the model by the last call
        that changed any (`RootElement.attribute_changes_since`).
    """

    def __init__(self, hooks: EnvironmentHooks, physics: mjcf.Physics, root: mjcf.RootElement):
        self._hooks = hooks
        self._physics = physics
        self._root = root
        self._compiled = root.modification_count
        self.changes: tuple = ()

    def __call__(self, random_state: np.random.RandomState) -> None:
        """Runs the hooks with `random_state` and patches the host model, whose varied
        fields the caller has put back as compiled.

        Raises:
          NotImplementedError: for a change that needs a recompile (see the module
            docstring), naming the element and attribute.
        """
        root = self._root
        before = root.modification_count
        self._hooks.initialize_episode_mjcf(random_state)
        episode = root.attribute_changes_since(before)
        changes = root.attribute_changes_since(self._compiled)
        if episode is None or changes is None:
            raise NotImplementedError(
                "initialize_episode_mjcf changed the MJCF model's structure (an element added, "
                f"removed or attached, or another change only a compile resolves): {_RECOMPILE}. "
                "Build every element any episode uses once, and vary its attributes per "
                f"episode (see {REFUSAL_DOCS})"
            )
        if not changes:
            return
        this_episode = set(episode)
        missing = [change for change in changes if change not in this_episode]
        if missing:
            element, attribute = missing[0]
            raise NotImplementedError(
                f"{binding.describe(element)} attribute {attribute!r}: set by "
                "initialize_episode_mjcf in an earlier episode but not in this one; a "
                "batch's worlds share a producer's MJCF tree, so every episode must set every "
                "attribute it varies (as an MJCFVariator does)"
            )
        if not self._physics.apply_attribute_changes(changes):
            raise _refusal(*_unpatchable_reason(changes))
        self.changes = changes


def _compiled_field_origins(changes) -> dict[str, str]:
    """The fields the MJCF `changes` compile into, each with the change that feeds it."""
    origins = {}
    for element, attribute in changes:
        ref = binding.compiled_field(element, attribute)
        if ref is not None:
            origins.setdefault(ref.name, f"{binding.describe(element)} attribute {attribute!r}")
    return origins


def measure(
    hooks: EnvironmentHooks, physics: mjcf.Physics, episode_model: EpisodeModel
) -> dict[str, str]:
    """The model fields that a task's episodes vary per world, each with what varies it.

    Runs two probe episodes (`PROBE_SEEDS`) of the hooks on `physics`, as a producer does,
    then puts its model and data back as they were.

    Args:
      hooks: the `EnvironmentHooks` of the task.
      physics: the task's host `mjcf.Physics`, as compiled (after `after_compile`).
      episode_model: the `EpisodeModel` of `physics`.

    Returns:
      Field name -> a description of its source for messages: the MJCF attribute whose
      compiled field it is, or 'initialize_episode' (a write, or a derived constant).

    Raises:
      NotImplementedError: from `EpisodeModel` for a change that needs a recompile.
    """
    model, data = physics.model.ptr, physics.data.ptr
    compiled = model_arrays(model)
    restore_data = _saved_data(model, data)
    probes = []
    try:
        for seed in PROBE_SEEDS:
            _write_arrays(model, compiled)
            random_state = np.random.RandomState(seed)
            episode_model(random_state)
            with physics.reset_context():
                hooks.initialize_episode(physics, random_state)
            probes.append(model_arrays(model))
    finally:
        _write_arrays(model, compiled)
        restore_data()
    origins = _compiled_field_origins(episode_model.changes)
    first, second = probes
    for name, value in first.items():
        if not np.array_equal(value, second[name], equal_nan=True):
            origins.setdefault(name, "initialize_episode")
    return origins


def _saved_data(model: mujoco.MjModel, data: mujoco.MjData):
    """Saves `data`; returns a function that puts it back as it was."""
    if hasattr(mujoco, "mj_copyData"):
        saved = mujoco.MjData(model)
        mujoco.mj_copyData(saved, model, data)
        return lambda: mujoco.mj_copyData(data, model, saved)
    # Bindings without mj_copyData (mujoco 3.3): the full physics state, and a forward to
    # recompute what derives from it (the data was forwarded when it was saved).
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)

    def restore() -> None:
        mujoco.mj_setState(model, data, state, spec)
        mujoco.mj_forward(model, data)

    return restore


def _write_arrays(model: mujoco.MjModel, arrays: Mapping[str, np.ndarray]) -> None:
    for name, value in arrays.items():
        getattr(model, name)[...] = value


class PerWorldFields(NamedTuple):
    """Where the fields that vary per world live.

    Attributes:
      device: fields MuJoCo Warp batches: one row per world on the device.
      host: fields MuJoCo Warp does not have (user data, some rendering parameters): they
        vary on the producers' host models only.
    """

    device: tuple[str, ...]
    host: tuple[str, ...]


def per_world_fields(
    varied: Mapping[str, str], device_fields: Mapping[str, bool], model: mujoco.MjModel
) -> PerWorldFields:
    """Sorts the fields of `measure` by where they live.

    Args:
      varied: field name -> its source, from `measure`.
      device_fields: MuJoCo Warp's model fields -> whether it can batch them.
      model: the host model (for the fields' dtypes).

    Returns:
      A `PerWorldFields`.

    Raises:
      NotImplementedError: for a field that MuJoCo Warp shares between worlds, or that
        holds integers, naming it and its source.
    """
    device, host = [], []
    for name, source in varied.items():
        if name not in device_fields:
            host.append(name)
            continue
        if not device_fields[name]:
            raise NotImplementedError(
                f"model field {name!r} (from {source}) varies per world, but MuJoCo Warp "
                "shares it between worlds"
            )
        if not np.issubdtype(getattr(model, name).dtype, np.floating):
            raise NotImplementedError(
                f"model field {name!r} (from {source}) varies per world, but it holds "
                "integers and a world's row can only hold floats"
            )
        device.append(name)
    return PerWorldFields(tuple(device), tuple(host))
