"""BatchEnvironment: `num_envs` copies of a composer task stepped together on MuJoCo Warp."""

import math
import numbers
from collections.abc import Sequence
from typing import Any, NamedTuple

import dm_env
import numpy as np
from dm_env import specs

import composer
import mjcf
from composer.batch import _warp, actions, kernels, outputs
from composer.batch.observables import BatchObservables
from composer.batch.physics import BatchPhysics
from composer.batch.task import BatchTask, for_task
from composer.hooks import EnvironmentHooks
from composer.utils import argument_checks

__all__ = ["BatchEnvironment", "BatchTimeStep", "EpisodeEnds"]

_FIRST, _MID, _LAST = (
    int(t) for t in (dm_env.StepType.FIRST, dm_env.StepType.MID, dm_env.StepType.LAST)
)


class BatchTimeStep(NamedTuple):
    """What `BatchEnvironment.reset` and `step` return, one row per world.

    The arrays are of the environment's `array_type` (NumPy by default; see
    `composer.batch.outputs`).

    Attributes:
      step_type: int8 (num_envs,), `dm_env.StepType` values: FIRST for a world whose
        episode starts, MID, or LAST for one whose episode ended at this step.
      reward: float64 (num_envs,); 0 for a FIRST world.
      discount: float64 (num_envs,); 1 for a FIRST world.
      observation: dict of float32 arrays (num_envs, *the CPU environment's observation
        shape).
    """

    step_type: Any
    reward: Any
    discount: Any
    observation: dict[str, Any]

    def first(self) -> Any:
        """Which worlds start an episode: a bool array (NumPy for Warp step types)."""
        return _step_types(self.step_type) == _FIRST

    def mid(self) -> Any:
        """Which worlds are mid-episode: a bool array (NumPy for Warp step types)."""
        return _step_types(self.step_type) == _MID

    def last(self) -> Any:
        """Which worlds ended their episode: a bool array (NumPy for Warp step types)."""
        return _step_types(self.step_type) == _LAST


def _step_types(step_type):
    # A Warp array has no elementwise comparison; its values come to the host to compare.
    return step_type.numpy() if outputs.array_library(step_type) == "warp" else step_type


class EpisodeEnds(NamedTuple):
    """How the episodes that ended at the last step ended, as host arrays (num_envs,) bool.

    Attributes:
      terminated: the task ended the episode (discount 0), Gymnasium's `terminated`.
      truncated: the episode ended with a non-zero discount (the time limit), Gymnasium's
        `truncated`.
    """

    terminated: np.ndarray
    truncated: np.ndarray


def _random_states(num_envs: int, random_state, random_states) -> list[np.random.RandomState]:
    if random_states is not None:
        if len(random_states) != num_envs:
            raise ValueError(
                f"random_states: expected {num_envs} (one per world), got {len(random_states)}"
            )
        return [
            rs if isinstance(rs, np.random.RandomState) else np.random.RandomState(rs)
            for rs in random_states
        ]
    if not isinstance(random_state, np.random.RandomState):
        random_state = np.random.RandomState(random_state)
    seeds = random_state.randint(2**31, size=num_envs)
    return [np.random.RandomState(seed) for seed in seeds]


def _control_step_limit(time_limit: float, physics_timestep: float, n_sub_steps: int) -> float:
    """The number of control steps after which C MuJoCo's float64 `time` reaches the limit.

    The time is accumulated as MuJoCo does (one addition per physics step), so a world
    ends at the same step as the CPU environment, whatever float32's `time` on the device.
    """
    if math.isinf(time_limit):
        return math.inf
    time, steps = 0.0, 0
    while time < time_limit:
        for _ in range(n_sub_steps):
            time += physics_timestep
        steps += 1
    return steps


