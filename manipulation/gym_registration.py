"""Registers the manipulation tasks with Gymnasium as `composer/<name>-v0`.

Importing this module imports `gymnasium` and registers one id per name in
`manipulation.ALL`, e.g. `composer/lift_brick_features-v0`. Users need not import it:
`import manipulation` does when gymnasium is already imported, or else as soon as
gymnasium is (see `manipulation._gymnasium_hook`), and `gymnasium.make` imports
manipulation for an id written `manipulation:composer/<name>-v0`.

`gymnasium.make(id, **kwargs)` builds `make_env(name, **kwargs)`;
`gymnasium.make_vec(id, num_envs=n, vectorization_mode='vector_entry_point', **kwargs)`
builds `make_vector_env(name, n, **kwargs)`, a `composer.gym.ThreadedVectorEnv`.
"""

import functools
from typing import TYPE_CHECKING

import gymnasium
from gymnasium.vector import AutoresetMode

import manipulation

if TYPE_CHECKING:
    from composer.gym import GymnasiumEnv, ThreadedVectorEnv

__all__ = ["NAMESPACE", "env_id", "make_env", "make_vector_env", "register_all"]

NAMESPACE = "composer"
_VERSION = 0


def env_id(environment_name: str) -> str:
    """The Gymnasium id of a manipulation task: 'composer/<name>-v0'."""
    return f"{NAMESPACE}/{environment_name}-v{_VERSION}"


def make_env(environment_name: str, **kwargs) -> "GymnasiumEnv":
    """Returns `manipulation.load(environment_name)` as a `GymnasiumEnv`.

    Args:
      environment_name: one of `manipulation.ALL`.
      **kwargs: passed to `GymnasiumEnv` (`render_mode`, `camera`, `width`, `height`,
        `flatten_observations`).
    """
    # Imported here: this module may run while composer.gym is being imported.
    from composer.gym import GymnasiumEnv

    return GymnasiumEnv(manipulation.load(environment_name), **kwargs)


def make_vector_env(
    environment_name: str,
    num_envs: int,
    *,
    num_threads: int | None = None,
    autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
    copy: bool = True,
    **kwargs,
) -> "ThreadedVectorEnv":
    """Returns a `ThreadedVectorEnv` of `num_envs` copies of `make_env(environment_name)`.

    Args:
      num_threads, autoreset_mode, copy: passed to `ThreadedVectorEnv`.
      **kwargs: passed to each sub-environment's `GymnasiumEnv`.
    """
    from composer.gym import ThreadedVectorEnv

    env_fn = functools.partial(make_env, environment_name, **kwargs)
    return ThreadedVectorEnv(
        [env_fn] * num_envs, num_threads, autoreset_mode=autoreset_mode, copy=copy
    )


def register_all() -> None:
    """Registers every task of `manipulation.ALL` that is not registered yet."""
    for name in manipulation.ALL:
        if env_id(name) in gymnasium.registry:
            continue
        gymnasium.register(
            id=env_id(name),
            entry_point=f"{__name__}:make_env",
            vector_entry_point=f"{__name__}:make_vector_env",
            kwargs={"environment_name": name},
        )


register_all()
