"""The Composer environment: a `dm_env.Environment` that runs a `composer.Task`."""

import enum
import math
import numbers
import warnings
import weakref

import dm_env
import numpy as np
from absl import logging

import mjcf
from composer import observation
from composer.action_validation import action_validator
from composer.hooks import HOOK_NAMES, EnvironmentHooks
from composer.utils import argument_checks
from composer.weak_physics import WeakPhysics
from mjcf.patching.compiled_model import CompiledModel, ModelUpdate

__all__ = [
    "HOOK_NAMES",
    "Environment",
    "EpisodeInitializationError",
    "ObservationPadding",
]


_FIRST, _MID, _LAST = dm_env.StepType.FIRST, dm_env.StepType.MID, dm_env.StepType.LAST
# How far from a whole number of control steps a time limit may be and still count as one.
_WHOLE_STEPS_TOLERANCE = 1e-6


class EpisodeInitializationError(RuntimeError):
    """Raised by a task or entity when it fails to set up an episode; reset may retry."""


class ObservationPadding(enum.Enum):
    """What a delayed observation buffer holds before its first sample arrives."""

    INITIAL_VALUE = -1
    ZERO = 0


def _time_limit_warning(time_limit: float, control_timestep: float) -> str | None:
    """The warning for a time limit that is not a whole number of control steps, or None."""
    steps = time_limit / control_timestep
    if math.isinf(steps) or abs(steps - round(steps)) <= _WHOLE_STEPS_TOLERANCE:
        return None
    last_step = math.ceil(steps)
    multiples = [f"{n * control_timestep:g} s" for n in (last_step - 1, last_step) if n > 0]
    steps_taken = f"{last_step} step{'s' if last_step > 1 else ''}"
    return (
        f"time_limit={time_limit:g} s is not a multiple of the control timestep "
        f"{control_timestep:g} s: an episode ends at the first step that reaches it, after "
        f"{steps_taken} at t={last_step * control_timestep:g} s; use a multiple of the "
        f"control timestep ({' or '.join(multiples)}) to end episodes at the time limit"
    )


def _collected(observables) -> tuple:
    """The names and observable objects of `task.observables` (a dict or a list of dicts),
    with the containers' types: two results are equal when they hold the same names and
    the very same observables (observables compare by identity)."""
    dicts = (observables,) if isinstance(observables, dict) else observables
    return type(observables), tuple((type(d), tuple(d.items())) for d in dicts)


