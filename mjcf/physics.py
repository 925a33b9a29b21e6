"""`mjcf.Physics`: the engine `Physics` plus `bind` and the constructors from an
`mjcf.RootElement`, as in dm_control."""

import re

import mujoco

from mjcf import binding as binding_module
from mjcf.appearance import changes_are_forward_neutral, forward_neutral_fields
from mjcf.patching import first_use_proof
from mjcf.patching.geom_size_cache import SizePatchCache
from mujoco_physics import engine
from mujoco_physics.engine import PhysicsError
from mujoco_physics.field_layout import ModelLayout

__all__ = ["Binding", "Physics", "PhysicsError", "compile_mjcf_model"]

# The message of the error that pickling a bound array raises, under the name dm_control's
# tests read it from.
_PICKLING_NOT_SUPPORTED = binding_module.PICKLING_NOT_SUPPORTED

_LINE_NUMBER = re.compile(r"\bline (\d+)")
_ELEMENT_NAME = re.compile(r"Element name '([^']*)'")
_XML_NAME = re.compile(r"""\bname=["']([^"']*)["']""")
_MAX_QUOTED_XML = 500

# dm_control's name for the binding class, which code may construct or check against.
Binding = binding_module.Binding
# dm_control compatibility, not our API: its private name, which MoMa imports.
_EmptyBinding = binding_module.EmptyBinding


class _BindableSimulation(engine._Simulation):
    """The engine's simulation plus the MjModel fields whose writes through a binding leave
    derived quantities valid (see `mjcf.appearance`)."""

    __slots__ = ("forward_neutral",)

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData):
        super().__init__(model, data)
        self.forward_neutral = forward_neutral_fields(model)


class Physics(engine.Physics):
    """A compiled MJCF model with its simulation data, API-compatible with dm_control.

    Everything of `mujoco_physics.Physics` (construction from XML, `model`/`data`,
    `named`, stepping, state, rendering), plus `from_mjcf_model` and
    `bind(element)`, which gives the fields of MJCF elements as attributes.
    """

    _mjcf_model = None

    def _load(self, data: mujoco.MjData) -> None:
        # Elements of the MJCF model this Physics was built from (if any) still bind, by
        # name, after a reload from XML.
        super()._load(data)
        self._bindings = {(): binding_module.EMPTY_BINDING}
        self._size_patch_cache = SizePatchCache()

    def _new_simulation(self, model: mujoco.MjModel, data: mujoco.MjData) -> engine._Simulation:
        return _BindableSimulation(model, data)

    @classmethod
    def from_mjcf_model(cls, mjcf_model) -> "Physics":
        """Compiles an `mjcf.RootElement` (its XML and assets) into a new Physics.

        Raises:
          ValueError: when MuJoCo rejects the model; the message names the offending
            element and quotes its XML where MuJoCo's message identifies it.
        """
        return cls.from_compiled_mjcf_model(mjcf_model, compile_mjcf_model(mjcf_model))

    @classmethod
    def from_compiled_mjcf_model(cls, mjcf_model, model: mujoco.MjModel) -> "Physics":
        """A Physics for `model`, already compiled from `mjcf_model` (see
        `compile_mjcf_model`), so that `bind` accepts the elements of `mjcf_model`."""
        physics = cls.__new__(cls)
        physics._mjcf_model = mjcf_model
        physics._reload_from_data(mujoco.MjData(model))
        return physics

    def reload_from_mjcf_model(self, mjcf_model) -> None:
        """Recompiles this Physics from `mjcf_model`, as `from_mjcf_model` would."""
        model = compile_mjcf_model(mjcf_model)
        self._mjcf_model = mjcf_model
        self._reload_from_model(model)

    @property
    def mjcf_model(self):
        """The `mjcf.RootElement` compiled into this Physics, whose elements `bind` accepts;
        None for a Physics built from XML or a binary."""
        return self._mjcf_model

    @property
    def field_layout(self) -> ModelLayout:
        """Which object owns each row of the compiled model's and data's arrays
        (`mujoco_physics.field_layout.ModelLayout`), as `bind` and `named` use it."""
        return self._layout

    @property
    def is_dirty(self) -> bool:
        """Whether a binding wrote an input since the last `forward()`."""
        return self._sim.dirty

    def mark_as_dirty(self) -> None:
        """Makes the next read of a derived quantity through a binding run `forward()`."""
        self._sim.dirty = True

    def bind(self, mjcf_elements) -> Binding:
        """The MuJoCo fields of an MJCF element, or of a sequence of same-kind elements.

        See `mjcf.binding.Binding`. Bindings are cached: binding the same element, or an
        equal sequence of elements, again returns the same object.

        Returns:
          A `Binding`; an empty binding for an empty sequence.

        Raises:
          ValueError: `mjcf_elements` is None, an element is not part of the model
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

    def _new_binding(self, mjcf_elements) -> Binding:
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

    def apply_attribute_changes(self, changes) -> bool:
        """Brings the compiled model up to date with attribute changes, without compiling.

        Args:
          changes: (element, XML attribute name) pairs of the MJCF model this Physics was
            compiled from, changed since that compile
            (`RootElement.attribute_changes_since`).

        Returns:
          True when the model now equals a fresh compile of the changed MJCF model; its
          data is then to be reset, as after a compile. False, having changed nothing, when
          a change is not one that `mjcf.patching.model_patch` can write, or one in a
          context no proof covers fails the proof made of it now on this model
          (`mjcf.patching.first_use_proof`): then recompile.

        What patches look up in the compiled model is kept for the next call, until
        this Physics loads another model (`mjcf.patching.geom_size_cache`).
        """
        return first_use_proof.patch(
            self, changes, cache=self._size_patch_cache, recompile=compile_mjcf_model
        )

    def changes_are_forward_neutral(self, changes) -> bool:
        """Whether every (element, XML attribute name) change compiles only into fields that
        `mj_forward` does not read in this model (`mjcf.appearance.forward_neutral_fields`):
        a colour's, a material's."""
        return changes_are_forward_neutral(changes, self._sim.forward_neutral)

    def __getstate__(self) -> dict:
        """What pickling (and `copy.deepcopy`) keeps: the model and data, with the MJCF
        model compiled into them; bindings and renderers are rebuilt on use."""
        return dict(super().__getstate__(), mjcf_model=self._mjcf_model)

    def __setstate__(self, state: dict) -> None:
        self._mjcf_model = state["mjcf_model"]
        super().__setstate__(state)

    def free(self) -> None:
        """Releases renderers, bindings, size-patch look-ups and MuJoCo structures (see the
        engine's `free`)."""
        self._bindings = {}
        self._size_patch_cache = SizePatchCache()
        super().free()


def compile_mjcf_model(mjcf_model) -> mujoco.MjModel:
    """Compiles an `mjcf.RootElement` into a `mujoco.MjModel`.

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
