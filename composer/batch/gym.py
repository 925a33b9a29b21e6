"""A `BatchEnvironment` as a `gymnasium.vector.VectorEnv` (imports gymnasium; Warp only
where the batch runs on MuJoCo Warp).

`step` returns `(observations, rewards, terminations, truncations, infos)` for all worlds at
once. Terminations, truncations and the batch's autoreset mode (NEXT_STEP or SAME_STEP) are
those of `composer.episode_end`; under SAME_STEP the last observations of the ended
episodes are in `infos["final_obs"]`, for the worlds of `infos["_final_obs"]`.
Observations are the batch's arrays: a dict of (num_envs, ...) arrays of the batch's float
dtype (float64 on the CPU batch, float32 on MuJoCo Warp; uint8 camera images), of the
batch's `array_type` (NumPy, or Warp, torch or JAX arrays on its device), as are rewards,
terminations and truncations.

`BatchVectorEnv` was called `WarpVectorEnv` when the batch ran on MuJoCo Warp only; that
name still works.
"""

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium.spaces import Dict
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from composer.batch.environment import AUTORESET_MODES, BatchTimeStep
from composer.episode_end import Autoreset
from composer.gym.spec_spaces import box_from_spec

if TYPE_CHECKING:
    from composer.batch.environment import BatchEnvironment

__all__ = ["BATCH_INTERFACE", "BatchVectorEnv", "WarpVectorEnv", "autoreset_mode_name"]


def autoreset_mode_name(mode) -> str:
    """The `BatchEnvironment` autoreset mode of a Gymnasium `AutoresetMode` (or its value).

    Raises:
      ValueError: for DISABLED, which a batch does not offer.
    """
    name = Autoreset.of(AutoresetMode(mode)).value
    if name not in AUTORESET_MODES:
        raise ValueError(
            f"autoreset_mode: backend 'batch' offers NEXT_STEP and SAME_STEP, got {mode!r}"
        )
    return name


#: What `BatchVectorEnv` uses of its environment: `BatchEnvironment`'s batch interface,
#: which `suite_batch.SuiteBatchEnvironment` (dm_control's Control Suite batched) has too.
BATCH_INTERFACE = (
    "num_envs",
    "autoreset_mode",
    "observation_spec",
    "action_spec",
    "reseed",
    "reset",
    "step",
    "episode_ends",
    "final_observation",
    "hand_out",
    "close",
)


class BatchVectorEnv(VectorEnv):
    """The worlds of `env` as one Gymnasium vector env.

    Args:
      env: the `BatchEnvironment` to run, or another environment with its batch interface
        (`BATCH_INTERFACE`), such as `suite_batch.SuiteBatchEnvironment`.

    `reset(seed=s)` seeds world i with `s + i` (or `s[i]` for a list of `num_envs` ints), as
    Gymnasium's vector envs and `composer.gym.ThreadedVectorEnv` seed their sub-environments,
    before resetting all worlds: world i then plays the episodes of the CPU environment
    reset with that seed. `reset(options=...)` is refused (every reset resets all worlds).
    """

    def __init__(self, env: "BatchEnvironment"):
        missing = [name for name in BATCH_INTERFACE if not hasattr(env, name)]
        if missing:
            raise TypeError(
                f"env: expected a composer.batch.BatchEnvironment (or an environment with its "
                f"batch interface), got {env!r}, which lacks {missing}"
            )
        self.env = env
        self._autoreset = Autoreset.of(env.autoreset_mode)
        self.metadata = {"autoreset_mode": AutoresetMode(self._autoreset.gymnasium_value)}
        self.num_envs = env.num_envs
        self.single_observation_space = Dict(
            {key: box_from_spec(spec) for key, spec in env.observation_spec().items()}
        )
        self.single_action_space = box_from_spec(env.action_spec())
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def reset(
        self,
        *,
        seed: int | Sequence[int] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Resets every world.

        Returns:
          (observations, infos): a dict of (num_envs, ...) arrays and an empty dict.

        Raises:
          ValueError: if `options` is given, or `seed` is a list of other than `num_envs`
            ints (None entries included: every world is reseeded at once).
        """
        if options:
            raise ValueError(
                f"options: a BatchVectorEnv resets all worlds and takes no options, got {options!r}"
            )
        if seed is not None:
            self.env.reseed(random_states=_world_seeds(seed, self.num_envs))
        return self.env.reset().observation, {}

    def step(
        self, actions
    ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict]:
        """Steps every world (see `composer.episode_end` for autoreset).

        Returns:
          observations (dict of (num_envs, ...) arrays), rewards (num_envs,) float32,
          terminations and truncations (num_envs,) bool, and infos with 'discount' (and,
          with SAME_STEP, 'final_obs' and '_final_obs'), all of the batch's `array_type`.
        """
        env = self.env
        time_step: BatchTimeStep = env.step(actions)
        ends = env.episode_ends()
        infos = {"discount": time_step.discount}
        if self._autoreset is Autoreset.SAME_STEP:
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


# The name of `BatchVectorEnv` from when the batch ran on MuJoCo Warp only.
WarpVectorEnv = BatchVectorEnv


def _world_seeds(seed, num_envs: int) -> list[int]:
    """One seed per world from `reset`'s `seed`: `seed + i`, or the list's ints."""
    if isinstance(seed, int | np.integer) and not isinstance(seed, bool):
        return [int(seed) + i for i in range(num_envs)]
    seeds = list(seed) if isinstance(seed, Sequence | np.ndarray) else None
    if (
        seeds is None
        or len(seeds) != num_envs
        or not all(isinstance(s, int | np.integer) and not isinstance(s, bool) for s in seeds)
    ):
        raise ValueError(
            f"seed: expected None, an int or {num_envs} ints (one per world; the batch "
            f"reseeds every world at once), got {seed!r}"
        )
    return [int(s) for s in seeds]
