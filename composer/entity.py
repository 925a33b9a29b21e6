"""Entities: the reusable things a Composer scene is built from (robots, props, arenas)."""

import abc
import weakref

import mujoco
import numpy as np
from absl import logging

import mjcf
from composer import define
from composer.entity_observables import Observables
from composer.observation import observable
from composer.observation.observable.base import view_source

_NOT_ATTACHED = "{entity} is not attached to a parent entity, so it has no attachment frame"
_INIT_NOT_CALLED = (
    "{cls} was never set up by composer.Entity.__init__ (it has no {name!r}): "
    "{init_owner}.__init__ replaces Entity.__init__ without calling it. Build the model in "
    "_build(self, ...), which Entity.__init__ calls with the constructor's arguments, instead "
    "of overriding __init__; or call super().__init__(...) in {init_owner}.__init__"
)


def _first_definer(instance, method: str, base: type) -> str:
    """The name of the first class in `instance`'s MRO, before `base`, that defines `method`."""
    for cls in type(instance).__mro__:
        if cls is base:
            break
        if method in vars(cls):
            return cls.__name__
    return type(instance).__name__


class BuiltAttribute:
    """An attribute that an entity's set-up gives each instance, explained if read before.

    Declared on an `Entity` subclass (`_mjcf_root = BuiltAttribute(hint)`). The instance's
    own attribute of the same name hides it once set; read before that, it raises an
    AttributeError that names the set-up step that never ran and how to fix the subclass,
    instead of "'Stage' object has no attribute '_mjcf_root'":

    - `Entity.__init__` never ran (a subclass overrides `__init__` without calling it);
    - otherwise `hint`, formatted with `cls` (the instance's class), `name` (the attribute)
      and `build_owner` (the subclass whose `_build` overrides the declaring class's).
    """

    def __init__(self, hint: str | None = None):
        self._hint = hint

    def __set_name__(self, owner: type, name: str) -> None:
        self._owner = owner
        self._name = name

    def __get__(self, instance: object, owner: type | None = None) -> "BuiltAttribute":
        if instance is None:
            return self
        # Entity.__init__ sets `_parent` before anything else.
        if self._hint is None or "_parent" not in vars(instance):
            message = _INIT_NOT_CALLED.format(
                cls=type(instance).__name__,
                name=self._name,
                init_owner=_first_definer(instance, "__init__", Entity),
            )
        else:
            message = self._hint.format(
                cls=type(instance).__name__,
                name=self._name,
                build_owner=_first_definer(instance, "_build", self._owner),
            )
        raise AttributeError(message)


