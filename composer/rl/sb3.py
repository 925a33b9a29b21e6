"""Stable-Baselines3's `VecEnv` over this project's Gymnasium vector envs.

`Sb3VecEnv` runs a `composer.gym.ThreadedVectorEnv` or `RayVectorEnv` (made with
`autoreset_mode=SAME_STEP`) as a `stable_baselines3.common.vec_env.VecEnv`, so SB3's
algorithms (`PPO`, `SAC`, ...), its wrappers (`VecNormalize`, `VecMonitor`) and
`evaluate_policy` train and evaluate on it directly; `make_vec_env` builds one from a
registered id or an environment factory (with `backend='batch'`, a batch of worlds in a
`composer.rl.sb3_batch.Sb3BatchVecEnv`, which keeps the same conventions). Importing this
module imports
Stable-Baselines3 and torch (the extra `[sb3]`); `import composer` does not.

SB3's conventions, as `step_wait` keeps them (those of SB3's own `DummyVecEnv`):

- `dones[i]` is `terminated or truncated` (as `composer.episode_end` maps a dm_env
  episode's end); a sub-environment whose episode ended was reset in the same step
  (SAME_STEP autoreset, done by the vector env on the sub-environment's own thread or
  actor), and its row of the observations is the new episode's first observation.
- For that sub-environment, `infos[i]` is the info of the episode's last step (with
  whatever the environment puts there at an episode's end, such as `is_success` or
  Gymnasium's `RecordEpisodeStatistics` 'episode', which SB3's callbacks and loggers
  read), plus `infos[i]['terminal_observation']`, the episode's last observation; the
  reset's info is in `reset_infos[i]`.
- `infos[i]['TimeLimit.truncated']` is `truncated and not terminated`, on every step;
  SB3's off-policy algorithms bootstrap from the terminal observation when it is True.
- Rewards are float32, dones bool, observations a batched array (or a dict of them, for
  SB3's `MultiInputPolicy`) with a leading axis of `num_envs`.
"""

from collections.abc import Callable, Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode

from composer.gym.sub_env_vector import SubEnvironmentError, SubEnvVectorEnv
from composer.rl import _sub_env
from composer.rl._sb3_import import VecEnv, VecMonitor

__all__ = ["BACKENDS", "Sb3VecEnv", "make_vec_env"]

# The vector env backends `make_vec_env` takes (as the registered ids' `make_vec` names them).
BACKENDS = ("threads", "ray", "batch")

# What Gymnasium's SAME_STEP autoreset adds to the infos of a step that ended episodes.
_AUTORESET_KEYS = frozenset({"final_obs", "_final_obs", "final_info", "_final_info"})


def _unbatch_infos(infos: dict[str, Any], num_envs: int) -> list[dict[str, Any]]:
    """Splits Gymnasium's batched infos (each key with its mask '_key') into one dict per
    sub-environment, holding the keys its mask marks (nested dicts split likewise)."""
    rows: list[dict[str, Any]] = [{} for _ in range(num_envs)]
    for key, value in infos.items():
        if key.startswith("_") and key[1:] in infos:
            continue
        mask = infos.get("_" + key)
        present = range(num_envs) if mask is None else np.flatnonzero(mask).tolist()
        if isinstance(value, dict):
            parts = _unbatch_infos(value, num_envs)
            for i in present:
                rows[i][key] = parts[i]
        else:
            for i in present:
                rows[i][key] = value[i]
    return rows


