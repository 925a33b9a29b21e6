"""`SuiteBatchEnvironment`: many worlds of one Control Suite task on `mujoco.batch`.

Every control step is one `Batch.step` of every world (dm_control's legacy step: the
physics sub-steps, then the position and velocity stages at the new state, which is what
dm_control's `Physics.step` leaves), then the task's array code (`suite_batch.tasks`). An
episode starts from the CPU task's own `initialize_episode`, run ahead of time by a
producer thread on the CPU environment's physics with the world's random generator
(`suite_batch.episode_starts`); its integration state (`mj_getState`, warm start
included) and its rows of the model fields the episodes vary are written into the world's
rows, followed by `mj_forward` with actuation disabled, as dm_control's `reset_context`
ends.
"""

import logging
from collections.abc import Sequence

import dm_env
import numpy as np

from composer import episode_end
from composer.batch import BatchTimeStep, MujocoBatchPhysics, actions, arrays
from composer.batch.environment import AUTORESET_MODES, world_random_states
from composer.batch.initial_states import StateProducer
from composer.batch.mujoco_batch import divergence_report
from composer.batch.state_slots import InitialStateStats, StateSlots
from composer.episode_end import Autoreset, EpisodeEnds
from suite_batch.episode_starts import StartHost, SuiteStateMaker, varied_model_fields
from suite_batch.tasks import SuiteBatchTask

__all__ = ["SuiteBatchEnvironment"]

_FIRST, _MID, _LAST = (int(t) for t in dm_env.StepType)


