"""Stable-Baselines3's vector env classes, or an ImportError that says how to install it
(`composer.rl.sb3` and `composer.rl.sb3_batch` import them from here)."""

try:
    from stable_baselines3.common.vec_env import VecEnv, VecMonitor
except ImportError as error:
    raise ImportError(
        "composer.rl.sb3 needs Stable-Baselines3: pip install 'mujoco-composer[sb3]'. "
        "On a machine without a CUDA GPU, install torch's CPU build first (pip install "
        "torch --index-url https://download.pytorch.org/whl/cpu): the default torch "
        "wheel is a CUDA build of several GB."
    ) from error

__all__ = ["VecEnv", "VecMonitor"]
