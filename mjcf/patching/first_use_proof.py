"""Proof at first use: a change no proof covers is proven on the model at hand, then patched.

`patch(physics, changes, recompile=...)` is what `mjcf.Physics.apply_attribute_changes`
runs. Each change either has a verdict in the proofs for the installed MuJoCo
(`mjcf.patching.patch_table`: a pair verdict, or a proof of its `PatchContext` made at an
earlier first use, in this process or another) or it is unproven. With every change
proven, the changes are written in place (`mjcf.patching.model_patch`). With some
unproven, the change set is proven on this very model, as the corpus proof proves a change:

1. a copy of the compiled model is patched (a plain write first, then a write followed by
   `mj_setConst`; the first only where the checked-in table, made on another release,
   does not say the pair needs `mj_setConst`: the table is the warm start);
2. the changed MJCF model is recompiled;
3. the two are compared bit for bit (`mjcf.patching.model_comparison`: every MjModel array,
   size and struct, every MjData array after `mj_forward`).

Equal: the unproven contexts are proven (kept with the model's name, `patch_table.record`)
and the Physics is patched. A context of a value set where none was proves the same context
of a value replacing another (so a reset after the first one, which sets what the model left
unset, does not prove again); not the reverse. Different: the contexts that were unproven
are refused together, with one warning per process naming them and the fields that differ,
and the caller recompiles, as it does whenever this returns False. So the first reset that
needs an unproven context costs one compile more than the recompile it replaces at most
(none when the proof passes: its compile replaces the recompile), and every later change in
a proven context patches. A change the patch declines (a value with fewer numbers than the
field, a free body's pose, ...) proves nothing and compiles nothing here.

What a proof promises: the contexts it proved, on every model (see
`mjcf.patching.patch_context`); a change in another context is proven again.
"""

from __future__ import annotations

import copy
import hashlib
import warnings
from collections.abc import Callable

import mujoco

from mjcf.element import AttributeChanges
from mjcf.patching import model_comparison, model_patch, patch_table, patchable_attributes
from mjcf.patching.geom_size_cache import SizePatchCache
from mjcf.patching.patch_context import PatchContext, context_of

__all__ = ["patch", "refusal_reason"]

Pair = tuple[str, str]
# The groups of contexts this process has warned about.
_WARNED: set[frozenset[PatchContext]] = set()
# How many differing fields a refusal names.
_FIELDS_SHOWN = 6


class _Coverage:
    """What the proofs say of a change set: the pairs' `mj_setConst` flags where proven,
    the contexts unproven, or the reason one change recompiles."""

    __slots__ = ("proven", "unproven", "refused", "by_group")

    def __init__(self, table: patch_table.ProvenTable, changes):
        self.proven: dict[Pair, bool] = {}
        self.unproven: dict[PatchContext, None] = {}
        self.refused: str | None = None
        # Whether `refused` is that of contexts that failed their proof together.
        self.by_group = False
        for change in changes:
            element, attribute = change
            pair = (element._spec.name, attribute)
            verdict = table.pair_verdict(pair)
            if isinstance(verdict, str):
                self.refused = f"the proof refuses <{pair[0]}> {pair[1]!r}: {verdict}"
                return
            if verdict is None:
                if not isinstance(changes, AttributeChanges):
                    self.refused = "its context cannot be told (not from attribute_changes_since)"
                    return
                context = context_of(change, changes)
                verdict = table.context_verdict(context)
                if verdict is None:
                    self.unproven[context] = None
                    continue
            self.proven[pair] = self.proven.get(pair, False) or verdict
        group = table.refusal_of(self.unproven)
        if group is not None:
            self.refused = (
                f"a write in place differs from a recompile of {group.models[0]}: {group.why}"
            )
            self.by_group = True


