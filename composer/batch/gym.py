"""A `BatchEnvironment` as a `gymnasium.vector.VectorEnv` (imports gymnasium and Warp).

`step` returns `(observations, rewards, terminations, truncations, infos)` for all worlds at
once, with Gymnasium's NEXT_STEP autoreset: the step after a world's episode ended resets
that world (its action is ignored) and returns its first observation with reward 0. An
episode that ends with discount 0 (the task ended it) is terminated, one that ends with a
non-zero discount (the time limit) truncated, as in `composer.gym.GymnasiumEnv`.
Observations are the batch's arrays: a dict of (num_envs, ...) float32 arrays, of the
batch's `array_type` (NumPy, or Warp, torch or JAX arrays on its device), as are rewards,
terminations and truncations.
"""

from typing import Any

import numpy as np
from gymnasium.spaces import Dict
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from composer.batch.environment import BatchEnvironment, BatchTimeStep
from composer.gym.spec_spaces import box_from_spec

__all__ = ["WarpVectorEnv"]


class WarpVectorEnv(VectorEnv):
    """The worlds of `env` as one Gymnasium vector env.

    Args:
      env: the `BatchEnvironment` to run.

    `reset(seed=s)` reseeds every world's random generator from `s` before resetting all
    worlds; `reset(options=...)` is refused (every reset resets all worlds).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, env: BatchEnvironment):
        if not isinstance(env, BatchEnvironment):
            raise TypeError(f"env: expected a composer.batch.BatchEnvironment, got {env!r}")
        self.env = env
        self.num_envs = env.num_envs
        self.single_observation_space = Dict(
            {key: box_from_spec(spec) for key, spec in env.observation_spec().items()}
        )
        self.single_action_space = box_from_spec(env.action_spec())
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Resets every world.

        Returns:
          (observations, infos): a dict of (num_envs, ...) arrays and an empty dict.

        Raises:
          ValueError: if `options` is given.
        """
        if options:
            raise ValueError(
                f"options: a WarpVectorEnv resets all worlds and takes no options, got {options!r}"
            )
        if seed is not None:
            self.env.reseed(seed)
        return self.env.reset().observation, {}

    def step(
        self, actions
    ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict]:
        """Steps every world (see the module docstring for autoreset).

        Returns:
          observations (dict of (num_envs, ...) arrays), rewards (num_envs,) float64,
          terminations and truncations (num_envs,) bool, and infos with 'discount', all
          of the batch's `array_type`.
        """
        time_step: BatchTimeStep = self.env.step(actions)
        ends = self.env.episode_ends()
        return (
            time_step.observation,
            time_step.reward,
            self.env.hand_out(ends.terminated),
            self.env.hand_out(ends.truncated),
            {"discount": time_step.discount},
        )