class Sb3VecEnv(VecEnv):
    """A `composer.gym` vector env as a Stable-Baselines3 `VecEnv`.

    See the module docstring for what `step_wait` returns. `seed(s)` seeds sub-environment
    i with `s + i` at the next `reset()` (as SB3's algorithms call them), `set_options`
    gives the next `reset()` its options (the same for every sub-environment, as the
    vector env takes one options dict). `env_method`, `get_attr`, `set_attr` and
    `env_is_wrapped` run on the chosen sub-environments only, each where it lives (its
    thread or Ray actor). With `render_mode='rgb_array'`, `render()` returns the
    sub-environments' frames tiled in one image. `close()` closes the vector env.

    Args:
      vector_env: a `composer.gym.ThreadedVectorEnv` or `RayVectorEnv` with
        `autoreset_mode=AutoresetMode.SAME_STEP` and `copy=True` (SB3 keeps the previous
        step's observations while it takes the next step). `gymnasium.make_vec(id,
        num_envs, vectorization_mode='vector_entry_point', autoreset_mode='SameStep')`
        makes one for a registered composer id; `make_vec_env` does it all.

    Raises:
      TypeError: if `vector_env` is not a `composer.gym.SubEnvVectorEnv`.
      ValueError: if its autoreset mode is not SAME_STEP, or it does not copy.
    """

    def __init__(self, vector_env: SubEnvVectorEnv):
        if not isinstance(vector_env, SubEnvVectorEnv):
            raise TypeError(
                "vector_env: expected a composer.gym.ThreadedVectorEnv or RayVectorEnv, got "
                f"{type(vector_env).__name__}"
            )
        if vector_env.autoreset_mode is not AutoresetMode.SAME_STEP:
            raise ValueError(
                f"vector_env: expected autoreset_mode SAME_STEP (SB3 resets a finished "
                f"episode in the step that ends it), got {vector_env.autoreset_mode}; make "
                "it with autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP"
            )
        if not vector_env.copy:
            raise ValueError(
                "vector_env: expected copy=True (SB3 keeps the observations of one step "
                "while it takes the next), got a vector env made with copy=False"
            )
        self.vector_env = vector_env
        self._actions: Any = None
        super().__init__(
            vector_env.num_envs,
            vector_env.single_observation_space,
            vector_env.single_action_space,
        )
        self.metadata = {**vector_env.metadata, **self.metadata}
        # VecMonitor names the environment after its spec in its log files.
        self.spec = vector_env.spec

    def reset(self):
        """Resets every sub-environment, with the seeds of the last `seed()` and the
        options of the last `set_options()` (each used once), and returns the batched
        observations; the infos are in `reset_infos`.

        Raises:
          ValueError: if `set_options` gave the sub-environments different options.
        """
        seeds = None if all(seed is None for seed in self._seeds) else list(self._seeds)
        options = self._options[0] or None
        if any(other != self._options[0] for other in self._options):
            raise ValueError(
                "set_options: expected one options dict for every sub-environment (the "
                f"vector env passes the same options to each), got {self._options!r}"
            )
        observations, infos = self.vector_env.reset(seed=seeds, options=options)
        self.reset_infos = _unbatch_infos(infos, self.num_envs)
        self._reset_seeds()
        self._reset_options()
        return observations

    def step_async(self, actions: np.ndarray) -> None:
        """Keeps `actions` (one row per sub-environment) for `step_wait`."""
        self._actions = actions

    def step_wait(self):
        """Steps every sub-environment with the actions of `step_async`.

        Returns:
          observations (batched, as the observation space), rewards (num_envs,) float32,
          dones (num_envs,) bool, and a list of `num_envs` info dicts (see the module
          docstring).

        Raises:
          composer.gym.SubEnvironmentError: if a sub-environment raised.
        """
        actions, self._actions = self._actions, None
        if actions is None:
            raise RuntimeError("step_wait() called without step_async(actions) before it")
        observations, rewards, terminations, truncations, infos = self.vector_env.step(actions)
        dones = terminations | truncations
        final_infos = _unbatch_infos(infos.get("final_info", {}), self.num_envs)
        step_infos = _unbatch_infos(
            {key: value for key, value in infos.items() if key not in _AUTORESET_KEYS},
            self.num_envs,
        )
        time_limits = (truncations & ~terminations).tolist()
        for i in np.flatnonzero(dones).tolist():
            # The vector env reset it: the step's info is the episode's last.
            self.reset_infos[i] = step_infos[i]
            step_infos[i] = final_infos[i]
            step_infos[i]["terminal_observation"] = infos["final_obs"][i]
        for info, time_limit in zip(step_infos, time_limits):
            info["TimeLimit.truncated"] = time_limit
        return observations, rewards.astype(np.float32), dones, step_infos

    def close(self) -> None:
        """Closes the vector env and its sub-environments."""
        self.vector_env.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        """Each sub-environment's `render()`, in order (frames with 'rgb_array')."""
        return list(self.vector_env.render())

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        """Attribute `attr_name` of the sub-environments `indices` (all for None)."""
        return self._apply(_sub_env.get_attr, attr_name, indices=indices)

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        """Sets attribute `attr_name` to `value` on the sub-environments `indices`."""
        self._apply(_sub_env.set_attr, attr_name, value, indices=indices)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        """Calls method `method_name` of the sub-environments `indices`; their results."""
        return self._apply(
            _sub_env.call_method, method_name, method_args, method_kwargs, indices=indices
        )

    def env_is_wrapped(
        self, wrapper_class: type[gymnasium.Wrapper], indices: Any = None
    ) -> list[bool]:
        """Whether each sub-environment of `indices` is wrapped with `wrapper_class`."""
        return self._apply(_sub_env.is_wrapped, wrapper_class, indices=indices)

    def _apply(self, function: Callable[..., Any], *args: Any, indices: Any) -> list[Any]:
        try:
            results = self.vector_env.apply(function, *args, indices=self._get_indices(indices))
        except SubEnvironmentError as error:
            # SB3 asks `has_attr` and `render_mode` by catching AttributeError.
            if isinstance(error.__cause__, AttributeError):
                raise AttributeError(str(error)) from error
            raise
        return list(results)


