"""rsl_rl's `VecEnv` over a batched composer environment (`composer.batch`, MuJoCo Warp).

rsl_rl (the PyPI package `rsl-rl-lib`, the extra `[rsl_rl]`) trains on torch tensors that
stay on the simulation's device. `RslRlVecEnv` hands it the batch's own torch views: the
observations, concatenated per world into the group "policy", rewards, dones and the time
outs it bootstraps on (`composer.episode_end`'s terminated and truncated), with no copy to
the host.

```python
import manipulation.batch
from composer.rl.rsl_rl import RslRlVecEnv

env = RslRlVecEnv(manipulation.batch.load(
    "reach_site_features", 1024, seed=0,
    array_type="torch", autoreset_mode="same_step"))
```

`rsl_rl.runners.OnPolicyRunner(env, train_cfg, device=env.device)` then trains on it
(`examples/train_rsl_rl.py`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from composer.observation import flattening

try:
    import torch
    from rsl_rl.env import VecEnv
    from tensordict import TensorDict
except ImportError as error:  # the extra is missing
    raise ImportError(
        "composer.rl.rsl_rl needs rsl_rl and torch: pip install 'mujoco-composer[rsl_rl]' "
        "(without a GPU, first install torch's CPU build: pip install torch "
        "--index-url https://download.pytorch.org/whl/cpu)"
    ) from error

if TYPE_CHECKING:
    from composer.batch import BatchEnvironment

#: The observation group the concatenated features are handed out as; rsl_rl's
#: actor and critic read it unless the runner's `obs_groups` say otherwise.
OBSERVATION_GROUP = "policy"


class RslRlVecEnv(VecEnv):
    """A `composer.batch.BatchEnvironment` as rsl_rl's `VecEnv`.

    The environment must hand out torch tensors (`array_type="torch"`) and reset a world
    within the step that ends its episode (`autoreset_mode="same_step"`), as rsl_rl
    expects, and have a time limit (rsl_rl's `max_episode_length`).

    Actions: rsl_rl's policies act in [-1, 1] per dimension. Each action is clipped to
    [-1, 1] and mapped linearly onto the action spec's bounds (-1 to the minimum, 1 to the
    maximum) before the batch steps.

    Observations: the group "policy" is float32 (num_envs, N), the features (see
    `composer.observation.flattening`) flattened per world and concatenated in the
    observation dict's order. Camera images are flattened into it too unless `images` says
    "apart", which makes each image a group of its own, named by its observation, float32
    (num_envs, *its shape), for a convolutional policy.

    `step` returns what rsl_rl's runner expects:
      observations: a `TensorDict` of the groups above.
      rewards: float32 (num_envs,).
      dones: int64 (num_envs,): 1 where an episode ended (`composer.episode_end`'s
        terminated or truncated); the observation of such a world is already the next
        episode's first.
      extras: {"time_outs": bool (num_envs,)}, the episodes truncated (by the time limit).

    Args:
      env: the batch environment to train on.
      images: `flattening.IMAGES_FLATTENED` ("flattened", the default, as this adapter has
        always done) or `flattening.IMAGES_APART` ("apart").

    Attributes:
      num_envs, num_actions, max_episode_length, device, cfg: rsl_rl's `VecEnv` contract.
      episode_length_buf: the control steps of each world's episode; rsl_rl sets it to
        random lengths at the start of training (`init_at_random_ep_len=True`).

    Raises:
      ValueError: when the environment hands out no torch tensors, does not autoreset in
        the same step, or has no time limit; for any other `images`, or images kept
        apart that leave no features or take the name "policy".
    """

    def __init__(self, env: BatchEnvironment, *, images: str = flattening.IMAGES_FLATTENED):
        if env.array_type != "torch":
            raise ValueError(
                f"env: rsl_rl trains on torch tensors; expected a batch environment with "
                f"array_type='torch', got array_type={env.array_type!r}"
            )
        if env.autoreset_mode != "same_step":
            raise ValueError(
                "env: rsl_rl expects a world to restart within the step that ends it; "
                f"expected autoreset_mode='same_step', got {env.autoreset_mode!r}"
            )
        if env.max_episode_steps is None:
            raise ValueError(
                "env: rsl_rl needs a maximum episode length; expected a batch environment "
                "with a finite time_limit, got none"
            )
        self._split = flattening.flat_split(env.observation_spec(), images=images)
        if not self._split.features:
            raise ValueError(
                f"images: {images!r} leaves no features for rsl_rl's {OBSERVATION_GROUP!r} "
                f"group (the observations are all camera images); use "
                f"{flattening.IMAGES_FLATTENED!r}"
            )
        if OBSERVATION_GROUP in self._split.images:
            raise ValueError(
                f"images: the camera observation {OBSERVATION_GROUP!r} kept apart would take "
                "the name of rsl_rl's feature group; rename the observable or flatten images"
            )
        self._env = env
        spec = env.action_spec()
        self.num_envs = env.num_envs
        self.num_actions = int(np.prod(spec.shape))
        self.max_episode_length = env.max_episode_steps
        self.cfg = {
            "autoreset_mode": env.autoreset_mode,
            "max_episode_steps": env.max_episode_steps,
        }
        first = env.reset()
        self.device = next(iter(first.observation.values())).device
        self._low = torch.tensor(np.array(spec.minimum), dtype=torch.float32, device=self.device)
        self._half_range = torch.as_tensor(
            (np.asarray(spec.maximum) - np.asarray(spec.minimum)) / 2.0,
            dtype=torch.float32,
            device=self.device,
        )
        self._observations = self._pack(first.observation)

    @property
    def unwrapped(self) -> BatchEnvironment:
        """The batch environment this adapter steps."""
        return self._env

    @property
    def episode_length_buf(self) -> torch.Tensor:
        return self._env.episode_steps

    @episode_length_buf.setter
    def episode_length_buf(self, steps: torch.Tensor) -> None:
        self._env.episode_steps = steps

    def get_observations(self) -> TensorDict:
        """The observations of the last `reset` or `step` (see the class docstring)."""
        return self._observations

    def reset(self) -> TensorDict:
        """Starts a new episode in every world; returns the first observations."""
        self._observations = self._pack(self._env.reset().observation)
        return self._observations

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        """Steps every world with `actions` (num_envs, num_actions) in [-1, 1]; see the
        class docstring for what it returns."""
        scaled = self._low + (actions.clamp(-1.0, 1.0) + 1.0) * self._half_range
        timestep = self._env.step(scaled)
        ends = self._env.episode_ends()
        time_outs = self._env.hand_out(ends.truncated)
        dones = (self._env.hand_out(ends.terminated) | time_outs).to(torch.long)
        self._observations = self._pack(timestep.observation)
        return self._observations, timestep.reward, dones, {"time_outs": time_outs}

    def close(self) -> None:
        """Closes the batch environment."""
        self._env.close()

    def _pack(self, observation: dict) -> TensorDict:
        features = torch.cat(
            [
                observation[name].reshape(self.num_envs, -1).to(torch.float32)
                for name in self._split.features
            ],
            dim=1,
        )
        groups = {OBSERVATION_GROUP: features}
        groups.update((name, observation[name].to(torch.float32)) for name in self._split.images)
        return TensorDict(groups, batch_size=[self.num_envs], device=self.device)
