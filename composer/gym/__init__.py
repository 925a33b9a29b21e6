"""Gymnasium integration: composer environments as `gymnasium.Env`, vector envs, and videos.

This package is this project's own (dm_control has no Gymnasium integration). Importing it
imports `gymnasium` (the optional extra `[gym]`); `import composer` does not. `RayVectorEnv`
needs the extra `[ray]`, imported only when one is made; `VideoRecorder` writes its videos
with the extra `[video]`, imported on its first recorded episode.
"""

from composer.gym.env import GymnasiumEnv
from composer.gym.ray_vector import RayVectorEnv
from composer.gym.sub_env_vector import SubEnvironmentError, SubEnvVectorEnv
from composer.gym.threaded import ThreadedVectorEnv
from composer.gym.video_recorder import VideoRecorder

__all__ = [
    "SubEnvVectorEnv",
    "GymnasiumEnv",
    "RayVectorEnv",
    "SubEnvironmentError",
    "ThreadedVectorEnv",
    "VideoRecorder",
]
