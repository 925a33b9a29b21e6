"""`Physics`: a compiled MuJoCo model and its simulation state, as dm_control's
`dm_control.mujoco.Physics` (which this module serves through the redirect).

This is the engine layer: it knows MuJoCo models and data, named indexing and rendering,
and nothing of MJCF elements. `mjcf.Physics` builds on it and adds `bind` and the
constructors from an `mjcf.RootElement`.
"""

import contextlib
import copy as copy_module
from collections.abc import Iterator
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from absl import logging
from dm_env import specs

from mujoco_physics import index
from mujoco_physics.camera import Camera, CameraMatrices, MovableCamera, Pose, TextOverlay
from mujoco_physics.field_layout import ModelLayout
from mujoco_physics.rendering import (
    BOTH_SEGMENTATION_AND_DEPTH_ENABLED,
    OVERLAYS_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION,
    RENDER_FLAG_OVERRIDES_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION,
    Contexts,
    Renderers,
)
from mujoco_physics.wrapper.core import MjData, MjModel, enable_timer

if TYPE_CHECKING:
    from mujoco_physics.reset_state import ResetState

_WARNING_NAMES = tuple(name for name in mujoco.mjtWarning.__members__ if name != "mjNWARNING")
_RK4 = int(mujoco.mjtIntegrator.mjINT_RK4)
_ACTUATION_DISABLED = int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
_STATE_SIGNATURE = int(mujoco.mjtState.mjSTATE_PHYSICS)
_STATE_SIGNATURE_WITH_PLUGINS = _STATE_SIGNATURE | int(mujoco.mjtState.mjSTATE_PLUGIN)
# dm_control's engine module holds the cameras; code imports them from here.
__all__ = [
    "Camera",
    "CameraMatrices",
    "MovableCamera",
    "Physics",
    "PhysicsError",
    "Pose",
    "TextOverlay",
    "action_spec",
    "invalid_state_message",
]

# Message formats, under the names dm_control's tests read them from.
_BOTH_SEGMENTATION_AND_DEPTH_ENABLED = BOTH_SEGMENTATION_AND_DEPTH_ENABLED
_OVERLAYS_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION = OVERLAYS_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION
_RENDER_FLAG_OVERRIDES_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION = (
    RENDER_FLAG_OVERRIDES_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION
)
_INVALID_PHYSICS_STATE = "Physics state is invalid. Warning(s) raised: {warning_names}"
_KEYFRAME_ID_OUT_OF_RANGE = "keyframe_id {actual} is out of range: expected 0 to {max_valid}"
# The MjData arrays of the default state, in mj_getState's order; those after the first
# three only where the model has them (a release without the array never has them).
_STATE_ARRAYS = ("qpos", "qvel", "act", "history", "plugin_state", "plastic")


def _log_mujoco_warning(message: str) -> None:
    logging.warning("MuJoCo warning: %s", message)


# MuJoCo's default handler appends warnings to MUJOCO_LOG.TXT in the working directory;
# route them to logging instead, unless the user installed a handler of their own.
if mujoco.get_mju_user_warning() is None:
    mujoco.set_mju_user_warning(_log_mujoco_warning)


class PhysicsError(RuntimeError):
    """Raised when the simulation diverges (MuJoCo warnings such as bad qacc).

    Under the dm_control redirect, `dm_control.rl.control.PhysicsError` is this class.
    """


class _Simulation:
    """Model, data and the warning flags shared by a Physics and what it hands out.

    Kept apart from `Physics` so that helpers (`mjcf` bindings) can run `forward()`
    without holding a reference to the Physics (no cycle keeps a discarded one alive).
    """

    __slots__ = ("model", "data", "opt", "warnings", "dirty", "raise_on_warnings")

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData):
        self.model = model
        self.data = data
        self.opt = model.opt
        self.warnings = data.warning.number
        self.dirty = False
        self.raise_on_warnings = True

    def forward(self) -> None:
        before = self.warnings.tobytes()
        mujoco.mj_forward(self.model, self.data)
        self.dirty = False
        if self.warnings.tobytes() != before:
            self.report_warnings(before)

    def report_warnings(self, before: bytes) -> None:
        """Raises PhysicsError (or logs) for warning counters that grew since `before`."""
        previous = np.frombuffer(before, dtype=self.warnings.dtype)
        message = invalid_state_message(previous, self.warnings)
        if message is None:
            return
        if self.raise_on_warnings:
            raise PhysicsError(message)
        logging.warning(message)


