"""Gymnasium integration: composer environments as `gymnasium.Env` and vector envs.

Importing this package imports `gymnasium` (the optional extra `[gym]`); `import
composer` does not. `RayVectorEnv` needs the extra `[ray]`, imported only when one is made.
"""

from composer.gym.batched import BatchedVectorEnv, SubEnvironmentError
from composer.gym.env import GymnasiumEnv
from composer.gym.ray_vector import RayVectorEnv
from composer.gym.threaded import ThreadedVectorEnv

__all__ = [
    "BatchedVectorEnv",
    "GymnasiumEnv",
    "RayVectorEnv",
    "SubEnvironmentError",
    "ThreadedVectorEnv",
]