def patch(
    physics,
    changes,
    *,
    cache: SizePatchCache | None,
    recompile: Callable[[object], mujoco.MjModel],
) -> bool:
    """Writes `changes` into `physics`'s model, proving first what no proof covers.

    Args:
      physics: an `mjcf.Physics` whose model is the compile of its MJCF model as it was
        before `changes`.
      changes: `AttributeChanges` of that model (`RootElement.attribute_changes_since`).
      cache: `physics`'s size-patch look-ups (`mjcf.patching.geom_size_cache`).
      recompile: MJCF root -> a fresh compile (`mjcf.physics.compile_mjcf_model`).

    Returns:
      As `model_patch.patch_model`: True when the model now equals a fresh compile; False,
      having changed nothing, when a change recompiles (refused, declined, or failing its
      proof now).
    """
    coverage = _Coverage(patch_table.current(), changes)
    if coverage.unproven and coverage.refused is None:
        # Another process may have proven them since this one read the cache.
        coverage = _Coverage(patch_table.refresh(), changes)
    if coverage.refused is not None:
        if coverage.by_group:
            _warn_once(coverage.unproven, coverage.refused)
        return False
    if not coverage.unproven:
        return model_patch.patch_model(physics, changes, cache=cache, proven=coverage.proven)
    return _prove_and_patch(physics, changes, coverage, cache, recompile)


def refusal_reason(changes) -> str | None:
    """Why `changes` recompile by the proofs known now (a refused pair, or contexts that
    failed their proof together), or None when nothing refuses them."""
    return _Coverage(patch_table.current(), changes).refused


def _prove_and_patch(physics, changes, coverage: _Coverage, cache, recompile) -> bool:
    root = physics.mjcf_model
    base = physics.model.ptr
    unproven = list(coverage.unproven)
    unproven_pairs = {context.pair for context in unproven}
    compiled = None
    differing: list[str] = []
    for set_const in _trials(unproven_pairs):
        trial = dict(coverage.proven)
        for pair in unproven_pairs:
            trial[pair] = trial.get(pair, False) or set_const
        candidate = type(physics).from_compiled_mjcf_model(root, copy.copy(base))
        try:
            if not model_patch.patch_model(candidate, changes, proven=trial):
                return False  # declined: the caller recompiles, and nothing is learnt
            if compiled is None:
                try:
                    compiled = recompile(root)
                except ValueError:
                    return False  # the caller's recompile raises MuJoCo's error
            differing = model_comparison.differences(candidate.model.ptr, compiled)
        finally:
            candidate.free()
        if not differing:
            patch_table.record(dict.fromkeys(_implied(unproven), set_const), {}, _model_label(root))
            return model_patch.patch_model(physics, changes, cache=cache, proven=trial)
    shown = ", ".join(differing[:_FIELDS_SHOWN])
    shown += " ..." if len(differing) > _FIELDS_SHOWN else ""
    label = _model_label(root)
    patch_table.record({}, {frozenset(unproven): shown}, label)
    _warn_once(unproven, f"a write in place differs from a recompile of {label}: {shown}")
    return False


def _implied(contexts: list[PatchContext]) -> list[PatchContext]:
    """`contexts` and what their proof proves besides: a value set where none was, written
    as a recompile writes it, proves a value replacing another in the same context (the
    second write replaces the first's fields; not the reverse: a control range set where
    none was also limits the actuator)."""
    replacing = [context._replace(from_unset=False) for context in contexts if context.from_unset]
    return list(dict.fromkeys(contexts + replacing))


def _trials(pairs: set[Pair]) -> tuple[bool, ...]:
    """The `mj_setConst` flags to try: a plain write first unless the checked-in table
    (proven on some release) says every one of `pairs` needs `mj_setConst`."""
    if all(patchable_attributes.PROVEN.get(pair) for pair in pairs):
        return (True,)
    return (False, True)


def _model_label(root) -> str:
    """'name (sha1 prefix of its XML)': which model a proof was made on."""
    digest = hashlib.sha1(root.to_xml_string().encode("utf-8")).hexdigest()[:10]
    return f"{root.model} ({digest})"


def _warn_once(contexts, reason: str) -> None:
    """Warns, once per process for a set of contexts, that changing them recompiles."""
    group = frozenset(contexts)
    if group in _WARNED:
        return
    _WARNED.add(group)
    described = "; ".join(context.describe() for context in sorted(group))
    warnings.warn(
        f"mjcf: changing {described} recompiles the model on mujoco {mujoco.__version__}: "
        f"{reason}. Resets that change it take as long as a compile",
        RuntimeWarning,
        stacklevel=2,
    )