def invalid_state_message(before: np.ndarray, after: np.ndarray) -> str | None:
    """The `PhysicsError` message for the MuJoCo warning counters (`MjData.warning.number`)
    that grew from `before` to `after`, or None when none grew."""
    raised = [name for name, grew in zip(_WARNING_NAMES, after > before) if grew]
    if not raised:
        return None
    return _INVALID_PHYSICS_STATE.format(warning_names=", ".join(raised))


class _ResetContext:
    """`Physics.reset_context()`: a class rather than a generator, as it runs at every
    reset (a generator-based context manager costs several times more to enter and exit)."""

    __slots__ = ("_physics", "_reset_state")

    def __init__(self, physics: "Physics", reset_state: "ResetState | None"):
        self._physics = physics
        self._reset_state = reset_state

    def __enter__(self) -> "Physics":
        physics = self._physics
        try:
            if self._reset_state is None:
                physics.reset()
            else:
                self._reset_state.reset(physics)
        except PhysicsError:
            pass
        return physics

    def __exit__(self, kind, value, traceback) -> None:
        if kind is None:
            self._physics.after_reset()


class _ErrorsSuppressed:
    """`Physics.suppress_physics_errors()`, as a class for the reason `_ResetContext` is."""

    __slots__ = ("_sim", "_previous")

    def __init__(self, sim: _Simulation):
        self._sim = sim

    def __enter__(self) -> None:
        sim = self._sim
        self._previous = sim.raise_on_warnings
        sim.raise_on_warnings = False

    def __exit__(self, kind, value, traceback) -> None:
        self._sim.raise_on_warnings = self._previous


