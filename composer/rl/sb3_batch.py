"""Stable-Baselines3's `VecEnv` over a batch: `Sb3BatchVecEnv`.

`composer.rl.sb3.Sb3VecEnv` runs vector envs of sub-environments; this runs a
`composer.batch.gym.BatchVectorEnv` (all worlds in one `BatchEnvironment`, the CPU batch on
`mujoco.batch` or MuJoCo Warp), keeping the same conventions (those of SB3's
`DummyVecEnv`, listed in `composer.rl.sb3`): `dones[i]` is `terminated or truncated`, a
world whose episode ended was reset in the same step (SAME_STEP autoreset) and
`infos[i]['terminal_observation']` is its episode's last observation,
`infos[i]['TimeLimit.truncated']` is `truncated and not terminated`, rewards are float32.
`composer.rl.sb3.make_vec_env(id, n, backend='batch')` builds one. Imports
Stable-Baselines3 (the extra `[sb3]`).

A batch has no sub-environment objects: `env_method` and `set_attr` are refused,
`get_attr` reads the vector env's attribute (the same for every world), `env_is_wrapped`
is False for every world, and there are no frames to render.
"""

from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode

from composer.batch.gym import BatchVectorEnv
from composer.gym.spec_spaces import FlatObservations
from composer.rl._sb3_import import VecEnv

__all__ = ["Sb3BatchVecEnv"]


class Sb3BatchVecEnv(VecEnv):
    """A `BatchVectorEnv` as a Stable-Baselines3 `VecEnv` (see the module docstring).

    Args:
      vector_env: a `composer.batch.gym.BatchVectorEnv` with SAME_STEP autoreset and NumPy
        arrays (`array_type="numpy"`, the default).
      flatten_observations: concatenate every feature observation into one vector per
        world, in the order and layout `composer.gym.GymnasiumEnv(flatten_observations=
        True)` gives one environment (for SB3's `MlpPolicy`).

    `seed(s)` seeds world i with `s + i` at the next `reset()`, as SB3's algorithms call it.

    Raises:
      TypeError: if `vector_env` is not a `BatchVectorEnv`.
      ValueError: if its autoreset mode is not SAME_STEP or its arrays are not NumPy.
    """

    def __init__(self, vector_env: BatchVectorEnv, *, flatten_observations: bool = False):
        if not isinstance(vector_env, BatchVectorEnv):
            raise TypeError(
                "vector_env: expected a composer.batch.gym.BatchVectorEnv, got "
                f"{type(vector_env).__name__}"
            )
        if vector_env.metadata["autoreset_mode"] is not AutoresetMode.SAME_STEP:
            raise ValueError(
                "vector_env: expected autoreset_mode SAME_STEP (SB3 resets a finished episode "
                f"in the step that ends it), got {vector_env.metadata['autoreset_mode']}"
            )
        if vector_env.env.array_type != "numpy":
            raise ValueError(
                "vector_env: expected array_type 'numpy' (SB3 takes NumPy arrays), got "
                f"{vector_env.env.array_type!r}"
            )
        self.vector_env = vector_env
        self._flat = (
            FlatObservations(vector_env.env.observation_spec()) if flatten_observations else None
        )
        space = vector_env.single_observation_space if self._flat is None else self._flat.space
        self._actions: Any = None
        super().__init__(vector_env.num_envs, space, vector_env.single_action_space)
        self.metadata = {**vector_env.metadata, **self.metadata}
        self.spec = vector_env.spec

    def _observations(self, observations: dict[str, np.ndarray]) -> Any:
        if self._flat is None:
            return observations
        return self._flat.rows(observations)

    def reset(self):
        """Resets every world, with the seeds of the last `seed()` (used once); returns
        the observations (the infos, empty, are in `reset_infos`).

        Raises:
          ValueError: if `set_options` gave options (a batch reset takes none).
        """
        if any(self._options):
            raise ValueError(
                f"set_options: a batch's reset takes no options, got {self._options!r}"
            )
        seeds = None if all(seed is None for seed in self._seeds) else list(self._seeds)
        observations, _ = self.vector_env.reset(seed=seeds)
        self.reset_infos = [{} for _ in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return self._observations(observations)

    def step_async(self, actions: np.ndarray) -> None:
        """Keeps `actions` (one row per world) for `step_wait`."""
        self._actions = actions

    def step_wait(self):
        """Steps every world with the actions of `step_async`.

        Returns:
          observations, rewards (num_envs,) float32, dones (num_envs,) bool, and a list of
          `num_envs` info dicts (see the module docstring).
        """
        actions, self._actions = self._actions, None
        if actions is None:
            raise RuntimeError("step_wait() called without step_async(actions) before it")
        observations, rewards, terminations, truncations, infos = self.vector_env.step(actions)
        dones = terminations | truncations
        time_limits = (truncations & ~terminations).tolist()
        step_infos: list[dict[str, Any]] = [
            {"TimeLimit.truncated": time_limit} for time_limit in time_limits
        ]
        ended = np.flatnonzero(dones)
        if ended.size:
            final = self._observations(infos["final_obs"])
            for i in ended.tolist():
                step_infos[i]["terminal_observation"] = _row(final, i)
        return self._observations(observations), rewards.astype(np.float32), dones, step_infos

    def close(self) -> None:
        """Closes the vector env (and the batch's producers)."""
        self.vector_env.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        """Refused: a batch renders no frames of its own (its camera observables are in
        the observations)."""
        raise NotImplementedError(
            "render: a batch renders no frames; camera observables are in the observations"
        )

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        """The vector env's attribute `attr_name`, once per world of `indices`.

        Raises:
          AttributeError: if the vector env has no such attribute.
        """
        value = getattr(self.vector_env, attr_name)
        return [value] * len(self._get_indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        """Refused: the worlds of a batch are not objects with attributes."""
        raise NotImplementedError(
            f"set_attr({attr_name!r}): the worlds of a batch have no attributes of their own"
        )

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        """Refused: the worlds of a batch are not objects with methods."""
        raise NotImplementedError(
            f"env_method({method_name!r}): the worlds of a batch have no methods of their own"
        )

    def env_is_wrapped(
        self, wrapper_class: type[gymnasium.Wrapper], indices: Any = None
    ) -> list[bool]:
        """False for every world: no Gymnasium wrapper wraps a world of a batch."""
        return [False] * len(self._get_indices(indices))


def _row(observations: Any, i: int) -> Any:
    """World i's observation from batched ones (an array or a dict of arrays)."""
    if isinstance(observations, dict):
        return {key: value[i] for key, value in observations.items()}
    return observations[i]