class Entity(metaclass=abc.ABCMeta):
    """Something that exists in the world: an MJCF model plus its behaviour and observables.

    Subclasses implement `_build(*args, **kwargs)`, which must create the model that
    the `mjcf_model` property returns, and may override `_build_observables()` to
    return their own `Observables` subclass. The constructor calls `_build` with the
    arguments it was given (except `observable_options`, a dict passed to
    `observables.set_options`), then `_build_observables`.

    Entities form a tree: `attach` puts another entity's model into this one and
    returns the attachment frame (an MJCF body). The environment calls the lifecycle
    hooks (`initialize_episode_mjcf`, `after_compile`, `initialize_episode`,
    `before_step`, `before_substep`, `after_substep`, `after_step`) of every entity
    in the tree that overrides them; the defaults do nothing.

    A subclass customises construction in `_build`, not `__init__`; one that overrides
    `__init__` must call `super().__init__(...)`, or its first use says it never did.
    """

    _parent = BuiltAttribute()
    _attached = BuiltAttribute()
    _observables = BuiltAttribute(
        "{cls}.observables do not exist yet: Entity.__init__ builds them (with "
        "_build_observables) after _build returns, so _build cannot use them; configure them "
        "after construction, or pass observable_options to the constructor"
    )

    def __init__(self, *args, **kwargs):
        self._parent = None
        self._attached = []
        observable_options = kwargs.pop("observable_options", None)
        self._build(*args, **kwargs)
        self._observables = self._build_observables()
        self._observables.set_options(observable_options)

    @abc.abstractmethod
    def _build(self, *args, **kwargs) -> None:
        """Creates this entity's MJCF model; called once by the constructor."""

    def _build_observables(self) -> Observables:
        """Returns this entity's observables container."""
        return Observables(self)

    @property
    @abc.abstractmethod
    def mjcf_model(self):
        """The `mjcf.RootElement` of this entity."""

    @property
    def observables(self) -> Observables:
        """The observables this entity declares (disabled until a task enables them)."""
        return self._observables

    @property
    def parent(self):
        """The entity this one is attached to, or None."""
        return self._parent() if self._parent is not None else None

    @property
    def attachment_site(self):
        """Where `attach` puts children by default: this entity's root model (its worldbody)."""
        return self.mjcf_model

    @property
    def root_body(self):
        """The body carrying this entity: its attachment frame, or its worldbody if unattached.

        The frame is returned whenever the MJCF model is attached, also when that was done
        with `mjcf` directly (`site.attach(entity.mjcf_model)`) rather than `Entity.attach`.
        """
        frame = mjcf.get_attachment_frame(self.mjcf_model)
        return self.mjcf_model.worldbody if frame is None else frame

    def iter_entities(self, exclude_self: bool = False):
        """Yields this entity (unless `exclude_self`) and everything attached below it.

        The order is depth first, children in the order they were attached.
        """
        if not exclude_self:
            yield self
        for child in self._attached:
            yield from child.iter_entities()

    def attach(self, entity: "Entity", attach_site=None):
        """Attaches `entity` rigidly (no joints) and returns its attachment frame.

        Args:
          entity: the entity to attach; it must not already have a parent.
          attach_site: an MJCF site or body of this entity's model (or a site's
            name); defaults to `attachment_site`.

        Raises:
          ValueError: if `entity` is this entity or is already attached, or a site
            named `attach_site` does not exist.
        """
        if entity is self:
            raise ValueError(f"cannot attach {self!r} to itself")
        if entity.parent is not None:
            raise ValueError(
                f"cannot attach {entity!r}: it is already attached to {entity.parent!r}; "
                "call its detach() first"
            )
        if attach_site is None:
            attach_site = self.attachment_site
        elif isinstance(attach_site, str):
            site = self.mjcf_model.find("site", attach_site)
            if site is None:
                raise ValueError(
                    f"attach_site: no site named {attach_site!r} in model {self.mjcf_model.model!r}"
                )
            attach_site = site
        frame = attach_site.attach(entity.mjcf_model)
        self._attached.append(entity)
        entity._parent = weakref.ref(self)
        return frame

    def detach(self) -> None:
        """Detaches this entity (and its model) from its parent.

        Raises:
          RuntimeError: if this entity is not attached.
        """
        parent = self.parent
        if parent is None:
            raise RuntimeError(f"cannot detach {self!r}: it is not attached to a parent entity")
        self.mjcf_model.detach()
        parent._attached.remove(self)
        self._parent = None

    def create_root_joints(self, attachment_frame) -> None:
        """Adds the joints that let this entity move inside its parent: a free joint.

        `composer.Arena.add_free_entity` calls this; override it to attach with other
        joints (e.g. planar slides).
        """
        attachment_frame.add("freejoint")

    def _free_joint(self):
        """The free joint of this entity's attachment frame, or None."""
        frame = mjcf.get_attachment_frame(self.mjcf_model)
        return None if frame is None else mjcf.get_freejoint(frame)

    def _require_attachment_frame(self):
        frame = mjcf.get_attachment_frame(self.mjcf_model)
        if frame is None:
            raise RuntimeError(_NOT_ATTACHED.format(entity=repr(self)))
        return frame

    def get_pose(self, physics) -> tuple[np.ndarray, np.ndarray]:
        """Returns (position (3,), quaternion (4,)) of this entity.

        For an entity with a free joint the pose is global (the joint's qpos);
        otherwise it is the attachment frame's pose relative to the parent.

        Raises:
          RuntimeError: if the entity is not attached.
        """
        free_joint = self._free_joint()
        if free_joint is not None:
            qpos = physics.bind(free_joint).qpos
            return qpos[:3], qpos[3:]
        frame = physics.bind(self._require_attachment_frame())
        return frame.pos, frame.quat

    def set_pose(self, physics, position=None, quaternion=None) -> None:
        """Sets the position and/or orientation of this entity (see `get_pose` for frames).

        A free entity's pose is written into its joint's qpos, a fixed entity's into the
        compiled model (its attachment frame's body pos/quat). The quaternion is
        normalised in both cases.

        Raises:
          RuntimeError: if the entity is not attached.
        """
        if quaternion is not None:
            quaternion = np.asarray(quaternion, dtype=np.float64)
            # np.linalg.norm's own arithmetic for a real array, without its dispatch (this
            # runs at every reset of many tasks).
            flat = quaternion.ravel(order="K")
            quaternion = quaternion / np.sqrt(flat.dot(flat))
        free_joint = self._free_joint()
        if free_joint is not None:
            qpos = physics.bind(free_joint).qpos
            if position is not None:
                qpos[:3] = position
            if quaternion is not None:
                qpos[3:] = quaternion
            return
        frame = physics.bind(self._require_attachment_frame())
        if position is not None:
            frame.pos = position
        if quaternion is not None:
            frame.quat = quaternion

    def shift_pose(
        self, physics, position=None, quaternion=None, rotate_velocity: bool = False
    ) -> None:
        """Moves this entity relative to its current pose.

        `position` is added to the current position; `quaternion` is pre-multiplied
        onto the current orientation. With `rotate_velocity`, a free entity's linear
        velocity (world frame) is rotated by `quaternion` too; its angular velocity,
        expressed in the body frame, already follows the rotation.
        """
        current_position, current_quaternion = self.get_pose(physics)
        new_position = None
        new_quaternion = None
        if position is not None:
            new_position = current_position + np.asarray(position, dtype=np.float64)
        if quaternion is not None:
            quaternion = np.asarray(quaternion, dtype=np.float64)
            new_quaternion = np.empty(4)
            mujoco.mju_mulQuat(new_quaternion, quaternion, np.array(current_quaternion))
            free_joint = self._free_joint()
            if rotate_velocity and free_joint is not None:
                rotated = np.empty(3)
                mujoco.mju_rotVecQuat(
                    rotated, np.array(physics.bind(free_joint).qvel[:3]), quaternion
                )
                self.set_velocity(physics, velocity=rotated)
        self.set_pose(physics, new_position, new_quaternion)

    def get_velocity(self, physics) -> tuple[np.ndarray, np.ndarray]:
        """Returns (linear (3,), angular (3,)) velocity of this free entity's joint.

        Raises:
          ValueError: if the entity is not attached with a free joint.
        """
        free_joint = self._free_joint()
        if free_joint is None:
            raise ValueError(f"{self!r} has no free joint, so it has no velocity to get")
        qvel = physics.bind(free_joint).qvel
        return qvel[:3], qvel[3:]

    def set_velocity(self, physics, velocity=None, angular_velocity=None) -> None:
        """Sets the linear and/or angular velocity of this free entity's joint.

        An entity without a free joint is left unchanged and a warning is logged.
        """
        free_joint = self._free_joint()
        if free_joint is None:
            logging.warning("Cannot set the velocity of %r: it has no free joint.", self)
            return
        qvel = physics.bind(free_joint).qvel
        if velocity is not None:
            qvel[:3] = velocity
        if angular_velocity is not None:
            qvel[3:] = angular_velocity

    def configure_joints(self, physics, position) -> None:
        """Sets the positions of the joints in this entity's own MJCF model.

        `position` holds the `qpos` values of the joints in
        `mjcf_model.find_all('joint', exclude_attachments=True)` order. Joints inside
        attached entities are left alone, but the root joints of attached entities (in
        their attachment frames, which belong to this model) are included. Subclasses
        with actuated joints may override this to keep the actuators' controls consistent
        with the new positions.
        """
        joints = self.mjcf_model.find_all("joint", exclude_attachments=True)
        physics.bind(joints).qpos = position

    def global_vector_to_local_frame(self, physics, vec_in_world_frame) -> np.ndarray:
        """Expresses world-frame vectors (last axis of size 2 or 3) in this entity's frame.

        A 2-D vector is rotated by the xy block of the root body's orientation.

        Raises:
          ValueError: if the last axis is not of size 2 or 3.
        """
        vec = np.asarray(vec_in_world_frame, dtype=np.float64)
        xmat = np.reshape(physics.bind(self.root_body).xmat, (3, 3))
        size = vec.shape[-1] if vec.ndim else 0
        if size not in (2, 3):
            raise ValueError(
                f"vec_in_world_frame: expected a last axis of size 2 or 3, got shape {vec.shape}"
            )
        return vec @ xmat[:size, :size]

    def global_xmat_to_local_frame(self, physics, xmat) -> np.ndarray:
        """Expresses a world-frame rotation matrix (9 values or 3x3) in this entity's frame.

        The result has the same shape as `xmat`.
        """
        xmat = np.asarray(xmat, dtype=np.float64)
        own = np.reshape(physics.bind(self.root_body).xmat, (3, 3))
        return np.reshape(own.T @ np.reshape(xmat, (3, 3)), xmat.shape)

    def initialize_episode_mjcf(self, random_state: np.random.RandomState) -> None:
        """Changes this entity's MJCF model before an episode is compiled."""
        return None

    def after_compile(self, physics, random_state: np.random.RandomState) -> None:
        """Runs after the model is compiled for an episode."""
        return None

    def initialize_episode(self, physics, random_state: np.random.RandomState) -> None:
        """Sets this entity's initial state; runs inside `physics.reset_context()`."""
        return None

    def before_step(self, physics, random_state: np.random.RandomState) -> None:
        """Runs after the task's `before_step`, before the physics steps of a control step."""
        return None

    def before_substep(self, physics, random_state: np.random.RandomState) -> None:
        """Runs before every physics step."""
        return None

    def after_substep(self, physics, random_state: np.random.RandomState) -> None:
        """Runs after every physics step."""
        return None

    def after_step(self, physics, random_state: np.random.RandomState) -> None:
        """Runs after the last physics step of a control step."""
        return None


