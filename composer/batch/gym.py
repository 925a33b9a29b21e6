"""A `BatchEnvironment` as a `gymnasium.vector.VectorEnv` (imports gymnasium and Warp).

`step` returns `(observations, rewards, terminations, truncations, infos)` for all worlds at
once, with the batch's autoreset mode as Gymnasium names it:
- NEXT_STEP: the step after a world's episode ended resets that world (its action is
  ignored) and returns its first observation with reward 0.
- SAME_STEP: the step in which a world's episode ends resets it and returns the first
  observation of the next episode; the last observation of the ended one is in
  `infos["final_obs"]`, for the worlds of `infos["_final_obs"]`.

An episode that ends with discount 0 (the task ended it) is terminated, one that ends with a
non-zero discount (the time limit) truncated, as in `composer.gym.GymnasiumEnv`.
Observations are the batch's arrays: a dict of (num_envs, ...) float32 arrays (uint8 camera
images), of the batch's `array_type` (NumPy, or Warp, torch or JAX arrays on its device), as
are rewards, terminations and truncations.
"""

from typing import Any

import numpy as np
from gymnasium.spaces import Dict
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from composer.batch.environment import BatchEnvironment, BatchTimeStep
from composer.gym.spec_spaces import box_from_spec

__all__ = ["WarpVectorEnv", "autoreset_mode_name"]

_MODES = {AutoresetMode.NEXT_STEP: "next_step", AutoresetMode.SAME_STEP: "same_step"}


def autoreset_mode_name(mode) -> str:
    """The `BatchEnvironment` autoreset mode of a Gymnasium `AutoresetMode` (or its value).

    Raises:
      ValueError: for DISABLED, which a batch does not offer.
    """
    gymnasium_mode = AutoresetMode(mode)
    if gymnasium_mode not in _MODES:
        raise ValueError(
            f"autoreset_mode: backend 'warp' offers NEXT_STEP and SAME_STEP, got {mode!r}"
        )
    return _MODES[gymnasium_mode]


class WarpVectorEnv(VectorEnv):
    """The worlds of `env` as one Gymnasium vector env.

    Args:
      env: the `BatchEnvironment` to run.

    `reset(seed=s)` reseeds every world's random generator from `s` before resetting all
    worlds; `reset(options=...)` is refused (every reset resets all worlds).
    """

    def __init__(self, env: BatchEnvironment):
        if not isinstance(env, BatchEnvironment):
            raise TypeError(f"env: expected a composer.batch.BatchEnvironment, got {env!r}")
        self.env = env
        self.metadata = {
            "autoreset_mode": AutoresetMode.SAME_STEP
            if env.autoreset_mode == "same_step"
            else AutoresetMode.NEXT_STEP
        }
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
          observations (dict of (num_envs, ...) arrays), rewards (num_envs,) float32,
          terminations and truncations (num_envs,) bool, and infos with 'discount' (and,
          with SAME_STEP, 'final_obs' and '_final_obs'), all of the batch's `array_type`.
        """
        env = self.env
        time_step: BatchTimeStep = env.step(actions)
        ends = env.episode_ends()
        infos = {"discount": time_step.discount}
        if env.autoreset_mode == "same_step":
            infos["final_obs"] = env.final_observation
            infos["_final_obs"] = env.hand_out(ends.terminated | ends.truncated)
        return (
            time_step.observation,
            time_step.reward,
            env.hand_out(ends.terminated),
            env.hand_out(ends.truncated),
            infos,
        )

    def close_extras(self, **kwargs) -> None:
        """Stops the batch's initial-state producers."""
        self.env.close()