class Environment(dm_env.Environment):
    """Runs a `composer.Task` as a `dm_env.Environment`.

    Args:
      task: the `composer.Task` to run.
      time_limit: seconds of simulated time after which an episode ends (LAST, with
        the task's discount): the first step that reaches it is the last. A time limit
        that is not a multiple of the control timestep gives a `UserWarning` once (and
        again if the control timestep changes), except under the dm_control redirect
        (`composer.dm_control_compat`), where code written for dm_control, which says
        nothing, sets such limits (its locomotion examples: 25 s every 0.03 s).
      random_state: an int seed or an `np.random.RandomState`; every hook gets it.
      n_sub_steps: physics steps per control step, overriding the task's
        `physics_steps_per_control_step`.
      raise_exception_on_physics_error: if False, a `PhysicsError` while stepping
        ends the episode with a logged warning, reward 0 and discount 0, and the
        next `step` starts a new episode.
      strip_singleton_obs_buffer_dim: drop the leading buffer axis of observations
        whose buffer size is 1.
      max_reset_attempts: how many times `reset` tries to initialise an episode
        when a hook raises `EpisodeInitializationError`.
      recompile_mjcf_every_episode: run the `initialize_episode_mjcf` hooks before
        every episode and start it from a freshly compiled model. The model is only
        really recompiled when the MJCF tree changed since the last compile;
        otherwise the compiled model's parameters are restored from a copy taken
        right after compiling (undoing any writes through `physics.bind`), which is
        indistinguishable and much faster. When only attribute values proven patchable
        changed (colours, frictions, gains, ...; `mjcf.patching.model_patch`), their
        compiled fields are written into the model instead of compiling. A recompile that
        changed only parameter values loads them into the current model, so the Physics and
        its bindings carry over; one that changed the model's structure gives a new Physics.
        If False, this happens only before the first episode (so `after_compile` hooks
        added after construction still run once), and changes made to the model during an
        episode persist.
      fixed_initial_state: restore the random state at every reset, so that every
        episode starts from the same state.
      delayed_observation_padding: an `ObservationPadding`.
      legacy_step: step with position- and velocity-dependent quantities up to date
        after each step (see `mjcf.Physics.step`).
      patch_compiled_model: whether a reset may patch the compiled model in place instead
        of recompiling (see `recompile_mjcf_every_episode`). Either way the episodes are
        the same, bit for bit; False always recompiles a changed model.

    Observables are collected from `task.observables` whenever the model is
    compiled; enabling, disabling or reconfiguring them takes effect at the next
    reset, and observables added to an entity take effect at the next compile.

    `reset()` returns `TimeStep(FIRST, None, None, observation)`. `step(action)`
    runs the task's and entities' `before_step` hooks, the physics sub-steps (with
    `before_substep`/`after_substep` hooks around each when any is defined), then
    `after_step`, and returns MID or LAST with the task's reward and discount. A
    `step` after LAST (or before the first `reset`) resets instead and returns FIRST.
    """

    def __init__(
        self,
        task,
        time_limit: float = float("inf"),
        random_state=None,
        n_sub_steps: int | None = None,
        raise_exception_on_physics_error: bool = True,
        strip_singleton_obs_buffer_dim: bool = False,
        max_reset_attempts: int = 1,
        recompile_mjcf_every_episode: bool = True,
        fixed_initial_state: bool = False,
        delayed_observation_padding: ObservationPadding = ObservationPadding.ZERO,
        legacy_step: bool = True,
        *,
        patch_compiled_model: bool = True,
    ):
        if not isinstance(time_limit, numbers.Real) or math.isnan(time_limit) or time_limit < 0:
            raise ValueError(f"time_limit: expected a number of seconds >= 0, got {time_limit!r}")
        if not isinstance(delayed_observation_padding, ObservationPadding):
            raise ValueError(
                "delayed_observation_padding: expected ObservationPadding.ZERO or "
                f"ObservationPadding.INITIAL_VALUE, got {delayed_observation_padding!r}"
            )
        self._task = task
        self._time_limit = float(time_limit)
        if isinstance(random_state, np.random.RandomState):
            self._random_state = random_state
        else:
            self._random_state = np.random.RandomState(random_state)
        self._overridden_n_sub_steps = (
            None if n_sub_steps is None else argument_checks.integer(n_sub_steps=n_sub_steps)
        )
        self._raise_exception_on_physics_error = raise_exception_on_physics_error
        self._strip_singleton_obs_buffer_dim = strip_singleton_obs_buffer_dim
        self._max_reset_attempts = argument_checks.integer(max_reset_attempts=max_reset_attempts)
        self._recompile_mjcf_every_episode = recompile_mjcf_every_episode
        self._pad_with_initial_value = (
            delayed_observation_padding is ObservationPadding.INITIAL_VALUE
        )
        self._legacy_step = legacy_step
        self._hooks = EnvironmentHooks(task)
        # The compiled model and what is built on it (see `_update_model`).
        self._compiled_model = CompiledModel(patch=patch_compiled_model)
        self._physics = None
        self._physics_proxy = None
        self._physics_view = None
        self._data = None
        self._ctrl = None
        self._check_action = None
        self._observation_updater = None
        self._observation_out = None  # see `write_observations_to`
        self._n_sub_steps = None
        self._collected_observables = None
        # Episode bookkeeping.
        self._reset_next_step = True
        self._episode_mjcf_prepared = False
        self._time_limit_checked_for = None
        self._update_model()
        self._warn_if_time_limit_is_not_whole_steps()
        self._fixed_random_state = self._random_state.get_state() if fixed_initial_state else None

    # Properties and specs.

    @property
    def physics(self) -> WeakPhysics | None:
        """A weak reference to the current `mjcf.Physics`, used like the Physics itself.

        It does not keep the Physics alive: the Physics belongs to this environment and is
        freed with it, so keep the environment for as long as you use its physics
        (`env = make_env()` and then `env.physics`, not `make_env().physics`). `close()`
        frees it, and a reset that recompiles a changed model structure replaces it (other
        resets keep the same Physics). Using an old reference after that raises a
        ReferenceError that says which of these happened. None after `close()`.
        """
        return self._physics_view

    @property
    def task(self):
        return self._task

    @property
    def time_limit(self) -> float:
        """Seconds of simulated time after which an episode ends; inf for no limit."""
        return self._time_limit

    @property
    def random_state(self) -> np.random.RandomState:
        return self._random_state

    def control_timestep(self) -> float:
        """Seconds between agent actions."""
        if self._overridden_n_sub_steps is not None:
            return self._physics.timestep() * self._overridden_n_sub_steps
        return self._task.control_timestep

    def _warn_if_time_limit_is_not_whole_steps(self) -> None:
        """Warns, once per control timestep, when the time limit falls between two steps
        (not under the dm_control redirect: see the class docstring)."""
        # Imported here: `python -m composer.dm_control_compat` must find that module not yet
        # imported when the `composer` package is.
        from composer import dm_control_compat

        control_timestep = self.control_timestep()
        if control_timestep == self._time_limit_checked_for or dm_control_compat.installed():
            return
        self._time_limit_checked_for = control_timestep
        message = _time_limit_warning(self._time_limit, control_timestep)
        if message is not None:
            # Points at the caller of the constructor or of reset().
            warnings.warn(message, UserWarning, stacklevel=3)

    def add_extra_hook(self, hook_name: str, hook_callable) -> None:
        """Calls `hook_callable` after the task's and entities' hooks named `hook_name`.

        It receives the same arguments as the task's hook of that name.

        Raises:
          ValueError: if `hook_name` is not one of `HOOK_NAMES`.
        """
        self._hooks.add_extra_hook(hook_name, hook_callable)

    def action_spec(self):
        return self._task.action_spec(self._physics_proxy)

    def observation_spec(self):
        return self._observation_updater.observation_spec()

    def write_observations_to(self, out) -> None:
        """Makes `reset` and `step` write their observations into `out` and return `out`
        itself as the TimeStep's observation, which the next `reset` or `step` overwrites.

        For a caller that keeps observations in arrays of its own, such as a vector env's
        batch rows: each observation is then copied once, straight there. It holds while
        the observation spec stays as it is; a reset that changes it (an observable added
        or changed between episodes) goes back to new arrays.

        Args:
          out: a dict of arrays in the structure of `observation_spec()` (its keys, in
            any order), each writeable, of its spec's shape and dtype; or None for new
            arrays at every call (the default).

        Raises:
          ValueError: naming the key of `out` that does not match `observation_spec()`.
        """
        if out is not None:
            problem = self._observation_updater.output_problem(out)
            if problem is not None:
                raise ValueError(f"write_observations_to: {problem}")
        self._observation_out = out

    def reward_spec(self):
        spec = self._task.get_reward_spec()
        return super().reward_spec() if spec is None else spec

    def discount_spec(self):
        spec = self._task.get_discount_spec()
        return super().discount_spec() if spec is None else spec

    def step_spec(self) -> dm_env.TimeStep:
        """Deprecated: use `reward_spec()` and `discount_spec()`.

        Returns a TimeStep of the task's reward and discount specs and the observation spec.

        Raises:
          NotImplementedError: if the task defines no reward spec or no discount spec.
        """
        warnings.warn(
            "Environment.step_spec is deprecated; use reward_spec() and discount_spec()",
            DeprecationWarning,
            stacklevel=2,
        )
        reward, discount = self._task.get_reward_spec(), self._task.get_discount_spec()
        if reward is None or discount is None:
            raise NotImplementedError(
                f"step_spec: the task {type(self._task).__name__} defines no "
                f"{'reward' if reward is None else 'discount'} spec"
            )
        return dm_env.TimeStep(None, reward, discount, self.observation_spec())

    def close(self) -> None:
        """Frees the physics. Closing again does nothing; a later `reset()` compiles a new
        Physics and starts an episode as on the first reset."""
        self._compiled_model.close()
        self._physics = None
        self._physics_proxy = None
        self._physics_view = None

    def __reduce_ex__(self, protocol):
        raise TypeError(
            "a composer.Environment cannot be copied or pickled (its task, entities, "
            "observables and physics refer to each other and to live MuJoCo data); build a "
            "new one from the same task factory and seed instead, or copy just the simulation "
            "with env.physics.copy()"
        )

    # Compiling.

    def _update_model(self) -> None:
        """Brings the compiled model up to date with the MJCF tree, as a fresh compile would,
        and rebuilds what depends on it.

        `CompiledModel.update` decides how (its class docstring is the contract: the four
        `ModelUpdate` outcomes, and when the next reset may copy the last one's data).
        After LOADED and NEW_PHYSICS, hooks are rescanned and the action check is rebuilt;
        after NEW_PHYSICS, the Physics' proxies are renewed. After every outcome the
        `after_compile` hooks run (each outcome stands for dm_control's compile); as they
        may write to the model, differently each time, their presence makes every reset
        compute its data afresh. The observation updater is rebuilt unless the Physics,
        the sub-steps and the task's observables (names and objects, see `_collected`) are
        all the same as last time: as in dm_control, which builds a new updater at every
        recompile, an observable added between episodes is observed from the next reset.
        Either way the updater is then reset, as dm_control resets its new one (the reset
        draws from the random state, which the seed guarantee counts on): with
        `Updater.reset_draws`, which makes the reset's calls into the observables but keeps
        the buffers of the last reset while nothing they depend on changed.
        """
        outcome = self._compiled_model.update(self._task.root_entity.mjcf_model)
        if outcome is ModelUpdate.NEW_PHYSICS:
            self._adopt_physics(self._compiled_model.physics)
        if outcome in (ModelUpdate.LOADED, ModelUpdate.NEW_PHYSICS):
            self._hooks.refresh_entity_hooks()
            self._check_action = action_validator(self._task.action_spec(self._physics_proxy))
        self._run_after_compile_hooks()
        if self._hooks.has_after_compile_hooks:
            self._compiled_model.model_may_have_changed()
        observables = self._task.observables
        collected = _collected(observables)
        if (
            self._observation_updater is None
            or self._task_sub_steps() != self._n_sub_steps
            or collected != self._collected_observables
        ):
            self._rebuild_observation_updater(observables)
        self._collected_observables = collected
        # dm_control resets the updater it builds at every compile; the reset may draw
        # from the random state, so its calls into the observables happen here too, for the
        # same draws in order. The episode's reset follows before anything reads the
        # buffers, so what the last reset built is kept where that is exact.
        self._observation_updater.reset_draws(self._physics_proxy, self._random_state)
        out = self._observation_out
        if out is not None and self._observation_updater.output_problem(out) is not None:
            self._observation_out = None  # the observation spec changed: new arrays again

    def _adopt_physics(self, physics: mjcf.Physics) -> None:
        """Makes `physics`, new, the one the environment steps and hands out."""
        physics.legacy_step = self._legacy_step
        self._physics = physics
        self._physics_proxy = weakref.proxy(physics)
        self._physics_view = WeakPhysics(physics, self)
        self._data = physics.data.ptr
        self._ctrl = self._data.ctrl
        self._observation_updater = None

    def _run_after_compile_hooks(self) -> None:
        # The hooks may set state, so they run inside a reset context; a divergence
        # there is reported but does not stop the episode from starting.
        if not self._hooks.has_after_compile_hooks:
            return
        try:
            with self._physics.reset_context():
                self._hooks.after_compile(self._physics_proxy, self._random_state)
        except mjcf.PhysicsError as error:
            logging.warning("Physics error in after_compile hooks: %s", error)

    def _task_sub_steps(self) -> int:
        if self._overridden_n_sub_steps is not None:
            return self._overridden_n_sub_steps
        return self._task.physics_steps_per_control_step

    def _rebuild_observation_updater(self, observables) -> None:
        self._n_sub_steps = self._task_sub_steps()
        self._observation_updater = observation.Updater(
            observables,
            self._n_sub_steps,
            self._strip_singleton_obs_buffer_dim,
            self._pad_with_initial_value,
        )

    # Resetting.

    def reset(self) -> dm_env.TimeStep:
        """Starts a new episode and returns its first TimeStep.

        Tries up to `max_reset_attempts` times while a hook raises
        `EpisodeInitializationError`, logging each failed attempt as a warning; the last
        such error propagates.
        """
        attempt = 1
        while True:
            try:
                timestep = self._reset_attempt()
            except EpisodeInitializationError as error:
                if attempt >= self._max_reset_attempts:
                    raise
                # The caller asked for retries, so a failed attempt is expected: a warning.
                logging.warning(
                    "Episode initialization failed (attempt %d of %d), retrying: %r",
                    attempt,
                    self._max_reset_attempts,
                    error,
                )
                attempt += 1
            else:
                # The task may have changed its control timestep since the last episode.
                self._warn_if_time_limit_is_not_whole_steps()
                return timestep

    def _reset_attempt(self) -> dm_env.TimeStep:
        # Hooks replaced on the task or an entity since the last episode take effect now.
        self._hooks.refresh_entity_hooks()
        if self._recompile_mjcf_every_episode or not self._episode_mjcf_prepared:
            self._restore_fixed_random_state()
            self._hooks.initialize_episode_mjcf(self._random_state)
            self._update_model()
            self._episode_mjcf_prepared = True
        else:
            # The model keeps what the last episode wrote into it.
            self._compiled_model.model_may_have_changed()
        self._restore_fixed_random_state()
        with self._compiled_model.reset_context():
            self._hooks.initialize_episode(self._physics_proxy, self._random_state)
        self._observation_updater.reset(self._physics_proxy, self._random_state)
        self._reset_next_step = False
        return dm_env.TimeStep(
            step_type=_FIRST,
            reward=None,
            discount=None,
            observation=self._observation_updater.get_observation(self._observation_out),
        )

    def _restore_fixed_random_state(self) -> None:
        # With a fixed initial state, the model's and the physics' initialisation each
        # start from the state the random state had after construction, as in dm_control.
        if self._fixed_random_state is not None:
            self._random_state.set_state(self._fixed_random_state)

    # Stepping.

    def step(self, action) -> dm_env.TimeStep:
        """Applies `action` for one control step and returns the resulting TimeStep.

        The action's bounds are not checked: as in dm_control, a value outside an
        actuator's `ctrlrange` is written to `ctrl` unchanged, and MuJoCo clamps it to
        the range when it computes the actuator's force.

        Raises:
          ValueError: if `action` does not match `action_spec()` in shape, cannot be
            cast to its dtype, or holds NaN or infinity; nothing is stepped.
          mjcf.PhysicsError: if the physics diverges and
            `raise_exception_on_physics_error` is True.
        """
        if self._reset_next_step:
            return self.reset()
        action = self._check_action(action)
        physics = self._physics_proxy
        random_state = self._random_state
        updater = self._observation_updater
        hooks = self._hooks
        if hooks.task_sets_controls:
            # What `Task.before_step` does, without its calls: the action is validated.
            self._ctrl[...] = action
        if hooks.has_before_step_hooks:
            hooks.before_step(physics, action, random_state)
        updater.prepare_for_next_control_step()
        try:
            if hooks.has_substep_hooks:
                unsampled_steps = self._substeps_with_hooks(action)
            else:
                unsampled_steps = self._substeps_in_chunks()
        except mjcf.PhysicsError as error:
            if self._raise_exception_on_physics_error:
                raise
            logging.warning("Physics error, ending the episode: %s", error)
            hooks.after_step(physics, random_state)
            updater.finish_control_step()
            self._reset_next_step = True
            return dm_env.TimeStep(_LAST, 0.0, 0.0, updater.get_observation(self._observation_out))
        if hooks.has_after_step_hooks:
            hooks.after_step(physics, random_state)
        updater.update(unsampled_steps)
        task = self._task
        reward = task.get_reward(physics)
        discount = task.get_discount(physics)
        if task.should_terminate_episode(physics) or self._data.time >= self._time_limit:
            self._reset_next_step = True
            step_type = _LAST
        else:
            step_type = _MID
        return dm_env.TimeStep(
            step_type, reward, discount, updater.get_observation(self._observation_out)
        )

    def _substeps_in_chunks(self) -> int:
        """Steps the physics straight through to each sub-step where observables are due.

        Returns the number of steps taken since the last observation update; the
        final update is left to the caller, after the `after_step` hooks.
        """
        updater = self._observation_updater
        step = self._physics.step
        n_sub_steps = self._n_sub_steps
        done = 0
        for sample_step in updater.sample_steps:
            if sample_step >= n_sub_steps:
                break
            step(sample_step - done)
            updater.update(sample_step - done)
            done = sample_step
        step(n_sub_steps - done)
        return n_sub_steps - done

    def _substeps_with_hooks(self, action) -> int:
        """Steps the physics one sub-step at a time, calling the sub-step hooks around each."""
        before, after = self._hooks.substep_calls(self._physics_proxy, action, self._random_state)
        updater = self._observation_updater
        sample_steps = frozenset(updater.sample_steps)
        n_sub_steps = self._n_sub_steps
        step = self._physics.step
        done = 0
        for sub_step in range(1, n_sub_steps + 1):
            for call in before:
                call()
            step()
            for call in after:
                call()
            if sub_step in sample_steps and sub_step < n_sub_steps:
                updater.update(sub_step - done)
                done = sub_step
        return n_sub_steps - done