class BatchEnvironment:
    """Runs `num_envs` worlds of a composer task on a MuJoCo Warp device, as one batch.

    The task's MJCF is compiled once through `mjcf` (the host `mjcf.Physics`, on which the
    `after_compile` hooks run once), then put on `device` with `num_envs` worlds. Each world
    is an episode of its own, with its own random generator, step count and time limit;
    a world whose episode ended is reset on its own at the next `step`, as
    `composer.Environment` does (the batch's action for it is ignored).

    Args:
      task: a `composer.Task` with a registered batched version, or a `BatchTask`.
      num_envs: the number of worlds.
      device: the Warp device: "cpu" or "cuda:0" (CUDA graph capture of the physics step).
      time_limit: seconds of simulated time after which a world's episode ends (LAST).
      random_state: an int seed or `np.random.RandomState` from which each world's random
        generator is seeded (ignored when `random_states` is given).
      random_states: one int seed or `np.random.RandomState` per world.
      n_sub_steps: physics steps per control step (default: the task's).
      strip_singleton_obs_buffer_dim: as in `composer.Environment`.
      batched_model_fields: MjModel fields to give one row per world, in addition to the
        task's own (see `BatchPhysics`).
      nconmax, njmax: per-world contact and constraint capacity for MuJoCo Warp.
      array_type: what `reset` and `step` hand out: "numpy" (host arrays), or "warp",
        "torch" or "jax": arrays on `device`, without copies (see `composer.batch.outputs`).
        Actions may be NumPy, Warp, torch or JAX arrays whatever the array type.

    Raises:
      ValueError: for a bad argument, named in the message.
      TypeError: for a task with no batched version, or an observable without a batched
        reader.
      NotImplementedError: for a task or entity with `initialize_episode_mjcf` hooks (MJCF
        variations need a recompile per episode), with sub-step or `after_step` hooks, or
        with a `before_step` that the `BatchTask` does not override.
    """

    def __init__(
        self,
        task: composer.Task | BatchTask,
        num_envs: int,
        *,
        device: str = "cpu",
        time_limit: float = float("inf"),
        random_state: int | np.random.RandomState | None = None,
        random_states: Sequence[int | np.random.RandomState] | None = None,
        n_sub_steps: int | None = None,
        strip_singleton_obs_buffer_dim: bool = False,
        batched_model_fields: Sequence[str] = (),
        nconmax: int | None = None,
        njmax: int | None = None,
        array_type: str = "numpy",
    ):
        self.num_envs = argument_checks.integer(num_envs=num_envs)
        outputs.check_array_type(array_type)
        if not isinstance(device, str):
            raise ValueError(
                f"device: expected a Warp device name such as 'cpu' or 'cuda:0', got {device!r}"
            )
        if not isinstance(time_limit, numbers.Real) or math.isnan(time_limit) or time_limit < 0:
            raise ValueError(f"time_limit: expected a number of seconds >= 0, got {time_limit!r}")
        self._batch_task = for_task(task)
        cpu_task = self._batch_task.task
        hooks = EnvironmentHooks(cpu_task)
        _refuse_mjcf_variations(cpu_task)
        _refuse_unbatched_hooks(hooks, self._batch_task)
        self._n_sub_steps = (
            cpu_task.physics_steps_per_control_step
            if n_sub_steps is None
            else argument_checks.integer(n_sub_steps=n_sub_steps)
        )
        self._random_states = _random_states(self.num_envs, random_state, random_states)
        host = mjcf.Physics.from_mjcf_model(cpu_task.root_entity.mjcf_model)
        with host.reset_context():
            hooks.after_compile(host, np.random.RandomState(0))
        fields = tuple(self._batch_task.batched_model_fields) + tuple(batched_model_fields)
        self._physics = BatchPhysics(
            host,
            self.num_envs,
            device=device,
            batched_model_fields=fields,
            nconmax=nconmax,
            njmax=njmax,
        )
        self._batch_task.after_compile(self._physics)
        self._outputs = outputs.DeviceOutputs(_warp.load()[0], self._physics.device, array_type)
        self._on_device = array_type != "numpy"
        self._controls_on_device = type(self._batch_task).before_step is BatchTask.before_step
        self._action_spec = cpu_task.action_spec(host)
        self._action_shape = (self.num_envs, *self._action_spec.shape)
        self._observables = BatchObservables(
            cpu_task.observables, self._physics, strip_singleton_obs_buffer_dim
        )
        self._step_limit = _control_step_limit(
            float(time_limit), cpu_task.physics_timestep, self._n_sub_steps
        )
        self._steps = np.zeros(self.num_envs, dtype=np.int64)
        self._reset_next = np.ones(self.num_envs, dtype=bool)
        self._discount = np.ones(self.num_envs)

    @property
    def physics(self) -> BatchPhysics:
        """The `BatchPhysics` of all worlds."""
        return self._physics

    @property
    def task(self) -> BatchTask:
        """The `BatchTask`; its `task` is the CPU task."""
        return self._batch_task

    @property
    def random_states(self) -> list[np.random.RandomState]:
        """Each world's random generator."""
        return self._random_states

    def reseed(self, seed: int | np.random.RandomState | None) -> None:
        """Reseeds every world's random generator from `seed`, as the constructor does."""
        self._random_states = _random_states(self.num_envs, seed, None)

    def action_spec(self) -> specs.BoundedArray:
        """One world's action spec (the CPU task's); actions have a leading num_envs axis."""
        return self._action_spec

    def observation_spec(self) -> dict[str, specs.Array]:
        """One world's observation specs by key (float32, the shapes of one world)."""
        return {
            name: specs.Array(value.shape[1:], value.dtype, name)
            for name, value in self._observables.read().items()
        }

    def _reset_worlds(self, env_ids: np.ndarray) -> None:
        states = [self._random_states[i] for i in env_ids]
        self._batch_task.initialize_episode(self._physics, env_ids, states)
        self._physics.forward(env_ids, actuation=False)
        self._steps[env_ids] = 0
        self._reset_next[env_ids] = False

    def reset(self) -> BatchTimeStep:
        """Starts a new episode in every world.

        Returns:
          A `BatchTimeStep` with every step type FIRST, rewards 0 and discounts 1.
        """
        self._reset_worlds(np.arange(self.num_envs))
        n = self.num_envs
        self._discount = np.ones(n)
        return self._time_step(np.full(n, _FIRST, np.int8), np.zeros(n), self._discount)

    def _time_step(self, step_type, reward, discount) -> BatchTimeStep:
        """The results of this step, handed out as `array_type` (see the module docstring)."""
        if not self._on_device:
            return BatchTimeStep(step_type, reward, discount, self._observables.read())
        observation = self._observables.read_device(self._outputs)
        return BatchTimeStep(
            self.hand_out(step_type),
            self.hand_out(reward),
            self.hand_out(discount),
            {name: self._outputs.hand_out(value) for name, value in observation.items()},
        )

    def hand_out(self, values: np.ndarray) -> Any:
        """Host `values` as this environment's `array_type` (on its device unless NumPy)."""
        if not self._on_device:
            return values
        return self._outputs.hand_out(self._outputs.upload(values))

    def episode_ends(self) -> EpisodeEnds:
        """How the episodes that ended at the last `step` ended (host arrays).

        Returns:
          An `EpisodeEnds`: `terminated` where the task ended an episode with discount 0,
          `truncated` where an episode ended with a non-zero discount (a time limit).
        """
        ended = self._reset_next
        terminated = ended & (self._discount == 0.0)
        return EpisodeEnds(terminated=terminated, truncated=ended & ~terminated)

    def _apply_action(self, action) -> None:
        """Checks `action` and sets the controls of every world (see `actions`)."""
        checked = actions.check_action(action, self._action_shape, self._outputs)
        physics = self._physics
        if not isinstance(checked, np.ndarray):
            if self._controls_on_device:
                wp = _warp.load()[0]
                ctrl = physics.warp_data.ctrl
                wp.launch(
                    kernels.kernels().write_float32,
                    dim=ctrl.shape,
                    inputs=[checked, ctrl],
                    device=physics.device,
                )
                return
            checked = checked.numpy().astype(np.float64).reshape(self._action_shape)
        self._batch_task.before_step(physics, checked)

    def step(self, action) -> BatchTimeStep:
        """Steps every world by one control step; worlds after LAST start a new episode.

        Args:
          action: shape (num_envs, *action_spec().shape): a NumPy array (or anything
            NumPy reads), or a Warp, torch or JAX array on the batch's device (used there,
            without a copy, when the task only sets the controls).

        Returns:
          A `BatchTimeStep`: FIRST (reward 0, discount 1) for worlds that were reset, LAST
          for worlds whose episode ended (the task terminated it or the time limit passed),
          MID for the others.

        Raises:
          ValueError: for an action of the wrong shape or with NaN or infinity; nothing is
            stepped.
        """
        if self._reset_next.all():
            actions.check_action(action, self._action_shape, self._outputs)
            return self.reset()
        restarting = np.flatnonzero(self._reset_next)
        physics, task = self._physics, self._batch_task
        self._apply_action(action)
        physics.step(self._n_sub_steps)
        if restarting.size:
            # These worlds were stepped with the others; their reset overwrites that step.
            self._reset_worlds(restarting)
        self._steps += 1
        self._steps[restarting] = 0
        reward = np.asarray(task.get_reward(physics), dtype=np.float64)
        discount = np.asarray(task.get_discount(physics), dtype=np.float64)
        ended = np.asarray(task.should_terminate_episode(physics), dtype=bool) | (
            self._steps >= self._step_limit
        )
        ended[restarting] = False
        step_type = np.where(ended, _LAST, _MID).astype(np.int8)
        step_type[restarting] = _FIRST
        reward[restarting] = 0.0
        discount[restarting] = 1.0
        self._reset_next, self._discount = ended, discount
        return self._time_step(step_type, reward, discount)


