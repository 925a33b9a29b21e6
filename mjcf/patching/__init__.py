"""Model patching: a compiled model kept equal, bit for bit, to a fresh compile of its MJCF
model, without compiling it at every reset.

Start at `compiled_model.CompiledModel`: its class docstring is the contract (which of four
ways a reset takes, and when the reset data is reused). The rest of the package is what it
stands on. From an MJCF change to the model a reset starts from:

1. The element tree records what changed: `RootElement.attribute_changes_since(count)`
   (`mjcf.element`) gives the (element, attribute) pairs set since a modification count,
   or None after a structural change.
2. Which attributes may patch is proven, not listed by hand: `patch_proof` changes each
   candidate attribute on real models, patches one copy, recompiles another and requires
   every MjModel array and every MjData array after `mj_forward` to be bit-identical. Its
   verdicts for one MuJoCo release are the generated table `patchable_attributes`
   (`python -m manipulation.patch_proof` gathers the task suite's models, runs the proof,
   and, on the table's release, fails when the table is stale). On any release, a change no
   proof covers is proven at its first use on the model at hand (`first_use_proof`: patch a
   copy, recompile, compare with `model_comparison`), per `patch_context.PatchContext` (the
   kind of change, where it is set, and what else changes how it compiles); `patch_table`
   says which proofs apply to the installed MuJoCo (the table on its release, the corpus
   command's cache, the proofs made at first use) and keeps them in a per-release cache
   that concurrent processes share.
3. `CompiledModel.update(root)`, once per reset, takes the cheapest exact way: RESTORED
   (nothing changed), PATCHED (only proven attributes changed: `model_patch`, through
   `mjcf.Physics.apply_attribute_changes` and `first_use_proof`), LOADED (recompiled, same
   structure: the new parameters written into the current model) or NEW_PHYSICS
   (recompiled).
4. The patch: `model_patch` writes each changed attribute's compiled value into its
   field, runs `mj_setConst` where the table says so, then recomputes what the compiler
   derives and `mj_setConst` does not (the model statistics: `model_statistics`). A
   primitive geom's `size` feeds more fields (bounds, its body's bounding volumes and
   inertia): `geom_size_patch` takes them from MuJoCo's own compiler run on
   `geom_body_copies` (copies of the changed bodies alone), and `geom_size_cache` keeps, per
   Physics, what those patches looked up.
5. The snapshot: `model_snapshot.ModelSnapshot` saves the model's parameters after each
   update, writes them back at the next (undoing writes through `physics.bind`), and
   takes a recompile's parameters in place when the structure is the same (LOADED).
   The reset data a reset leaves is kept by `mujoco_physics.reset_state.ResetState`,
   which stays in the engine layer because `Physics.reset_context` takes it; colours and
   materials, which `mj_forward` never reads (`mjcf.appearance`), keep it valid.

Which module answers which question:

- `compiled_model`: how does a reset make the model current, and may it reuse the last
  reset's data?
- `patch_proof`: how is an attribute proven patchable?
- `patchable_attributes`: which (tag, attribute) pairs are proven, on which MuJoCo, and
  why each refused one recompiles?
- `patch_table`: which proofs apply to the installed MuJoCo, and where and how are they
  cached?
- `first_use_proof`: what does a reset do with a change no proof covers yet?
- `patch_context`: what does a proof on one model promise for a change on another?
- `model_comparison`: when are a patched model and a recompile the same, bit for bit?
- `model_patch`: which changes can be written in place, and how?
- `geom_size_patch`: which fields does a primitive geom's size change besides `geom_size`?
- `geom_body_copies`: how does MuJoCo's compiler give those fields for a few bodies?
- `geom_size_cache`: what do size patches of one compiled model remember?
- `model_statistics`: how is `MjModel.stat` recomputed after a patch?
- `model_snapshot`: how are a compiled model's parameters saved, restored and replaced in
  place?

Users: `composer.Environment` (one `CompiledModel`, updated at every reset),
`composer.batch.variations` (patches on the host physics that makes each world's episode),
and `manipulation.patch_proof` (the proof command, on the task suite's models). The tests
are in `tests/mjcf/patching/`.

This package's `__init__` imports nothing: `mjcf.physics` imports `model_patch`, and
`compiled_model` builds on `mjcf.physics`, so import the modules themselves:
`from mjcf.patching.compiled_model import CompiledModel`.
"""
