"""Whether two compiled models are the same, bit for bit: the test every patch proof applies.

`differences(patched, compiled)` names what differs between a patched model and a fresh
compile: every MjModel array (the name and text buffers too), size and struct field
(`opt`, `vis`, `stat`), then every MjData array after a reset and `mj_forward` from the
same state, leaving out the arrays that `mj_forward` does not write on that model
(`scratch_arrays`). An empty list is the proof that the patch equals the compile.
"""

from __future__ import annotations

import copy

import mujoco
import numpy as np

from mujoco_physics.field_layout import DATA_FIELDS, MODEL_FIELDS

__all__ = ["data_arrays", "differences", "model_arrays", "scratch_arrays"]

# How many forwards of copies of a model tell its scratch arrays (see `scratch_arrays`).
_SCRATCH_RUNS = 6


def model_arrays(model: mujoco.MjModel) -> dict[str, bytes]:
    """Every array (of numbers or characters) and size (`ngravcomp`, ...) of `model`, and
    its structs' fields, as bytes."""
    fields = MODEL_FIELDS.arrays + MODEL_FIELDS.texts + MODEL_FIELDS.scalars
    arrays = {name: np.asarray(getattr(model, name)).tobytes() for name in fields}
    for struct in MODEL_FIELDS.structs:
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


def data_arrays(model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, bytes]:
    """MjData arrays after a reset and `mj_forward`."""
    mujoco.mj_resetData(model, data)
    mujoco.mj_forward(model, data)
    return {name: getattr(data, name).tobytes() for name in DATA_FIELDS.arrays}


def scratch_arrays(model: mujoco.MjModel) -> frozenset[str]:
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
    runs = [data_arrays(copy.copy(model), data) for _ in range(_SCRATCH_RUNS)]
    return frozenset(
        name for name in runs[0] if any(run[name] != runs[0][name] for run in runs[1:])
    )


def differences(patched: mujoco.MjModel, compiled: mujoco.MjModel) -> list[str]:
    """The MjModel arrays, then the MjData arrays after mj_forward (prefixed `data.`) other
    than the compiled model's scratch arrays (see `scratch_arrays`), that are not identical
    between `patched` and `compiled`; empty when the two are the same model."""
    model_patched, model_compiled = model_arrays(patched), model_arrays(compiled)
    differing = [name for name in model_compiled if model_patched[name] != model_compiled[name]]
    data = mujoco.MjData(compiled)
    data_patched = data_arrays(patched, data)
    data_compiled = data_arrays(compiled, data)
    suspects = [name for name in data_compiled if data_patched[name] != data_compiled[name]]
    if suspects:
        scratch = scratch_arrays(compiled)
        differing += [f"data.{name}" for name in suspects if name not in scratch]
    return differing
