"""``mjcf.Physics``: a compiled MJCF model and its simulation state, as in dm_control."""

import contextlib
import copy as copy_module
import re
from collections.abc import Iterator

import mujoco
import numpy as np
from absl import logging

from mjcf import binding as binding_module
from mjcf import named_indexing
from mjcf.appearance import forward_neutral_fields
from mjcf.field_layout import ModelLayout
from mjcf.rendering import Renderers
from mjcf.struct_wrappers import DataWrapper, ModelWrapper, flags_set

# The message of the error that pickling a bound array raises, under the name dm_control's
# tests read it from.
_PICKLING_NOT_SUPPORTED = binding_module.PICKLING_NOT_SUPPORTED

_WARNING_NAMES = tuple(name for name in mujoco.mjtWarning.__members__ if name != "mjNWARNING")
_RK4 = int(mujoco.mjtIntegrator.mjINT_RK4)
_ACTUATION_DISABLED = int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
_STATE_SIGNATURE = int(mujoco.mjtState.mjSTATE_PHYSICS)
_STATE_SIGNATURE_WITH_PLUGINS = _STATE_SIGNATURE | int(mujoco.mjtState.mjSTATE_PLUGIN)
_LINE_NUMBER = re.compile(r"\bline (\d+)")
_ELEMENT_NAME = re.compile(r"Element name '([^']*)'")
_XML_NAME = re.compile(r"""\bname=["']([^"']*)["']""")
_MAX_QUOTED_XML = 500
# The name under which MJB bytes are handed to MuJoCo in a one-file virtual file system.
_MJB_NAME = "model.mjb"

# dm_control's name for the binding class, which code may construct or check against.
Binding = binding_module.Binding


def _log_mujoco_warning(message: str) -> None:
    logging.warning("MuJoCo warning: %s", message)


# MuJoCo's default handler appends warnings to MUJOCO_LOG.TXT in the working directory;
# route them to logging instead, unless the user installed a handler of their own.
if mujoco.get_mju_user_warning() is None:
    mujoco.set_mju_user_warning(_log_mujoco_warning)


class PhysicsError(RuntimeError):
    """Raised when the simulation diverges (MuJoCo warnings such as bad qacc)."""


class _Simulation:
    """Model, data and the flags shared by a Physics and its bindings.

    Kept apart from ``Physics`` so that bindings can run ``forward()`` without holding a
    reference to the Physics (no reference cycle keeps a discarded simulation alive).
    """

    __slots__ = (
        "model",
        "data",
        "opt",
        "warnings",
        "dirty",
        "raise_on_warnings",
        "forward_neutral",
    )

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData):
        self.model = model
        self.data = data
        self.opt = model.opt
        self.warnings = data.warning.number
        self.dirty = False
        self.raise_on_warnings = True
        # MjModel fields whose writes leave derived quantities valid (see mjcf.appearance).
        self.forward_neutral = forward_neutral_fields(model)

    def forward(self) -> None:
        before = self.warnings.tobytes()
        mujoco.mj_forward(self.model, self.data)
        self.dirty = False
        if self.warnings.tobytes() != before:
            self.report_warnings(before)

    def report_warnings(self, before: bytes) -> None:
        """Raises PhysicsError (or logs) for warning counters that grew since ``before``."""
        previous = np.frombuffer(before, dtype=self.warnings.dtype)
        raised = [name for name, grew in zip(_WARNING_NAMES, self.warnings > previous) if grew]
        if not raised:
            return
        message = f"Physics state is invalid. Warning(s) raised: {', '.join(raised)}"
        if self.raise_on_warnings:
            raise PhysicsError(message)
        logging.warning(message)