def _hook_owners(task: composer.Task, names: tuple[str, ...]) -> list[str]:
    """'Owner.hook' for each of `names` that the task or an entity overrides."""
    found = []
    for owner in (task, *task.root_entity.iter_entities()):
        base = composer.Task if isinstance(owner, composer.Task) else composer.Entity
        for name in names:
            if getattr(type(owner), name) is not getattr(base, name):
                found.append(f"{type(owner).__name__}.{name}")
    return found


def _refuse_unbatched_hooks(hooks: EnvironmentHooks, batch_task: BatchTask) -> None:
    """Raises NotImplementedError for CPU hooks that a batch would otherwise skip."""
    task = batch_task.task
    if hooks.has_substep_hooks or hooks.has_after_step_hooks:
        owners = _hook_owners(task, ("before_substep", "after_substep", "after_step"))
        raise NotImplementedError(
            f"{', '.join(owners)}: a batch steps its sub-steps on the device, without Python "
            "hooks between them (before_substep, after_substep and after_step are not run)"
        )
    if hooks.has_before_step_hooks and type(batch_task).before_step is BatchTask.before_step:
        owners = _hook_owners(task, ("before_step",))
        raise NotImplementedError(
            f"{', '.join(owners)} does more than set the controls; "
            f"{type(batch_task).__name__} must override before_step to do it for every world"
        )


def _refuse_mjcf_variations(task: composer.Task) -> None:
    """Raises NotImplementedError if the task or an entity changes its MJCF per episode."""
    owners = [task, *task.root_entity.iter_entities()]
    base_hooks = (composer.Task.initialize_episode_mjcf, composer.Entity.initialize_episode_mjcf)
    for owner in owners:
        hook = getattr(type(owner), "initialize_episode_mjcf", None)
        if hook is not None and hook not in base_hooks:
            raise NotImplementedError(
                f"{type(owner).__name__}.initialize_episode_mjcf changes the MJCF model per "
                "episode, which needs a recompile; a batch compiles once (put per-world "
                "physics variation in batched_model_fields instead)"
            )