class ModelWrapperEntity(Entity):
    """An entity around an existing `mjcf.RootElement`, with no behaviour of its own."""

    def _build(self, mjcf_model) -> None:
        self._mjcf_model = mjcf_model

    @property
    def mjcf_model(self):
        return self._mjcf_model


class RootBodyFeature(observable.Observable):
    """Field `kind` of an entity's root body, indexed by `index`, found when it is read.

    Resolving the body late matters: a prop's observables are built with the prop, before
    it is attached and its root body becomes the attachment frame. `FreePropObservableMixin`
    builds its pose and velocity observables from this class.

    Args:
      entity: the `composer.Entity` whose `root_body` is read.
      kind: the binding attribute, such as 'xpos' or 'cvel'.
      index: the key selecting from the bound attribute (`slice(3, 6)`).
    """

    def __init__(self, entity: Entity, kind: str, index):
        self._entity = entity
        self._kind = kind
        self._index = index
        super().__init__(
            update_interval=1, buffer_size=None, delay=None, aggregator=None, corruptor=None
        )

    @property
    def selection(self) -> observable.MJCFSelection:
        """What this observable reads now: the entity's current root body, `kind`, `(index,)`.

        A new record at each access, since the root body changes when the entity is
        attached (see `MJCFFeature.selection` for how readers use it).
        """
        return observable.MJCFSelection(self._entity.root_body, self._kind, (self._index,))

    def _callable(self, physics):
        return self.selection.reader(physics)

    def _live_source(self, physics):
        # One body's rows are a view of MuJoCo's array, so the updater may gather them.
        return view_source(self.selection.reader(physics)())

    def __repr__(self) -> str:
        return f"<root body {self._kind!r}[{self._index}] observable of {self._entity!r}>"


class FreePropObservableMixin:
    """Pose and velocity observables of a freely moving entity, in the world frame.

    Mix into an `Observables` subclass: `position` (xpos) and `orientation` (xquat)
    of the entity's root body, `linear_velocity` (of the entity's centre of mass) and
    `angular_velocity`; the velocities are the parts of the root body's com-based
    velocity `cvel`.
    """

    @define.observable
    def position(self):
        return RootBodyFeature(self._entity, "xpos", slice(None))

    @define.observable
    def orientation(self):
        return RootBodyFeature(self._entity, "xquat", slice(None))

    @define.observable
    def linear_velocity(self):
        return RootBodyFeature(self._entity, "cvel", slice(3, 6))

    @define.observable
    def angular_velocity(self):
        return RootBodyFeature(self._entity, "cvel", slice(0, 3))