class Physics:
    """A compiled MuJoCo model with its simulation data, API-compatible with dm_control.

    Construct it with ``from_mjcf_model``, ``from_xml_string``, ``from_xml_path`` or
    ``from_model``. ``model`` and ``data`` expose every MjModel/MjData field as NumPy views
    (``.ptr`` gives the raw ``mujoco`` objects); ``named`` indexes fields by object name;
    ``bind(element)`` gives the fields of MJCF elements as attributes.

    ``step(nstep)`` advances the simulation. With ``legacy_step`` True (the default) it runs
    ``mj_step2``, then ``mj_step(nstep - 1)``, then ``mj_step1``, so position- and
    velocity-dependent quantities (xpos, sensordata of position sensors, ...) describe the
    state after the step; with RK4 it runs ``mj_step(nstep)`` then ``mj_step1``. With
    ``legacy_step`` False it runs ``mj_step(nstep)``. ``step(k)`` equals ``k`` calls to
    ``step()``. Any method that runs MuJoCo raises ``PhysicsError`` when MuJoCo reports a
    divergence warning during it, unless inside ``suppress_physics_errors()``.
    """

    legacy_step = True

    def __init__(self, data: mujoco.MjData):
        """Wraps ``data`` (a ``mujoco.MjData`` or a ``DataWrapper``) and runs forward."""
        self._initialize(getattr(data, "ptr", data), None)

    def _initialize(self, data: mujoco.MjData, mjcf_model) -> None:
        self._load(data, mjcf_model)
        try:
            self.after_reset()
        except PhysicsError as error:
            logging.warning(str(error))

    def _load(self, data: mujoco.MjData, mjcf_model) -> None:
        model = data.model
        self._sim = _Simulation(model, data)
        self._model = ModelWrapper(model)
        self._data = DataWrapper(data, self._model)
        self._layout = ModelLayout(model)
        self._mjcf_model = mjcf_model
        self._bindings = {(): binding_module.EMPTY_BINDING}
        self._named = None
        self._renderers = None
        self._ctrl = data.ctrl
        self._state_signature = _STATE_SIGNATURE_WITH_PLUGINS if model.nplugin else _STATE_SIGNATURE
        self._state_size = mujoco.mj_stateSize(model, self._state_signature)

    # Constructors.

    @classmethod
    def from_model(cls, model: mujoco.MjModel) -> "Physics":
        """A Physics with fresh data for ``model`` (a ``mujoco.MjModel`` or ModelWrapper)."""
        return cls(mujoco.MjData(getattr(model, "ptr", model)))

    @classmethod
    def from_xml_string(cls, xml_string: str, assets: dict | None = None) -> "Physics":
        """Compiles an MJCF string; ``assets`` maps file names used in it to their bytes."""
        return cls.from_model(mujoco.MjModel.from_xml_string(xml_string, assets=assets))

    @classmethod
    def from_xml_path(cls, file_path: str) -> "Physics":
        """Compiles the MJCF file at ``file_path``."""
        return cls.from_model(mujoco.MjModel.from_xml_path(str(file_path)))

    @classmethod
    def from_binary_path(cls, file_path: str) -> "Physics":
        """Loads a compiled MJB model file."""
        return cls.from_model(mujoco.MjModel.from_binary_path(str(file_path)))

    @classmethod
    def from_byte_string(cls, byte_string: bytes) -> "Physics":
        """Loads a compiled model from MJB bytes (what ``mujoco.mj_saveModel`` writes).

        Raises:
          ValueError: if ``byte_string`` is not a MuJoCo model binary.
        """
        try:
            model = mujoco.MjModel.from_binary_path(_MJB_NAME, {_MJB_NAME: bytes(byte_string)})
        except ValueError as error:
            raise ValueError(
                f"Physics.from_byte_string: byte_string ({len(byte_string)} bytes) is not a "
                f"MuJoCo model binary (MJB) that this MuJoCo can load: {error}"
            ) from None
        return cls.from_model(model)

    @classmethod
    def from_mjcf_model(cls, mjcf_model) -> "Physics":
        """Compiles an ``mjcf.RootElement`` (its XML and assets) into a new Physics.

        Raises:
          ValueError: when MuJoCo rejects the model; the message names the offending
            element and quotes its XML where MuJoCo's message identifies it.
        """
        return cls.from_compiled_mjcf_model(mjcf_model, compile_mjcf_model(mjcf_model))

    @classmethod
    def from_compiled_mjcf_model(cls, mjcf_model, model: mujoco.MjModel) -> "Physics":
        """A Physics for ``model``, already compiled from ``mjcf_model`` (see
        ``compile_mjcf_model``), so that ``bind`` accepts the elements of ``mjcf_model``."""
        physics = cls.__new__(cls)
        physics._initialize(mujoco.MjData(model), mjcf_model)
        return physics

    def reload_from_mjcf_model(self, mjcf_model) -> None:
        """Recompiles this Physics from ``mjcf_model``, as ``from_mjcf_model`` would."""
        data = mujoco.MjData(compile_mjcf_model(mjcf_model))
        self._close_renderers()
        self._initialize(data, mjcf_model)

    def reload_from_xml_string(self, xml_string: str, assets: dict | None = None) -> None:
        """Recompiles this Physics from MJCF text, as ``from_xml_string`` would.

        Earlier bindings are dropped; elements of the MJCF model this Physics was built
        from (if any) still bind, by name, to the new model.
        """
        model = mujoco.MjModel.from_xml_string(xml_string, assets=assets)
        self._close_renderers()
        self._initialize(mujoco.MjData(model), self._mjcf_model)

    def reload_from_xml_path(self, file_path: str) -> None:
        """Recompiles this Physics from the MJCF file at ``file_path`` (see
        ``reload_from_xml_string``)."""
        model = mujoco.MjModel.from_xml_path(str(file_path))
        self._close_renderers()
        self._initialize(mujoco.MjData(model), self._mjcf_model)

    # Structures.

    @property
    def model(self) -> ModelWrapper:
        """The MjModel; ``physics.model.ptr`` is the ``mujoco.MjModel``."""
        return self._model

    @property
    def data(self) -> DataWrapper:
        """The MjData; ``physics.data.ptr`` is the ``mujoco.MjData``."""
        return self._data

    @property
    def named(self) -> named_indexing.NamedIndexStructs:
        """``named.model.<field>[name]`` and ``named.data.<field>[name]`` access."""
        if self._named is None:
            self._named = named_indexing.make_struct_indexers(
                self._sim.model, self._sim.data, self._layout
            )
        return self._named

    @property
    def is_dirty(self) -> bool:
        """Whether a binding wrote an input since the last ``forward()``."""
        return self._sim.dirty

    def mark_as_dirty(self) -> None:
        """Makes the next read of a derived quantity through a binding run ``forward()``."""
        self._sim.dirty = True

    # Bindings.

    def bind(self, mjcf_elements):
        """The MuJoCo fields of an MJCF element, or of a sequence of same-kind elements.

        See ``mjcf.binding.Binding``. Bindings are cached: binding the same element, or an
        equal sequence of elements, again returns the same object.

        Returns:
          A ``Binding``; an empty binding for an empty sequence.

        Raises:
          ValueError: ``mjcf_elements`` is None, an element is not part of the model
            compiled into this Physics or is not compiled into a MuJoCo object, or the
            elements are of mixed kinds (mocap and other bodies count as different kinds).
        """
        if mjcf_elements is None:
            raise ValueError("bind expects an mjcf element or a sequence of them, got None")
        key = tuple(mjcf_elements) if type(mjcf_elements) is list else mjcf_elements
        try:
            return self._bindings[key]
        except (KeyError, TypeError):
            return self._new_binding(mjcf_elements)

    def _new_binding(self, mjcf_elements):
        single = hasattr(mjcf_elements, "tag")
        if single:
            key = mjcf_elements
        else:
            try:
                key = tuple(mjcf_elements)
            except TypeError:
                raise ValueError(
                    "bind expects an mjcf element or a sequence of them, got "
                    f"{type(mjcf_elements).__name__}"
                ) from None
            cached = self._bindings.get(key)
            if cached is not None:
                return cached
        new_binding = binding_module.create(self._sim, self._layout, self._mjcf_model, key, single)
        self._bindings[key] = new_binding
        return new_binding

    # Simulation.

    def step(self, nstep: int = 1) -> None:
        """Advances the simulation by ``nstep`` timesteps (see the class docstring)."""
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
        """Recomputes every derived quantity from the state (``mj_forward``)."""
        self._sim.forward()

    def reset(self, keyframe_id: int | None = None) -> None:
        """Resets the data to the model defaults, or to keyframe ``keyframe_id``, then
        runs forward with actuation disabled.

        Raises:
          ValueError: if ``keyframe_id`` is not in [0, nkey).
        """
        sim = self._sim
        if keyframe_id is None:
            mujoco.mj_resetData(sim.model, sim.data)
        else:
            if not 0 <= keyframe_id < sim.model.nkey:
                raise ValueError(
                    f"keyframe_id {keyframe_id} is out of range: the model has "
                    f"{sim.model.nkey} keyframe(s)"
                )
            mujoco.mj_resetDataKeyframe(sim.model, sim.data, keyframe_id)
        self.after_reset()

    def after_reset(self) -> None:
        """Runs forward with actuation disabled (no meaningful controls exist yet)."""
        with flags_set(self._sim.opt, "disableflags", _ACTUATION_DISABLED):
            self._sim.forward()

    @contextlib.contextmanager
    def reset_context(self) -> Iterator["Physics"]:
        """Resets, yields this Physics for setting the initial state, then runs forward.

        A PhysicsError from the reset itself is ignored (the state is about to be set);
        errors raised inside the block propagate and skip the final forward.
        """
        try:
            self.reset()
        except PhysicsError:
            pass
        yield self
        self.after_reset()

    @contextlib.contextmanager
    def check_invalid_state(self) -> Iterator[None]:
        """Raises PhysicsError at exit if MuJoCo raised a warning inside the block."""
        sim = self._sim
        before = sim.warnings.tobytes()
        yield
        if sim.warnings.tobytes() != before:
            sim.report_warnings(before)

    @contextlib.contextmanager
    def suppress_physics_errors(self) -> Iterator[None]:
        """Inside the block, divergence warnings are logged instead of raised."""
        sim = self._sim
        previous = sim.raise_on_warnings
        sim.raise_on_warnings = False
        try:
            yield
        finally:
            sim.raise_on_warnings = previous

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
        """Sets the actuator controls (``nu`` values)."""
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

    def get_state(self) -> np.ndarray:
        """The physics state: qpos, qvel and act (plus actuator history, plasticity and
        plugin state where the model has them), as one flat array."""
        state = np.empty(self._state_size)
        mujoco.mj_getState(self._sim.model, self._sim.data, state, self._state_signature)
        return state

    def state(self) -> np.ndarray:
        """Same as ``get_state()``."""
        return self.get_state()

    def set_state(self, physics_state) -> None:
        """Restores a state returned by ``get_state()``.

        Raises:
          ValueError: if ``physics_state`` does not have the state's shape.
        """
        state = np.asarray(physics_state, dtype=np.float64)
        if state.shape != (self._state_size,):
            raise ValueError(
                f"physics_state has shape {state.shape}; expected ({self._state_size},) "
                "(qpos, qvel, act, ...)"
            )
        mujoco.mj_setState(self._sim.model, self._sim.data, state, self._state_signature)

    # Copies and resources.

    def copy(self, share_model: bool = False) -> "Physics":
        """A new Physics with a copy of this data; the model is copied unless ``share_model``."""
        # MjData's copy shares its model; its deep copy copies the model too.
        copier = copy_module.copy if share_model else copy_module.deepcopy
        data = copier(self._sim.data)
        new = self.__class__.__new__(self.__class__)
        new._load(data, self._mjcf_model)
        new.legacy_step = self.legacy_step
        return new

    def __getstate__(self) -> dict:
        """What pickling (and ``copy.deepcopy``) keeps: the model and data, with the MJCF
        model compiled into them; bindings and renderers are rebuilt on use."""
        return {
            "data": self._sim.data,
            "mjcf_model": self._mjcf_model,
            "legacy_step": self.legacy_step,
        }

    def __setstate__(self, state: dict) -> None:
        self._load(state["data"], state["mjcf_model"])
        self.legacy_step = state["legacy_step"]

    def free(self) -> None:
        """Releases renderers and MuJoCo structures; the Physics is unusable afterwards.

        Any later use raises an AttributeError that says the Physics was freed.
        """
        self._close_renderers()
        self._bindings = {}
        self._named = None
        del self._sim, self._model, self._data, self._layout, self._ctrl
        self.__class__ = _FreedPhysics

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
    ) -> np.ndarray:
        """Renders a camera view off-screen.

        Args:
          height, width: image size in pixels; at most the model's offscreen buffer size
            (``<visual><global offheight offwidth>``).
          camera_id: camera index or name; -1 is the free camera.
          overlays: must be empty (text overlays are not supported).
          depth: return depth in metres, (H, W) float32.
          segmentation: return (H, W, 2) int32 (object id, mjtObj type); -1 for background.
          scene_option: an optional ``mujoco.MjvOption``.
          render_flag_overrides: optional {flag name or mjtRndFlag: bool} for RGB images.

        Returns:
          (H, W, 3) uint8 RGB unless ``depth`` or ``segmentation``.
        """
        if overlays:
            raise ValueError(f"text overlays are not supported; got {len(overlays)} overlay(s)")
        if self._renderers is None:
            self._renderers = Renderers(self._sim.model)
        return self._renderers.render(
            self._sim.data,
            height,
            width,
            camera_id,
            depth,
            segmentation,
            scene_option,
            render_flag_overrides,
        )


