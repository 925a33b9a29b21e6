"""`CompiledModel`: a Physics kept, reset after reset, equal to a fresh compile of its model.

This is the one owner of "is the compiled model current, and can the reset data be
reused": the current `mjcf.Physics`, the `ModelSnapshot` of its parameters and the
`ResetState` its resets copy from. `composer.Environment` asks it once per reset.
"""

from __future__ import annotations

import contextlib
import enum

from mjcf.patching.model_snapshot import ModelSnapshot, snapshots_supported
from mjcf.physics import Physics, compile_mjcf_model
from mujoco_physics.reset_state import ResetState

__all__ = ["CompiledModel", "ModelUpdate"]


class ModelUpdate(enum.Enum):
    """How `CompiledModel.update` made the Physics' model equal to a fresh compile."""

    RESTORED = "restored"
    PATCHED = "patched"
    LOADED = "loaded"
    NEW_PHYSICS = "new physics"


class CompiledModel:
    """A `mjcf.Physics` that `update(root)` makes equal, bit for bit, to a fresh compile of
    the MJCF model `root`, by the cheapest of four ways that is exact.

    `update(root)` returns the `ModelUpdate` it took:

    - RESTORED: `root` is the model of the last update and has not changed since. The
      model's parameters saved at the last update are written back, undoing writes made
      through `physics.bind` since.
    - PATCHED: only attribute values of `root` changed, each one that
      `mjcf.patching.model_patch` proved it can write
      (`RootElement.attribute_changes_since`), and `patch` is True. The saved parameters are
      written back, the new values are written into the model in place, and the result is
      saved.
    - LOADED: `root` changed otherwise and is compiled; the new model has the structure
      of the current one (`ModelSnapshot.load`: only float parameters differ), whose
      parameters are replaced by the new ones in place.
    - NEW_PHYSICS: anything else (the first update, an update after `close()`, another
      `root` than last time, a structural change, or a MuJoCo on which snapshots are not
      supported): a new Physics replaces the old one, which is freed.

    Every outcome but NEW_PHYSICS keeps the Physics object, its bindings and its views.
    PATCHED and LOADED tell it that its model changed in place
    (`Physics.model_changed_in_place`): its next render equals that of a fresh compile's
    Physics, its render contexts refreshed only where what they hold of the model
    changed. RESTORED needs no refresh: it gives the model of the last update back, which
    the contexts hold (code that writes the model and uploads it to the contexts itself,
    through `physics.contexts`, uploads again after each reset, as on dm_control's new
    Physics).
    The look-ups that size patches keep go with the Physics
    (`mjcf.patching.geom_size_cache`).

    The reset data is reused: `reset_context()` resets as `Physics.reset()` does, but
    copies the data its last reset left (`mujoco_physics.reset_state`) instead of
    recomputing it while the model is the same, in every field `mj_forward` reads, as at
    that reset. That holds after RESTORED, and after PATCHED when every change is a colour
    or material (`Physics.changes_are_forward_neutral`), unless `model_may_have_changed()`
    was called since the update. After LOADED or NEW_PHYSICS, or another PATCHED, the next
    reset is computed afresh.

    Args:
      patch: whether `update` may patch the model in place; False recompiles every
        changed model.
    """

    __slots__ = ("_patch", "_physics", "_snapshot", "_reset_state", "_compiled_count")

    def __init__(self, *, patch: bool = True):
        self._patch = patch
        self._physics: Physics | None = None
        self._snapshot: ModelSnapshot | None = None
        self._reset_state = ResetState()
        # `root.modification_count` at the last update.
        self._compiled_count: int | None = None

    @property
    def physics(self) -> Physics:
        """The current Physics.

        Raises:
          RuntimeError: before the first `update`, or after `close()`.
        """
        if self._physics is None:
            raise RuntimeError(
                "CompiledModel.physics: there is no Physics before the first update(root) "
                "or after close(); call update(root) first"
            )
        return self._physics

    def update(self, root) -> ModelUpdate:
        """Makes the Physics' model equal to a fresh compile of `root` (see the class).

        Raises:
          ValueError: when MuJoCo rejects `root` (see `compile_mjcf_model`); the current
            Physics stays.
        """
        outcome = self._bring_up_to_date(root)
        self._compiled_count = root.modification_count
        return outcome

    def _bring_up_to_date(self, root) -> ModelUpdate:
        snapshot = self._snapshot
        if snapshot is not None and root is not self._physics.mjcf_model:
            snapshot = None
        if snapshot is not None:
            changes = root.attribute_changes_since(self._compiled_count)
            if changes == ():
                snapshot.restore()
                return ModelUpdate.RESTORED
            if changes and self._patch:
                snapshot.restore()
                if self._physics.apply_attribute_changes(changes):
                    snapshot.save()
                    self._physics.model_changed_in_place()
                    if not self._physics.changes_are_forward_neutral(changes):
                        self._reset_state.invalidate()
                    return ModelUpdate.PATCHED
        self._reset_state.invalidate()
        model = compile_mjcf_model(root)
        if snapshot is not None and snapshot.load(model):
            self._physics.model_changed_in_place()
            return ModelUpdate.LOADED
        physics = Physics.from_compiled_mjcf_model(root, model)
        if self._physics is not None:
            self._physics.free()
        self._physics = physics
        self._snapshot = ModelSnapshot(physics.model.ptr) if snapshots_supported() else None
        return ModelUpdate.NEW_PHYSICS

    def model_may_have_changed(self) -> None:
        """Says that the model may have been written since the last update (by code that
        runs after it, or during an episode not followed by an update): the next reset is
        computed afresh."""
        self._reset_state.invalidate()

    def reset_context(self) -> contextlib.AbstractContextManager[Physics]:
        """`physics.reset_context()`, copying the data of the last reset where the class
        docstring says it may.

        Raises:
          RuntimeError: before the first `update`, or after `close()`.
        """
        return self.physics.reset_context(reset_state=self._reset_state)

    def close(self) -> None:
        """Frees the Physics and forgets the saved parameters and reset data; the next
        `update` gives NEW_PHYSICS. Closing again does nothing."""
        if self._physics is not None:
            self._physics.free()
        self._physics = None
        self._snapshot = None
        self._reset_state = ResetState()