def make_vec_env(
    env: str | Callable[[], gymnasium.Env],
    num_envs: int,
    *,
    seed: int | None = None,
    backend: str = "threads",
    monitor: bool = True,
    **kwargs: Any,
) -> VecEnv:
    """Builds `num_envs` sub-environments in a vector env of `backend`, for SB3.

    The vector env runs Gymnasium's SAME_STEP autoreset (as `Sb3VecEnv` needs).

    Args:
      env: a registered Gymnasium id with a vector entry point (such as
        'composer/reach_site_features-v0'), made with `gymnasium.make_vec(env, num_envs,
        vectorization_mode='vector_entry_point', backend=backend, **kwargs)`; or a
        function returning a new `gymnasium.Env` on each call.
      num_envs: the number of sub-environments.
      seed: with an int, sub-environment i is seeded with `seed + i` at the first
        `reset()`; None leaves them unseeded.
      backend: 'threads' for a `composer.gym.ThreadedVectorEnv`, 'ray' for a
        `composer.gym.RayVectorEnv` (the extra `[ray]`), 'batch' (an id of
        `manipulation.batch.BATCHED` only) for a `composer.batch.gym.BatchVectorEnv` in a
        `composer.rl.sb3_batch.Sb3BatchVecEnv`, which takes `flatten_observations` itself
        and gives the other kwargs to the `BatchEnvironment` (`device`, `time_limit`, ...).
      monitor: wrap the result in SB3's `VecMonitor`, which puts each finished episode's
        return and length in `info['episode']` (SB3 logs them as `rollout/ep_rew_mean`,
        `evaluate_policy` reads them).
      **kwargs: for an id, its options (the sub-environments', such as
        `flatten_observations`, and the vector env's, such as `num_threads` or Ray's
        `envs_per_actor`); for a function, the vector env's options only.

    Returns:
      An `Sb3VecEnv` (an `Sb3BatchVecEnv` for 'batch'), in a `VecMonitor` when `monitor`
      is True.

    Raises:
      ValueError: for an unknown `backend`, `num_envs` < 1, an id without a vector entry
        point, or an `autoreset_mode` in `kwargs`.
      TypeError: if `env` is neither a string nor callable, or an id's vector entry point
        does not make a composer.gym vector env.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend: expected one of {BACKENDS}, got {backend!r}")
    if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
        raise ValueError(f"num_envs: expected an integer >= 1, got {num_envs!r}")
    if "autoreset_mode" in kwargs:
        raise ValueError(
            "autoreset_mode: make_vec_env always uses SAME_STEP (SB3's convention), got "
            f"{kwargs['autoreset_mode']!r}"
        )
    mode = AutoresetMode.SAME_STEP
    if backend == "batch":
        venv = _batch_vec_env(env, int(num_envs), mode, kwargs)
    elif isinstance(env, str):
        entry_point = gymnasium.spec(env).vector_entry_point
        if entry_point is None:
            raise ValueError(
                f"env: {env!r} has no vector entry point; pass a function that makes one "
                f"environment instead (lambda: gymnasium.make({env!r}))"
            )
        try:
            vector_env = gymnasium.make_vec(
                env,
                num_envs=int(num_envs),
                vectorization_mode="vector_entry_point",
                backend=backend,
                autoreset_mode=mode,
                **kwargs,
            )
        except TypeError as error:
            raise TypeError(
                f"env: the vector entry point of {env!r} ({entry_point}) refused "
                f"make_vec_env's options: {error}. It must make a composer.gym "
                "ThreadedVectorEnv or RayVectorEnv (taking backend and autoreset_mode)"
            ) from error
    elif callable(env):
        from composer.gym import RayVectorEnv, ThreadedVectorEnv

        vector_class = ThreadedVectorEnv if backend == "threads" else RayVectorEnv
        vector_env = vector_class([env] * int(num_envs), autoreset_mode=mode, **kwargs)
    else:
        raise TypeError(
            "env: expected a registered Gymnasium id or a function returning a "
            f"gymnasium.Env, got {type(env).__name__}"
        )
    if backend != "batch":
        venv = Sb3VecEnv(vector_env)
    if seed is not None:
        venv.seed(seed)
    return VecMonitor(venv) if monitor else venv


def _batch_vec_env(env: Any, num_envs: int, mode: AutoresetMode, kwargs: dict) -> VecEnv:
    """`make_vec_env`'s backend 'batch': the id's `BatchVectorEnv` in an `Sb3BatchVecEnv`."""
    if not isinstance(env, str):
        raise TypeError(
            "env: backend 'batch' needs the registered id of a batched task (such as "
            f"'composer/reach_site_features-v0'), got {type(env).__name__}"
        )
    from composer.rl.sb3_batch import Sb3BatchVecEnv

    flatten = bool(kwargs.pop("flatten_observations", False))
    vector_env = gymnasium.make_vec(
        env,
        num_envs=num_envs,
        vectorization_mode="vector_entry_point",
        backend="batch",
        autoreset_mode=mode,
        **kwargs,
    )
    return Sb3BatchVecEnv(vector_env, flatten_observations=flatten)
