"""What every vector env of this package shares: batching, seeding and autoreset.

`SubEnvVectorEnv` is a `gymnasium.vector.VectorEnv` that keeps the batched outputs in
preallocated arrays and implements Gymnasium's autoreset modes; a subclass says only
where the sub-environments live and how a function reaches them (`_map`). The functions
that run next to a sub-environment (`reset_sub_env`, `step_sub_env`, `call_sub_env`) are
plain module functions of the sub-environment and picklable arguments, so a backend that
runs sub-environments in other threads, processes or machines calls the same ones.

Observations are written once, straight into their batch rows: a backend gives each
sub-environment that is a `GymnasiumEnv` its row (`rows.attach_row`), views of the batched
arrays that it writes its observations into and returns; any other sub-environment's
observation is copied into its row when its outcome is stored.

Autoreset follows Gymnasium's modes (https://farama.org/Vector-Autoreset-Mode) as
`composer.episode_end` defines them: NEXT_STEP resets a sub-environment at the step after
its episode ended, SAME_STEP within that step (its last observation and info then in
`info['final_obs']` and `info['final_info']`, masks `info['_final_obs']`, ...), and under
DISABLED the caller resets it with `reset(options={'reset_mask': mask})` before stepping
it again.
"""

from collections.abc import Callable, Iterable, Sequence
from typing import Any, NamedTuple

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space, iterate

from composer.episode_end import Autoreset
from composer.gym.output_buffer import OutputBuffer
from composer.gym.rows import copied, row_views, row_writer

__all__ = [
    "SubEnvVectorEnv",
    "SubEnvOutcome",
    "SubEnvironmentError",
    "advance_sub_env",
    "call_sub_env",
    "check_spaces_match",
    "reset_sub_env",
    "step_sub_env",
]


# The Python types whose infos `VectorEnv._add_info` batches into arrays of that type.
_INFO_NUMBERS = frozenset((int, float, bool))


class SubEnvironmentError(RuntimeError):
    """A sub-environment raised; `index` says which, the original error is `__cause__`."""

    def __init__(self, index: int, error: BaseException):
        super().__init__(f"sub-environment {index} raised {type(error).__name__}: {error}")
        self.index = index


class SubEnvOutcome(NamedTuple):
    """What one sub-environment returned from a reset or a step.

    `final_observation` and `final_info` are set only when a SAME_STEP autoreset
    replaced the observation of an episode's last step.
    """

    observation: Any
    reward: float
    terminated: bool
    truncated: bool
    info: dict[str, Any]
    final_observation: Any = None
    final_info: dict[str, Any] | None = None


def check_spaces_match(index: int, env: Any, first: Any) -> None:
    """Checks that sub-environment `index` has sub-environment 0's spaces.

    Args:
      index: the index of `env`, for the message.
      env, first: anything with `observation_space` and `action_space` (a
        `gymnasium.Env`, or what a remote host reports of one); `first` is sub-environment 0.

    Raises:
      ValueError: naming `index` and the space that differs.
    """
    for name in ("observation_space", "action_space"):
        if getattr(env, name) != getattr(first, name):
            raise ValueError(
                f"sub-environment {index}: {name.replace('_', ' ')} {getattr(env, name)} "
                f"differs from sub-environment 0's {getattr(first, name)}"
            )


def reset_sub_env(env: gymnasium.Env, seed: int | None, options: dict | None) -> SubEnvOutcome:
    """Resets `env`; reward 0, neither terminated nor truncated."""
    observation, info = env.reset(seed=seed, options=options)
    return SubEnvOutcome(observation, 0.0, False, False, info)


def step_sub_env(
    env: gymnasium.Env, action, autoreset_mode: Autoreset | AutoresetMode, episode_over: bool
) -> SubEnvOutcome:
    """Steps `env`, or resets it as `autoreset_mode` says (see `composer.episode_end`).

    Args:
      episode_over: whether the previous step ended `env`'s episode.
    """
    mode = Autoreset.of(autoreset_mode)
    return SubEnvOutcome(
        *advance_sub_env(
            env,
            action,
            bool(mode.resets_before_step(episode_over)),
            bool(mode.resets_after_step(True)),
        )
    )


def advance_sub_env(env: gymnasium.Env, action, reset_first: bool, reset_at_end: bool) -> tuple:
    """`step_sub_env`'s work with the autoreset decided: the fields of a `SubEnvOutcome`.

    Args:
      reset_first: reset `env` instead of stepping it (its episode ended at the previous
        step and the mode resets at the next one).
      reset_at_end: reset `env` right after a step that ends its episode (SAME_STEP).

    Returns:
      (observation, reward, terminated, truncated, info, final_observation, final_info),
      as a plain tuple: a vector env that stores the fields at once makes no record.
    """
    if reset_first:
        observation, info = env.reset()
        return observation, 0.0, False, False, info, None, None
    observation, reward, terminated, truncated, info = env.step(action)
    if reset_at_end and (terminated or truncated):
        # The reset overwrites the row that an attached sub-environment returned.
        final_observation = copied(observation)
        reset_observation, reset_info = env.reset()
        return reset_observation, reward, terminated, truncated, reset_info, final_observation, info
    return observation, reward, terminated, truncated, info, None, None