class SuiteBatchEnvironment:
    """`num_envs` worlds of the Control Suite task of `env`, stepped at once.

    World i is the episode of the CPU environment seeded with `random_states[i]`
    (`suite.load(domain, task, task_kwargs={"random": seed})`), bit for bit: every
    observation, reward, discount and step type, over episodes and resets. A world's
    episode ends (LAST) when its task terminates it or at the suite's time limit (discount
    1 there, as dm_control's). A world whose state becomes invalid (NaN, infinite or huge,
    which MuJoCo answers by resetting it) ends its episode with reward 0 and discount 0,
    logged with a warning naming it, where dm_control's environment raises its
    `PhysicsError`; the other worlds go on.

    Autoreset follows `composer.episode_end`: under "next_step" (the default) the `step`
    after a world's LAST starts its next episode (FIRST, reward 0, discount 1), as
    dm_control's `step` after LAST resets; under "same_step" (Stable-Baselines3's and
    rsl_rl's) the `step` that ends an episode returns LAST with that episode's reward and
    discount and the next episode's first observation (dm_control's `reset` after it),
    the ended episode's last observation being `final_observation`.

    Made by `suite_batch.load`.

    Args:
      env: the CPU suite environment (a dm_control `control.Environment`): its model is
        every world's, its task starts every world's episodes.
      batch_task_type: the `SuiteBatchTask` of its task.
      random_states: one `np.random.RandomState` per world.
      world_envs: for a task whose model is drawn from the seed (lqr's), world i's own
        CPU environment, loaded with `random_states[i]`, on which its episodes start;
        `env` is then only the template of the batch's model.
      seeded_fields: the model fields in which the `world_envs`' models differ
        (`episode_starts.seeded_model_fields`): each world gets its row of them.
      threads: the C threads that step the worlds (None: the cores this process may use).
      autoreset_mode: "next_step" (dm_env's order, the default) or "same_step" (above).
      slots_per_world: episode starts made ahead per world (>= 1), by one producer thread.
      refill_interval: control steps between two requests for more starts (>= 1).

    Raises:
      ValueError: for bad `random_states`, `threads`, `slots_per_world` or
        `refill_interval`.
      NotImplementedError: for `legacy_step=False`, a task with its own `before_step` or
        `after_step`, which the array code does not cover yet, episode starts that vary
        a model field the batch cannot give each world (`varied_model_fields`), or a task
        with `world_envs` that keeps values from its starts (`initial_values`).
    """

    def __init__(
        self,
        env,
        batch_task_type: type[SuiteBatchTask],
        random_states: Sequence[np.random.RandomState],
        *,
        world_envs: Sequence | None = None,
        seeded_fields: Sequence[str] = (),
        threads: int | None = None,
        autoreset_mode: str = "next_step",
        slots_per_world: int = 3,
        refill_interval: int = 8,
    ):
        from dm_control.suite import base

        host, task = env.physics, env.task
        name = type(task).__qualname__
        if not host.legacy_step:
            raise NotImplementedError(
                "environment_kwargs legacy_step=False: the batch steps as dm_control's legacy "
                "step (the default)"
            )
        for hook in ("before_step", "after_step"):
            if getattr(type(task), hook) is not getattr(base.Task, hook):
                raise NotImplementedError(f"{name}.{hook}: not batched yet")
        if not random_states:
            raise ValueError("random_states: expected one generator per world, got none")
        if autoreset_mode not in AUTORESET_MODES:
            raise ValueError(
                f"autoreset_mode: expected one of {list(AUTORESET_MODES)}, got {autoreset_mode!r}"
            )
        self.autoreset_mode = autoreset_mode
        self._autoreset = Autoreset.of(autoreset_mode)
        for argument, value in (
            ("slots_per_world", slots_per_world),
            ("refill_interval", refill_interval),
        ):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{argument}: expected an integer >= 1, got {value!r}")
        self.num_envs = len(random_states)
        self._env = env
        self._random_states = list(random_states)
        self._world_envs = list(world_envs or ())
        if self._world_envs and len(self._world_envs) != self.num_envs:
            raise ValueError(
                f"world_envs: expected one environment per world ({self.num_envs}), got "
                f"{len(self._world_envs)}"
            )
        if self._world_envs and (
            batch_task_type.initial_values is not SuiteBatchTask.initial_values
        ):
            raise NotImplementedError(
                f"{batch_task_type.__name__}: a task whose model is drawn from the seed keeps "
                "no values from its starts yet (initial_values)"
            )
        model_fields = tuple(sorted({*varied_model_fields(task, host), *seeded_fields}))
        self.physics = MujocoBatchPhysics(
            host,
            self.num_envs,
            arrays=arrays.ArrayBridge.host("numpy"),
            batched_model_fields=model_fields,
            threads=threads,
        )
        self._batch_task = batch_task_type(task, host, self.physics)
        start_hosts = [
            StartHost(world_env.task, world_env.physics)
            for world_env in (self._world_envs or [env])
        ]
        maker = SuiteStateMaker(start_hosts, self._batch_task, model_fields)
        self._slots = StateSlots(
            self.physics,
            StateProducer(maker),
            self._random_states,
            model_fields=model_fields,
            slots_per_world=slots_per_world,
            refill_interval=refill_interval,
        )
        self._batch_task.episode_values = self._slots.values
        # dm_control's control.Environment keeps these two as private attributes.
        self._n_sub_steps = int(env._n_sub_steps)
        self._step_limit = env._step_limit
        self._flat_observation = bool(env._flat_observation)
        self._action_shape = (self.num_envs, *env.action_spec().shape)
        self._steps = np.zeros(self.num_envs, np.int64)
        self._ended = np.zeros(self.num_envs, bool)
        self._discount = np.ones(self.num_envs)
        self._final_observation: dict[str, np.ndarray] = {}
        self._started = False

    @property
    def random_states(self) -> list[np.random.RandomState]:
        """Each world's random generator, drawn from by its episode starts (on the producer
        thread, up to `slots_per_world` episodes ahead of the world)."""
        return self._random_states

    def initial_state_stats(self) -> InitialStateStats:
        """How the producer kept up with the episode starts (`InitialStateStats`)."""
        return self._slots.stats

    def action_spec(self):
        """One world's action spec (the CPU environment's); actions are (num_envs, *shape)."""
        return self._env.action_spec()

    def observation_spec(self):
        """One world's observation spec (the CPU environment's); observations have a leading
        num_envs axis."""
        return self._env.observation_spec()

    #: What `reset` and `step` hand out: NumPy arrays (as `BatchEnvironment.array_type`).
    array_type = "numpy"

    @property
    def final_observation(self) -> dict[str, np.ndarray]:
        """With autoreset "same_step": the last observation of the episodes that ended at
        the last step (other worlds' rows are that step's observation)."""
        return self._final_observation

    def episode_ends(self) -> EpisodeEnds:
        """How the last step ended each world's episode, as Gymnasium says it
        (`composer.episode_end`): `terminated` where the task ended it (discount 0),
        `truncated` where the time limit did; bool (num_envs,)."""
        return episode_end.episode_ends(self._ended, self._discount)

    def hand_out(self, value: np.ndarray) -> np.ndarray:
        """`value` as `step` hands arrays out: NumPy, as is."""
        return value

    def reseed(
        self,
        seed: int | np.random.RandomState | None = None,
        *,
        random_states: Sequence[int | np.random.RandomState] | None = None,
    ) -> None:
        """Reseeds every world's generator, as `suite_batch.load` seeds them: from `seed`,
        or world i from `random_states[i]`; the next `step` or `reset` starts every world's
        episode anew.

        Raises:
          ValueError: for `random_states` of other than `num_envs` entries.
          NotImplementedError: for a task whose model is drawn from the seed (lqr's): its
            worlds' models were compiled from their first generators; load it anew.
        """
        if self._world_envs:
            raise NotImplementedError(
                f"reseed: {type(self._env.task).__qualname__}'s model is drawn from each "
                "world's seed when it is loaded; call suite_batch.load with the new seeds"
            )
        self._random_states[:] = world_random_states(self.num_envs, seed, random_states)
        self._slots.restart(self._random_states)
        self._started = False

    def reset(self) -> BatchTimeStep:
        """Starts an episode in every world.

        Returns:
          A `BatchTimeStep`: FIRST everywhere, reward 0, discount 1.
        """
        self._slots.refill(wait=True)
        everything = np.ones(self.num_envs, bool)
        self._start_episodes(everything)
        self._steps = np.zeros(self.num_envs, np.int64)
        self._ended = np.zeros(self.num_envs, bool)
        self._discount = np.ones(self.num_envs)
        self._started = True
        observation = self._observation()
        self._final_observation = observation
        return BatchTimeStep(
            np.full(self.num_envs, _FIRST, np.int8),
            np.zeros(self.num_envs),
            np.ones(self.num_envs),
            observation,
        )

    def step(self, action) -> BatchTimeStep:
        """Steps every world with its row of `action` (num_envs, *action_spec().shape).

        Returns:
          A `BatchTimeStep`: LAST for the worlds whose episode ends at this step; under
          "next_step", FIRST (reward 0, discount 1) for those whose episode ended at the
          last step; MID elsewhere.

        Raises:
          ValueError: for an action of the wrong shape or with NaN or infinity; nothing is
            stepped.
        """
        checked = actions.check_action(
            action,
            self._action_shape,
            self.physics.arrays,
            check_values=False,
            dtype=np.float64,
        )
        if not self._started:
            return self.reset()
        physics, autoreset = self.physics, self._autoreset
        # The suite's `base.Task.before_step`: the action is the control.
        physics.data.ctrl[...] = checked.reshape(self.num_envs, -1)
        physics.step(self._n_sub_steps)
        restarting = autoreset.resets_before_step(self._ended)
        diverged = self._diverged_worlds(restarting)
        if restarting.any():
            # These worlds were stepped with the others; their start overwrites that step.
            self._start_episodes(restarting)
        task = self._batch_task
        reward = task.get_reward()
        termination = task.get_termination()
        steps = np.where(restarting, 0, self._steps + 1)
        # dm_control's order: the time limit ends an episode with discount 1, else the
        # task's termination with its discount.
        at_limit = steps >= self._step_limit
        if termination is None:
            ended = at_limit
            discount = np.ones(self.num_envs)
        else:
            terminated = ~np.isnan(termination)
            ended = at_limit | terminated
            discount = np.where(at_limit | ~terminated, 1.0, termination)
        if diverged is not None:
            # As dm_control's PhysicsError ends the episode: discount 0.
            reward = np.where(diverged, 0.0, reward)
            discount = np.where(diverged, 0.0, discount)
            ended = ended | diverged
        ended &= ~restarting
        step_type = np.where(restarting, _FIRST, np.where(ended, _LAST, _MID)).astype(np.int8)
        reward = np.where(restarting, 0.0, reward)
        discount = np.where(restarting, 1.0, discount)
        observation = self._observation()
        if autoreset is Autoreset.SAME_STEP:
            self._final_observation = observation
            if ended.any():
                self._start_episodes(ended)
                fresh = self._observation()
                observation = {
                    key: np.where(ended.reshape(-1, *[1] * (value.ndim - 1)), fresh[key], value)
                    for key, value in observation.items()
                }
            steps = np.where(ended, 0, steps)
        self._steps, self._ended, self._discount = steps, ended, discount
        self._slots.after_step()
        return BatchTimeStep(step_type, reward, discount, observation)

    def _diverged_worlds(self, restarting: np.ndarray) -> np.ndarray | None:
        """The worlds whose state became invalid in the last physics step (MuJoCo reset
        them) and whose episode this step ends, a bool (num_envs,) mask, logged with a
        warning naming them; None for none. A world restarting at this step is overwritten
        by its start."""
        found = [d for d in self.physics.last_divergences if not restarting[d.world]]
        if not found:
            return None
        logging.warning("Physics error, ending the episode of %s", divergence_report(found))
        diverged = np.zeros(self.num_envs, bool)
        diverged[[d.world for d in found]] = True
        return diverged

    def _observation(self) -> dict[str, np.ndarray]:
        observation = self._batch_task.get_observation()
        if not self._flat_observation:
            return observation
        # dm_control's `flatten_observation`: the values in order, under "observations".
        rows = [np.reshape(value, (self.num_envs, -1)) for value in observation.values()]
        return {"observations": np.concatenate(rows, axis=1)}

    def _start_episodes(self, mask: np.ndarray) -> None:
        """Starts the next episode of the worlds of `mask` from their prepared starts."""
        self._slots.apply(mask)
        # dm_control's `reset_context` ends with a forward pass with actuation disabled:
        # activation actuators (dog's) read differently in the first step's sensors.
        self.physics.forward(mask, actuation=False)

    def close(self) -> None:
        """Stops the producer and closes the CPU environment (dm_env's `close`); the worlds
        are freed with this environment."""
        self._slots.close()
        for env in (self._env, *self._world_envs):
            env.close()
