"""`ResetState`: the MjData that `Physics.reset()` leaves, kept to be copied back.

`Physics.reset()` resets the data (`mj_resetData`) and runs forward with actuation
disabled. What that leaves in MjData is a function of the model alone, unless code outside
the model takes part: a plugin (its state is reset by its own code) or a global callback
(`mujoco.set_mjcb_passive`, ...). So while the model is unchanged in every field
`mj_forward` reads, copying the data the last reset left (`mj_copyData`, a few µs) gives
the same bytes as resetting again (tens to hundreds of µs: the forward).

Whether the model is unchanged is for the owner to say: it calls `invalidate()` whenever
the model may have changed in a field `mj_forward` reads since the last `reset`.
`mjcf.patching.compiled_model.CompiledModel` does, and its class docstring states when: its
updates restore the model's parameters from a `ModelSnapshot`, so the model each reset
starts from is known.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco

if TYPE_CHECKING:
    # For the annotation only: the engine names this module in its own annotations.
    from mujoco_physics.engine import Physics

__all__ = ["ResetState"]

# Bindings without mj_copyData (mujoco 3.3) cannot copy one MjData into another: every
# reset is computed there.
_CAN_COPY = hasattr(mujoco, "mj_copyData")
# MuJoCo's global callbacks, found in the installed bindings by their getters' names.
_CALLBACK_GETTERS = tuple(
    getattr(mujoco, name) for name in sorted(dir(mujoco)) if name.startswith("get_mjcb_")
)


def _outside_code_takes_part(model: mujoco.MjModel) -> bool:
    return bool(model.nplugin) or any(get() is not None for get in _CALLBACK_GETTERS)


def _may_keep(model: mujoco.MjModel, data: mujoco.MjData) -> bool:
    """Whether what a reset left in `data` may be copied back later: the bindings can copy,
    no code outside the model took part, and the forward did not warn (resetting again
    must warn, or raise, again)."""
    return _CAN_COPY and not _outside_code_takes_part(model) and not data.warning.number.any()


class ResetState:
    """Resets a Physics as `Physics.reset()` does, copying the data of the last reset
    instead of recomputing it while that is exact.

    The kept data belongs to one MjModel object: a reset of a Physics with another model
    (a recompile) resets afresh. Data is kept from the second reset of a model on, so a
    model that is reset once (a task whose structure changes every episode) costs no
    MjData of its own. Once kept data was invalidated unused, resets that follow an
    invalidation keep nothing (a model changed before every reset, such as one patched
    every episode, costs no copies) until a reset follows none, or kept data is used. A
    reset whose forward warned keeps nothing, so the next one raises (or logs) the warning
    again; with bindings that lack `mj_copyData` (mujoco 3.3) nothing is ever kept.
    """

    __slots__ = ("_model", "_data", "_seen", "_used", "_wasted", "_invalidated")

    def __init__(self):
        self._model: mujoco.MjModel | None = None  # the model `_data` is valid for
        self._data: mujoco.MjData | None = None
        self._seen: mujoco.MjModel | None = None  # the model of the last reset afresh
        self._used = False  # whether `_data` was copied since it was kept
        self._wasted = False  # whether the last kept data was invalidated unused
        self._invalidated = False  # whether `invalidate()` was called since the last reset

    def invalidate(self) -> None:
        """Forgets the kept data: the model may have changed in a field forward reads."""
        if self._model is not None and not self._used:
            self._wasted = True
        self._model = None
        self._invalidated = True

    def reset(self, physics: Physics) -> None:
        """Leaves `physics`'s data as `physics.reset()` would.

        Raises:
          PhysicsError: as `physics.reset()` does, when it resets afresh.
        """
        model = physics.model.ptr
        invalidated, self._invalidated = self._invalidated, False
        if self._model is model and not _outside_code_takes_part(model):
            physics.copy_data_from(self._data)
            self._used, self._wasted = True, False
            return
        self._model = None
        physics.reset()
        first_reset, self._seen = self._seen is not model, model
        if first_reset or (invalidated and self._wasted):
            return
        if not _may_keep(model, physics.data.ptr):
            return
        if self._data is None or self._data.model is not model:
            self._data = mujoco.MjData(model)
        mujoco.mj_copyData(self._data, model, physics.data.ptr)
        self._model, self._used = model, False