def call_sub_env(env: gymnasium.Env, name: str, args: tuple, kwargs: dict) -> Any:
    """Calls `env`'s method `name` (looked up through its wrappers), or returns the attribute."""
    attribute = env.get_wrapper_attr(name)
    return attribute(*args, **kwargs) if callable(attribute) else attribute


def _set_sub_env_attr(env: gymnasium.Env, name: str, value: Any) -> None:
    env.set_wrapper_attr(name, value)


def _render_sub_env(env: gymnasium.Env):
    return env.render()


def _close_sub_env(env: gymnasium.Env) -> None:
    env.close()


class SubEnvVectorEnv(VectorEnv):
    """A `VectorEnv` of `num_envs` sub-environments reached through `_map`.

    `reset(seed=s)` seeds sub-environment i with `s + i` (or `s[i]` for a list);
    `reset(options={'reset_mask': mask})` resets only where `mask` (bool, shape
    (num_envs,)) is True. `step(actions)` returns the batched `(observations, rewards,
    terminations, truncations, infos)`; observations are written into arrays allocated
    once (returned as copies when `copy` is True), infos are batched as Gymnasium does
    (each key with a boolean mask `'_' + key`). After `close()`, every call raises
    `gymnasium.error.ClosedEnvironmentError`.

    Args:
      single_observation_space, single_action_space: one sub-environment's spaces.
      num_envs: the number of sub-environments.
      autoreset_mode: an `AutoresetMode` or its value (see `composer.episode_end`).
      metadata: the sub-environments' metadata; 'autoreset_mode' is added.
      render_mode: the sub-environments' render mode.
      copy: return copies of the observation arrays rather than the arrays themselves
        (which the next `step` or `reset` overwrites). A step's copies are never written
        again while anything refers to them (or to a view of them); the memory of those
        nobody holds any more is reused (see `output_buffer`).
    """

    def __init__(
        self,
        single_observation_space: gymnasium.Space,
        single_action_space: gymnasium.Space,
        num_envs: int,
        *,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        metadata: dict[str, Any] | None = None,
        render_mode: str | None = None,
        copy: bool = True,
    ):
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self._autoreset = Autoreset.of(self.autoreset_mode)
        self.num_envs = num_envs
        self.metadata = {**(metadata or {}), "autoreset_mode": self.autoreset_mode}
        self.render_mode = render_mode
        self.copy = copy
        self.single_observation_space = single_observation_space
        self.single_action_space = single_action_space
        self.observation_space = batch_space(single_observation_space, num_envs)
        self.action_space = batch_space(single_action_space, num_envs)
        # The batched outputs live in one buffer, copied out with one copy per step.
        self._outputs = OutputBuffer(single_observation_space, num_envs)
        live = self._outputs.live
        self._observations = live.observations
        self._rewards = live.rewards
        self._terminations = live.terminations
        self._truncations = live.truncations
        # Row i's views are what sub-environment i writes into (see `rows.attach_row`).
        self._rows = [row_views(self._observations, i) for i in range(num_envs)]
        self._row_writers = [row_writer(row) for row in self._rows]
        # Read and written per sub-environment on every step: a list of bools is cheaper
        # there than an array. The autoreset rule is applied to one ended episode here,
        # once, rather than on every step.
        self._episode_over = [False] * num_envs
        self._refuses_after_end = bool(self._autoreset.refuses_step(True))
        self._over_after_end = bool(self._autoreset.over_after_step(True))
        self._box_actions = isinstance(self.action_space, gymnasium.spaces.Box)

    def _map(
        self,
        function: Callable[..., Any],
        arguments: dict[int, tuple],
        store: Callable[[int, Any], None] | None = None,
    ) -> dict[int, Any]:
        """Returns {i: function(sub_env_i, *arguments[i])} for each i in `arguments`.

        With `store`, also calls `store(i, result)` once per result before returning,
        from whichever thread is convenient (calls for different i touch different data).
        Every listed sub-environment runs its call even when another raises.

        Raises:
          SubEnvironmentError: for the lowest index whose call raised.
        """
        raise NotImplementedError

    def _reset_sub_envs(self, arguments: dict[int, tuple]) -> dict[int, SubEnvOutcome]:
        """Runs `reset_sub_env` with `arguments` and stores the outcomes (a backend that
        can lose sub-environments overrides it to report them)."""
        return self._map(reset_sub_env, arguments, self._store)

    def _step_sub_envs(self, arguments: dict[int, tuple]) -> dict[int, SubEnvOutcome]:
        """Runs `step_sub_env` with `arguments` and stores the outcomes (a backend that
        can lose sub-environments overrides it to report them)."""
        return self._map(step_sub_env, arguments, self._store)

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[Any, dict[str, Any]]:
        """Resets every sub-environment, or those in `options['reset_mask']`.

        Returns:
          The batched observations and infos.

        Raises:
          ValueError: for a seed list whose length is not `num_envs`, or a reset mask
            that is not a bool array of shape (num_envs,) with at least one True.
          SubEnvironmentError: if a sub-environment raised.
        """
        self._check_open()
        seeds = self._seeds(seed)
        options = dict(options or {})
        mask = self._reset_mask(options.pop("reset_mask", None))
        sub_options = options or None
        indices = np.flatnonzero(mask).tolist()
        outcomes = self._reset_sub_envs({i: (seeds[i], sub_options) for i in indices})
        return self._observations_out(), self._batched_infos(outcomes.items())

    def step(self, actions) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Steps every sub-environment with its row of `actions`, autoresetting as set.

        Returns:
          observations, rewards (float64), terminations and truncations (bool), infos.

        Raises:
          ValueError: if `actions` does not hold one action per sub-environment.
          RuntimeError: in DISABLED mode, if a sub-environment whose episode is over was
            not reset.
          SubEnvironmentError: if a sub-environment raised.
        """
        self._check_open()
        episode_over = self._episode_over
        if self._refuses_after_end and True in episode_over:
            raise RuntimeError(
                f"sub-environments {[i for i, over in enumerate(episode_over) if over]} "
                "ended their episodes and autoreset_mode is DISABLED: reset them with "
                "reset(options={'reset_mask': mask}) before stepping"
            )
        # A Box's batch is an array whose rows are the actions: no need for `iterate`.
        if self._box_actions and isinstance(actions, np.ndarray) and actions.ndim:
            rows = actions
        else:
            rows = list(iterate(self.action_space, actions))
        if len(rows) != self.num_envs:
            raise ValueError(
                f"actions: expected one per sub-environment ({self.num_envs}), got {len(rows)}"
            )
        infos = self._step_rows(rows)
        if self.copy:
            return (*self._outputs.copy(), infos)
        return (
            self._observations,
            self._rewards.copy(),
            self._terminations.copy(),
            self._truncations.copy(),
            infos,
        )

    def _step_rows(self, rows: Sequence[Any]) -> dict[str, Any]:
        """Steps sub-environment i with `rows[i]` for every i, stores the outcomes and
        returns the batched infos (a backend may take a shorter way to the same)."""
        mode, episode_over = self._autoreset, self._episode_over
        # The arguments hold each episode's state from before the step, which `_store`
        # then updates.
        outcomes = self._step_sub_envs(
            {i: (action, mode, episode_over[i]) for i, action in enumerate(rows)}
        )
        return self._batched_infos(outcomes.items())

    def render(self) -> tuple[Any, ...]:
        """Returns each sub-environment's `render()`, in order."""
        self._check_open()
        return self._in_order(self._map(_render_sub_env, self._all(())))

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """Calls method `name` of every sub-environment (or reads the attribute)."""
        self._check_open()
        return self._in_order(self._map(call_sub_env, self._all((name, args, kwargs))))

    def get_attr(self, name: str) -> tuple[Any, ...]:
        """Returns attribute `name` of every sub-environment."""
        return self.call(name)

    def set_attr(self, name: str, values: Any) -> None:
        """Sets attribute `name` of every sub-environment: `values[i]` for a list or
        tuple (of length `num_envs`), otherwise the same value everywhere.

        Raises:
          ValueError: for a list or tuple whose length is not `num_envs`.
        """
        if not isinstance(values, list | tuple):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(
                f"set_attr({name!r}): expected {self.num_envs} values, got {len(values)}"
            )
        self._check_open()
        self._map(_set_sub_env_attr, {i: (name, value) for i, value in enumerate(values)})

    def apply(
        self, function: Callable[..., Any], *args: Any, indices: Sequence[int] | None = None
    ) -> tuple[Any, ...]:
        """Returns `function(sub_env, *args)` for each sub-environment in `indices`.

        Each call runs where its sub-environment lives (its thread, or its Ray actor: there
        `function` and `args` must pickle, and `function` is best a module-level function of
        a module the actor can import cheaply).

        Args:
          function: called with a sub-environment (the `gymnasium.Env` built for it) and `args`.
          indices: which sub-environments, in the order of the results; None for all.

        Raises:
          ValueError: for an index outside [0, num_envs) or given twice.
          SubEnvironmentError: if a call raised.
        """
        self._check_open()
        order = list(range(self.num_envs)) if indices is None else self._indices(indices)
        results = self._map(function, dict.fromkeys(order, args))
        return tuple(results[i] for i in order)

    def close_extras(self, **kwargs: Any) -> None:
        """Closes every sub-environment."""
        self._map(_close_sub_env, self._all(()))

    def _check_open(self) -> None:
        """Raises `gymnasium.error.ClosedEnvironmentError` once `close()` was called."""
        if self.closed:
            raise gymnasium.error.ClosedEnvironmentError(f"this {type(self).__name__} is closed")

    def _all(self, arguments: tuple) -> dict[int, tuple]:
        return dict.fromkeys(range(self.num_envs), arguments)

    def _in_order(self, results: dict[int, Any]) -> tuple[Any, ...]:
        return tuple(results[i] for i in range(self.num_envs))

    def _indices(self, indices: Sequence[int]) -> list[int]:
        order = list(indices)
        integers = all(isinstance(i, int | np.integer) and not isinstance(i, bool) for i in order)
        if (
            not integers
            or len(set(order)) != len(order)
            or not all(0 <= i < self.num_envs for i in order)
        ):
            raise ValueError(
                f"indices: expected distinct sub-environment indices in [0, {self.num_envs}), "
                f"got {list(indices)!r}"
            )
        return [int(i) for i in order]

    def _seeds(self, seed) -> list[int | None]:
        if seed is None:
            return [None] * self.num_envs
        if isinstance(seed, int | np.integer):
            return [int(seed) + i for i in range(self.num_envs)]
        seeds = list(seed)
        if len(seeds) != self.num_envs:
            raise ValueError(
                f"seed: expected None, an int or {self.num_envs} seeds (one per "
                f"sub-environment), got {len(seeds)}"
            )
        return seeds

    def _reset_mask(self, mask) -> np.ndarray:
        if mask is None:
            return np.ones(self.num_envs, dtype=np.bool_)
        if (
            not isinstance(mask, np.ndarray)
            or mask.dtype != np.bool_
            or mask.shape != (self.num_envs,)
            or not mask.any()
        ):
            raise ValueError(
                f"options['reset_mask']: expected a bool array of shape ({self.num_envs},) "
                f"with at least one True, got {mask!r}"
            )
        return mask

    def _store(self, index: int, outcome: SubEnvOutcome) -> None:
        """Writes one sub-environment's outcome into row `index` of the batched arrays."""
        observation, reward, terminated, truncated = outcome[:4]
        if observation is not self._rows[index]:  # not written there already
            self._row_writers[index](observation)
        self._rewards[index] = reward
        self._terminations[index] = terminated
        self._truncations[index] = truncated
        self._episode_over[index] = self._over_after_end and bool(terminated or truncated)

    def _observations_out(self):
        return self._outputs.copy_observations() if self.copy else self._observations

    def _batched_infos(self, outcomes: Iterable[tuple[int, tuple]]) -> dict[str, Any]:
        """Gymnasium's batching of the outcomes' infos (`VectorEnv._add_info`).

        Args:
          outcomes: (index, outcome) pairs in index order, each outcome a `SubEnvOutcome`
            or the plain tuple of its fields (`advance_sub_env`'s).

        Common infos take shorter ways to `_add_info`'s results, without its calls: a
        number (int, float, bool or NumPy number) whose key is new gets the column and mask
        `_add_info` would make for it (zeros of the number's type, and of bools), and a key
        already batched as an array, with its mask, by an earlier sub-environment is
        filled in. The adapter's 'discount' takes these ways on every step.
        """
        infos: dict[str, Any] = {}
        for i, outcome in outcomes:
            info, final_observation, final_info = outcome[4:]
            if final_info is not None:
                infos = self._add_info(
                    infos, {"final_obs": final_observation, "final_info": final_info}, i
                )
            for key, value in info.items():
                column = infos.get(key)
                mask_key = "_" + key
                if column is None:
                    kind = type(value)
                    if (kind in _INFO_NUMBERS or issubclass(kind, np.number)) and (
                        mask_key not in infos and key != "final_obs"
                    ):
                        column = infos[key] = np.zeros(self.num_envs, dtype=kind)
                        column[i] = value
                        mask = infos[mask_key] = np.zeros(self.num_envs, dtype=np.bool_)
                        mask[i] = True
                        continue
                elif type(column) is np.ndarray and key != "final_obs":
                    mask = infos.get(mask_key)
                    if type(mask) is np.ndarray and not isinstance(value, dict):
                        column[i] = value
                        mask[i] = True
                        continue
                infos = self._add_info(infos, {key: value}, i)
        return infos