def compile_mjcf_model(mjcf_model) -> mujoco.MjModel:
    """Compiles an ``mjcf.RootElement`` into a ``mujoco.MjModel``.

    Raises:
      ValueError: when MuJoCo rejects the model, naming the offending element.
    """
    xml_string = mjcf_model.to_xml_string()
    try:
        return mujoco.MjModel.from_xml_string(xml_string, mjcf_model.get_assets())
    except ValueError as error:
        raise ValueError(_describe_compile_error(str(error), xml_string)) from error


def _describe_compile_error(message: str, xml_string: str) -> str:
    """MuJoCo's compile error with the offending element's identifier and XML added."""
    message = message.strip()
    line_match = _LINE_NUMBER.search(message)
    name_match = _ELEMENT_NAME.search(message)
    xml_line = None
    if line_match:
        lines = xml_string.splitlines()
        number = int(line_match.group(1))
        if 0 < number <= len(lines):
            xml_line = lines[number - 1].strip()
            if len(xml_line) > _MAX_QUOTED_XML:
                xml_line = xml_line[:_MAX_QUOTED_XML] + " ..."
    identifier = name_match.group(1) if name_match else None
    if identifier is None and xml_line:
        xml_name = _XML_NAME.search(xml_line)
        identifier = xml_name.group(1) if xml_name else None
    parts = ["MuJoCo could not compile the MJCF model"]
    if identifier:
        parts.append(f" at element {identifier!r}")
    parts.append(f": {message}")
    if xml_line:
        parts.append(f"\nOffending XML: {xml_line}")
    return "".join(parts)


class _FreedPhysics(Physics):
    """What a `Physics` becomes once freed: any use but `free()` raises an AttributeError
    that says so (the attributes' own errors stay intact on a live Physics)."""

    def __getattribute__(self, name: str):
        if name == "free" or name.startswith("__"):
            return object.__getattribute__(self, name)
        raise AttributeError(
            f"this Physics was freed (free() was called) and can no longer be used; it has no "
            f"{name!r}"
        )

    def free(self) -> None:
        """Does nothing: the Physics is already freed."""