class Physics:
    """A compiled MuJoCo model with its simulation data, API-compatible with dm_control.

    Construct it with `from_xml_string`, `from_xml_path`, `from_binary_path`,
    `from_byte_string` or `from_model`. `model` and `data` expose every
    MjModel/MjData field as NumPy views (`.ptr` gives the raw `mujoco` objects);
    `named` indexes fields by object name (`named.data.qpos['hinge']`).

    `step(nstep)` advances the simulation. With `legacy_step` True (the default) it runs
    `mj_step2`, then `mj_step(nstep - 1)`, then `mj_step1`, so position- and
    velocity-dependent quantities (xpos, sensordata of position sensors, ...) describe the
    state after the step; with RK4 it runs `mj_step(nstep)` then `mj_step1`. With
    `legacy_step` False it runs `mj_step(nstep)`. `step(k)` equals `k` calls to
    `step()`. Any method that runs MuJoCo raises `PhysicsError` when MuJoCo reports a
    divergence warning during it, unless inside `suppress_physics_errors()`.

    Example:
        >>> physics = Physics.from_xml_string(
        ...     "<mujoco><worldbody><body><joint name='hinge'/><geom size='.1'/>"
        ...     "</body></worldbody></mujoco>")
        >>> with physics.reset_context():
        ...     physics.named.data.qpos["hinge"] = 0.5
        >>> physics.step()
    """

    legacy_step = True

    def __init__(self, data: MjData | mujoco.MjData):
        """Wraps `data` (a `mujoco.MjData` or a `wrapper.MjData`) and runs forward.

        A divergence warning from that first forward is logged, not raised (the state is
        about to be set).

        Raises:
          PhysicsError: naming the model, when MuJoCo aborts that first forward
            (`mujoco.FatalError`, e.g. arena memory exhausted on some releases).
        """
        self._reload_from_data(data)

    def _reload_from_data(self, data: MjData | mujoco.MjData) -> None:
        """(Re)builds this Physics around `data` and runs forward.

        Every constructor and reload ends here, so a subclass that keeps derived state (as
        dm_control's suite domains do) overrides this method and calls it first.
        """
        self._close_renderers()
        self._load(getattr(data, "ptr", data))
        try:
            self.after_reset()
        except PhysicsError as error:
            logging.warning(str(error))
        except mujoco.FatalError as error:
            # Some releases (3.17) abort the first forward of a model whose arena is too
            # small instead of warning: the model cannot be simulated at all.
            name = self._model.name
            raise PhysicsError(
                f"MuJoCo could not run the first forward of the model "
                f"{repr(name) if name else '(unnamed)'}: {str(error).strip()} (a model that "
                "needs more memory than <size memory=...> gives fails here)"
            ) from error

    def _reload_from_model(self, model: MjModel | mujoco.MjModel) -> None:
        """(Re)builds this Physics with fresh data for `model`."""
        self._reload_from_data(mujoco.MjData(getattr(model, "ptr", model)))

    _renderers = None

    def _load(self, data: mujoco.MjData) -> None:
        model = data.model
        self._sim = self._new_simulation(model, data)
        self._data = MjData(data)
        self._model = self._data.model
        self._layout = ModelLayout(model)
        self._named = None
        self._renderers = None
        self._ctrl = data.ctrl
        self._state_signature = _STATE_SIGNATURE_WITH_PLUGINS if model.nplugin else _STATE_SIGNATURE
        self._state_size = mujoco.mj_stateSize(model, self._state_signature)

    def _new_simulation(self, model: mujoco.MjModel, data: mujoco.MjData) -> _Simulation:
        return _Simulation(model, data)

    # Constructors.

    @classmethod
    def from_model(cls, model: MjModel | mujoco.MjModel) -> "Physics":
        """A Physics with fresh data for `model` (a `mujoco.MjModel` or wrapper.MjModel)."""
        return cls(mujoco.MjData(getattr(model, "ptr", model)))

    @classmethod
    def from_xml_string(cls, xml_string: str, assets: dict | None = None) -> "Physics":
        """Compiles an MJCF string; `assets` maps file names used in it to their bytes."""
        return cls.from_model(MjModel.from_xml_string(xml_string, assets=assets))

    @classmethod
    def from_xml_path(cls, file_path: str) -> "Physics":
        """Compiles the MJCF file at `file_path`."""
        return cls.from_model(MjModel.from_xml_path(file_path))

    @classmethod
    def from_binary_path(cls, file_path: str) -> "Physics":
        """Loads a compiled MJB model file."""
        return cls.from_model(MjModel.from_binary_path(file_path))

    @classmethod
    def from_byte_string(cls, byte_string: bytes) -> "Physics":
        """Loads a compiled model from MJB bytes (what `mujoco.mj_saveModel` writes).

        Raises:
          ValueError: if `byte_string` is not a MuJoCo model binary.
        """
        return cls.from_model(MjModel.from_byte_string(byte_string))

    def reload_from_xml_string(self, xml_string: str, assets: dict | None = None) -> None:
        """Recompiles this Physics from MJCF text, as `from_xml_string` would."""
        self._reload_from_model(MjModel.from_xml_string(xml_string, assets=assets))

    def reload_from_xml_path(self, file_path: str) -> None:
        """Recompiles this Physics from the MJCF file at `file_path`."""
        self._reload_from_model(MjModel.from_xml_path(file_path))

    # Structures.

    @property
    def model(self) -> MjModel:
        """The MjModel; `physics.model.ptr` is the `mujoco.MjModel`."""
        return self._model

    @property
    def data(self) -> MjData:
        """The MjData; `physics.data.ptr` is the `mujoco.MjData`."""
        return self._data

    @property
    def contexts(self) -> "Contexts | None":
        """The rendering contexts, for code that uploads changed assets (heightfields,
        textures) to them; None until something was rendered."""
        return None if self._renderers is None else self._renderers.contexts()

    @property
    def named(self) -> index.NamedIndexStructs:
        """`named.model.<field>[name]` and `named.data.<field>[name]` access."""
        if self._named is None:
            self._named = index.make_struct_indexers(self._sim.model, self._sim.data, self._layout)
        return self._named

    # Simulation.

    def step(self, nstep: int = 1) -> None:
        """Advances the simulation by `nstep` timesteps (see the class docstring)."""
        sim = self._sim
        model, data = sim.model, sim.data
        before = sim.warnings.tobytes()
        if self.legacy_step:
            if sim.opt.integrator != _RK4:
                mujoco.mj_step2(model, data)
                if nstep > 1:
                    mujoco.mj_step(model, data, nstep - 1)
            else:
                mujoco.mj_step(model, data, nstep)
            mujoco.mj_step1(model, data)
        else:
            mujoco.mj_step(model, data, nstep)
        if sim.warnings.tobytes() != before:
            sim.report_warnings(before)

    def forward(self) -> None:
        """Recomputes every derived quantity from the state (`mj_forward`)."""
        self._sim.forward()

    def reset(self, keyframe_id: int | None = None) -> None:
        """Resets the data to the model defaults, or to keyframe `keyframe_id`, then
        runs forward with actuation disabled.

        Raises:
          ValueError: if `keyframe_id` is not in [0, nkey).
        """
        sim = self._sim
        if keyframe_id is None:
            mujoco.mj_resetData(sim.model, sim.data)
        else:
            if not 0 <= keyframe_id < sim.model.nkey:
                raise ValueError(
                    _KEYFRAME_ID_OUT_OF_RANGE.format(
                        actual=keyframe_id, max_valid=sim.model.nkey - 1
                    )
                )
            mujoco.mj_resetDataKeyframe(sim.model, sim.data, keyframe_id)
        self.after_reset()

    def after_reset(self) -> None:
        """Runs forward with actuation disabled (no meaningful controls exist yet)."""
        # What `wrapper.core.flags_set` does, without a generator: this runs at every reset.
        sim = self._sim
        opt = sim.opt
        previous = opt.disableflags
        opt.disableflags = previous | _ACTUATION_DISABLED
        try:
            sim.forward()
        finally:
            opt.disableflags = previous

    def reset_context(
        self, *, reset_state: "ResetState | None" = None
    ) -> contextlib.AbstractContextManager["Physics"]:
        """Resets, yields this Physics for setting the initial state, then runs forward.

        A PhysicsError from the reset itself is ignored (the state is about to be set);
        errors raised inside the block propagate and skip the final forward.

        Args:
          reset_state: a `ResetState` that resets in place of `reset()`, copying the data
            of its last reset while that is exact (see `mujoco_physics.reset_state`).
        """
        return _ResetContext(self, reset_state)

    def copy_data_from(self, data: mujoco.MjData) -> None:
        """Copies `data`, an MjData of this Physics' model, into this Physics' data in place
        (`mj_copyData`); its derived quantities are taken as up to date.

        Raises:
          NotImplementedError: with mujoco bindings that have no `mj_copyData` (3.3).
        """
        if not hasattr(mujoco, "mj_copyData"):
            raise NotImplementedError(
                f"copy_data_from needs mujoco.mj_copyData, which mujoco {mujoco.__version__}'s "
                "bindings do not have"
            )
        sim = self._sim
        mujoco.mj_copyData(sim.data, sim.model, data)
        sim.dirty = False

    @contextlib.contextmanager
    def check_invalid_state(self) -> Iterator[None]:
        """Raises PhysicsError at exit if MuJoCo raised a warning inside the block."""
        sim = self._sim
        before = sim.warnings.tobytes()
        yield
        if sim.warnings.tobytes() != before:
            sim.report_warnings(before)

    def suppress_physics_errors(self) -> contextlib.AbstractContextManager[None]:
        """Inside the block, divergence warnings are logged instead of raised."""
        return _ErrorsSuppressed(self._sim)

    def enable_profiling(self) -> None:
        """Turns on MuJoCo's timers (`data.timer`), as `wrapper.enable_timer(True)`."""
        enable_timer(True)

    # State and controls.

    def time(self) -> float:
        """The simulation time in seconds."""
        return self._sim.data.time

    def timestep(self) -> float:
        """The simulation timestep in seconds."""
        return self._sim.opt.timestep

    def control(self) -> np.ndarray:
        """A copy of the actuator controls."""
        return self._ctrl.copy()

    def set_control(self, control) -> None:
        """Sets the actuator controls (`nu` values)."""
        np.copyto(self._ctrl, control)

    def activation(self) -> np.ndarray:
        """A copy of the actuator activations."""
        return self._sim.data.act.copy()

    def position(self) -> np.ndarray:
        """A copy of the generalized positions (qpos)."""
        return self._sim.data.qpos.copy()

    def velocity(self) -> np.ndarray:
        """A copy of the generalized velocities (qvel)."""
        return self._sim.data.qvel.copy()

    def get_state(self, sig: int | None = None) -> np.ndarray:
        """The physics state as one flat array.

        Args:
          sig: an `mjtState` bit mask for `mj_getState`; by default qpos, qvel and act
            (plus actuator history and plugin state where the model has them).
        """
        signature, size = self._state_layout(sig)
        state = np.empty(size)
        mujoco.mj_getState(self._sim.model, self._sim.data, state, signature)
        return state

    def _state_layout(self, sig: int | None) -> tuple[int, int]:
        """The `mjtState` signature `sig` stands for (the default one for None) and
        the size of its state."""
        if sig is None:
            return self._state_signature, self._state_size
        return int(sig), mujoco.mj_stateSize(self._sim.model, int(sig))

    def _physics_state_items(self) -> list[np.ndarray]:
        """The MjData arrays that `get_state()` concatenates: qpos, qvel, act, then actuator
        history, plugin state and plasticity where the model has them."""
        data = self._sim.data
        arrays = [getattr(data, name, None) for name in _STATE_ARRAYS]
        return arrays[:3] + [a for a in arrays[3:] if a is not None and a.size]

    def state(self) -> np.ndarray:
        """Same as `get_state()`."""
        return self.get_state()

    def set_state(self, physics_state, sig: int | None = None) -> None:
        """Restores a state returned by `get_state(sig)`.

        Raises:
          ValueError: if `physics_state` does not have the state's shape.
        """
        signature, size = self._state_layout(sig)
        state = np.asarray(physics_state, dtype=np.float64)
        if state.shape != (size,):
            raise ValueError(
                f"physics_state has shape {state.shape}; expected ({size},) (qpos, qvel, act, ...)"
            )
        mujoco.mj_setState(self._sim.model, self._sim.data, state, signature)

    # Copies and resources.

    def copy(self, share_model: bool = False) -> "Physics":
        """A new Physics with a copy of this data; the model is copied unless `share_model`."""
        # MjData's copy shares its model; its deep copy copies the model too.
        copier = copy_module.copy if share_model else copy_module.deepcopy
        new = self.__class__.__new__(self.__class__)
        new.__setstate__(dict(self.__getstate__(), data=copier(self._sim.data)))
        return new

    def __getstate__(self) -> dict:
        """What pickling (and `copy.deepcopy`) keeps: model, data and the step mode;
        named indexers and renderers are rebuilt on use."""
        return {"data": self._sim.data, "legacy_step": self.legacy_step}

    def __setstate__(self, state: dict) -> None:
        self._load(state["data"])
        self.legacy_step = state["legacy_step"]

    def free(self) -> None:
        """Releases renderers and MuJoCo structures; the Physics is unusable afterwards.

        Any later use raises an AttributeError that says the Physics was freed.
        """
        self._close_renderers()
        self._named = None
        del self._sim, self._model, self._data, self._layout, self._ctrl
        self.__class__ = _freed_class(type(self))

    def model_changed_in_place(self) -> None:
        """Says that the model's parameters were written in place (by a patch, or the load
        of another compile: `mjcf.patching`): the next render refreshes what the render
        contexts hold of the model where it changed (`rendering.Renderers.model_changed`),
        so that images equal those of a Physics made afresh from the model."""
        if self._renderers is not None:
            self._renderers.model_changed()

    def _offscreen_renderers(self) -> Renderers:
        if self._renderers is None:
            self._renderers = Renderers(self._sim.model)
        return self._renderers

    def _offscreen_renderer(self, height: int, width: int) -> mujoco.Renderer:
        """The renderer (and OpenGL context) of images of this size that `render` and every
        `Camera` of this Physics share."""
        return self._offscreen_renderers().renderer(height, width)

    def _close_renderers(self) -> None:
        if self._renderers is not None:
            self._renderers.close()
            self._renderers = None

    # Rendering.

    def render(
        self,
        height: int = 240,
        width: int = 320,
        camera_id=-1,
        overlays=(),
        depth: bool = False,
        segmentation: bool = False,
        scene_option=None,
        render_flag_overrides=None,
        scene_callback=None,
    ) -> np.ndarray:
        """Renders a camera view off-screen.

        Args:
          height, width: image size in pixels; at most the model's offscreen buffer size
            (`<visual><global offheight offwidth>`).
          camera_id: camera index or name; -1 is the free camera.
          overlays: `TextOverlay`s drawn over an RGB image.
          depth: return depth in metres, (H, W) float32.
          segmentation: return (H, W, 2) int32 (object id, mjtObj type); -1 for background.
          scene_option: an optional `mujoco.MjvOption`.
          render_flag_overrides: optional {flag name or mjtRndFlag: bool} for RGB images.
          scene_callback: optional `f(physics, scene)` called before rendering (to add
            geoms to the scene, say).

        Returns:
          (H, W, 3) uint8 RGB unless `depth` or `segmentation`.

        Raises:
          ValueError: for an unknown camera, an image larger than the offscreen buffer,
            depth with segmentation, or overlays or flag overrides with either.
        """
        if overlays or scene_callback is not None:
            # One-off: a camera of its own can draw text and call back into the scene.
            camera = Camera(self, height, width, camera_id, scene_callback=scene_callback)
            try:
                return camera.render(
                    overlays, depth, segmentation, scene_option, render_flag_overrides
                )
            finally:
                camera.close()
        return self._offscreen_renderers().render(
            self._sim.data,
            height,
            width,
            camera_id,
            depth,
            segmentation,
            scene_option,
            render_flag_overrides,
        )


