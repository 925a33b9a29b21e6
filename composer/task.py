"""The task: what is rewarded, when an episode ends, and how often the agent acts."""

import abc
import collections

import mujoco
import numpy as np
from dm_env import specs

_DEFAULT_PHYSICS_TIMESTEP = 0.002  # MuJoCo's default `option.timestep`.
_TIMESTEP_TOLERANCE = 1e-6


def _steps_per_control_step(control_timestep: float, physics_timestep: float) -> int:
    """Returns how many physics steps make one control step, or raises ValueError."""
    for name, value in (
        ("control_timestep", control_timestep),
        ("physics_timestep", physics_timestep),
    ):
        if not value > 0:
            raise ValueError(f"{name}: expected a positive number of seconds, got {value!r}")
    ratio = control_timestep / physics_timestep
    steps = round(ratio)
    if steps < 1 or abs(ratio - steps) > _TIMESTEP_TOLERANCE:
        raise ValueError(
            "control_timestep must be an integer multiple of physics_timestep: got "
            f"control_timestep={control_timestep!r}, physics_timestep={physics_timestep!r} "
            f"(ratio {ratio!r})"
        )
    return steps


class Task(metaclass=abc.ABCMeta):
    """Defines the reward, termination and timing of a Composer environment.

    A subclass provides `root_entity` (the entity, usually an arena, at the top of the
    model tree) and `get_reward(physics)`. Everything else has a default:

    - `should_terminate_episode` returns False and `get_discount` returns 1.0;
    - `get_success` returns None (success is not defined);
    - `before_step` writes the action into the actuators' controls;
    - the other lifecycle hooks (`initialize_episode_mjcf`, `after_compile`,
      `initialize_episode`, `before_substep`, `after_substep`, `after_step`) do nothing;
    - `observables` merges `task_observables` with every entity's observables;
    - `action_spec` describes one control per actuator, bounded by its ctrlrange.

    The control timestep defaults to the physics timestep (the root model's
    `option.timestep`, 0.002 s when unset); `set_timesteps` changes both.
    """

    @property
    @abc.abstractmethod
    def root_entity(self):
        """The `composer.Entity` at the root of this task's model tree."""

    @abc.abstractmethod
    def get_reward(self, physics):
        """Returns the reward for the current physics state."""

    def iter_entities(self):
        """Iterates over every entity in the task, root first, depth first."""
        return self.root_entity.iter_entities()

    @property
    def observables(self) -> collections.OrderedDict:
        """Every observable of the task: `task_observables` first, then each entity's.

        Entity observables are keyed by the entity's scoped model name, e.g.
        'jaco_arm/jaco_hand/pinch_site_pos'. Disabled observables are included; the
        environment only samples the enabled ones.
        """
        observables = collections.OrderedDict(self.task_observables)
        for entity in self.root_entity.iter_entities():
            observables.update(entity.observables.as_dict())
        return observables

    @property
    def task_observables(self) -> collections.OrderedDict:
        """Observables that belong to the task rather than to an entity (none by default)."""
        return collections.OrderedDict()

    def _root_model_option(self, caller: str):
        try:
            root_entity = self.root_entity
        except AttributeError as error:
            raise AttributeError(
                f"{type(self).__name__}.{caller} needs root_entity, which is not available "
                f"yet: {error}"
            ) from error
        return root_entity.mjcf_model.option

    @property
    def physics_timestep(self) -> float:
        """Seconds per physics step: the root model's `option.timestep`."""
        timestep = self._root_model_option("physics_timestep").timestep
        return _DEFAULT_PHYSICS_TIMESTEP if timestep is None else float(timestep)

    @physics_timestep.setter
    def physics_timestep(self, value: float) -> None:
        option = self._root_model_option("physics_timestep")
        if hasattr(self, "_control_timestep"):
            _steps_per_control_step(self._control_timestep, value)
        option.timestep = value

    @property
    def control_timestep(self) -> float:
        """Seconds between agent actions (the physics timestep unless set)."""
        if hasattr(self, "_control_timestep"):
            return self._control_timestep
        return self.physics_timestep

    @control_timestep.setter
    def control_timestep(self, value: float) -> None:
        _steps_per_control_step(value, self.physics_timestep)
        self._control_timestep = value

    def set_timesteps(self, control_timestep: float, physics_timestep: float) -> None:
        """Sets both timesteps at once.

        Raises:
          ValueError: if `control_timestep` is not an integer multiple of
            `physics_timestep` (within 1e-6 of the ratio) or either is not positive.
        """
        option = self._root_model_option("set_timesteps")
        _steps_per_control_step(control_timestep, physics_timestep)
        option.timestep = physics_timestep
        self._control_timestep = control_timestep

    @property
    def physics_steps_per_control_step(self) -> int:
        """The number of physics steps in one control step."""
        return _steps_per_control_step(self.control_timestep, self.physics_timestep)

    def action_spec(self, physics) -> specs.BoundedArray:
        """One float64 control per actuator, bounded by ctrlrange (±inf when unlimited).

        The spec's name is the actuators' full names joined by tabs (an actuator
        without a name is listed by its index).
        """
        model = physics.model
        raw_model = model.ptr
        nu = raw_model.nu
        names = [
            mujoco.mj_id2name(raw_model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) or str(i)
            for i in range(nu)
        ]
        limited = np.asarray(raw_model.actuator_ctrllimited, dtype=bool).reshape(nu)
        ctrlrange = np.asarray(raw_model.actuator_ctrlrange, dtype=np.float64).reshape(nu, 2)
        minimum = np.where(limited, ctrlrange[:, 0], -np.inf)
        maximum = np.where(limited, ctrlrange[:, 1], np.inf)
        return specs.BoundedArray(
            shape=(nu,),
            dtype=np.float64,
            minimum=minimum,
            maximum=maximum,
            name="\t".join(names),
        )

    def get_reward_spec(self) -> specs.Array | None:
        """The reward's spec, or None for dm_env's default (a float64 scalar)."""
        return None

    def get_discount_spec(self) -> specs.BoundedArray | None:
        """The discount's spec, or None for dm_env's default (a float64 scalar in [0, 1])."""
        return None

    def should_terminate_episode(self, physics) -> bool:
        """Whether the episode ends after the current step (False by default)."""
        return False

    def get_discount(self, physics) -> float:
        """The discount for the current step (1.0 by default)."""
        return 1.0

    def get_success(self, physics) -> bool | None:
        """Whether the task's goal is met in the current state; None (the default) for a
        task that does not define success.

        Not part of dm_control's Task: `composer.gym.GymnasiumEnv` reports it as
        `info['is_success']` at the end of each episode.
        """
        return None

    def initialize_episode_mjcf(self, random_state: np.random.RandomState) -> None:
        """Changes the MJCF model before an episode is compiled (nothing by default)."""
        return None

    def after_compile(self, physics, random_state: np.random.RandomState) -> None:
        """Runs after the model is compiled for an episode (nothing by default)."""
        return None

    def initialize_episode(self, physics, random_state: np.random.RandomState) -> None:
        """Sets the initial state, inside `physics.reset_context()` (nothing by default)."""
        return None

    def before_step(self, physics, action, random_state: np.random.RandomState) -> None:
        """Applies the agent's action; by default writes it into the actuator controls.

        An override must set the controls itself or call this implementation.
        """
        physics.set_control(action)

    def before_substep(self, physics, action, random_state: np.random.RandomState) -> None:
        """Runs before every physics step (nothing by default)."""
        return None

    def after_substep(self, physics, random_state: np.random.RandomState) -> None:
        """Runs after every physics step (nothing by default)."""
        return None

    def after_step(self, physics, random_state: np.random.RandomState) -> None:
        """Runs after the last physics step of a control step (nothing by default)."""
        return None


class NullTask(Task):
    """A task around a single root entity that always gives zero reward."""

    def __init__(self, root_entity):
        self._root_entity = root_entity

    @property
    def root_entity(self):
        return self._root_entity

    def get_reward(self, physics) -> float:
        return 0.0