_FREED_CLASSES: dict[type, type] = {}


def _freed_class(cls: type) -> type:
    """The class a freed instance of `cls` becomes (one per Physics subclass, so that
    `isinstance` checks against the user's subclass still hold)."""
    if cls not in _FREED_CLASSES:
        _FREED_CLASSES[cls] = type(f"Freed{cls.__name__}", (_Freed, cls), {})
    return _FREED_CLASSES[cls]


class _Freed:
    """Mixed in front of a freed Physics: any use but `free()` raises an AttributeError
    that says so (a live Physics's own AttributeErrors keep their messages)."""

    def __getattribute__(self, name: str):
        if name == "free" or name.startswith("__"):
            return object.__getattribute__(self, name)
        raise AttributeError(
            f"this Physics was freed (free() was called) and can no longer be used; it has no "
            f"{name!r}"
        )

    def free(self) -> None:
        """Does nothing: the Physics is already freed."""


def action_spec(physics: Physics) -> specs.BoundedArray:
    """The action spec of `physics`'s actuators: one float64 per actuator, bounded by
    `actuator_ctrlrange` where `actuator_ctrllimited` is set and by +-`mjMAXVAL`
    elsewhere.

    Returns:
      A `dm_env.specs.BoundedArray` of shape `(nu,)`.
    """
    model = physics.model.ptr
    limited = model.actuator_ctrllimited.astype(bool)
    minimum = np.where(limited, model.actuator_ctrlrange[:, 0], -mujoco.mjMAXVAL)
    maximum = np.where(limited, model.actuator_ctrlrange[:, 1], mujoco.mjMAXVAL)
    return specs.BoundedArray(shape=(model.nu,), dtype=float, minimum=minimum, maximum=maximum)
