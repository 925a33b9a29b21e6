"""The batched Control Suite through Gymnasium: `make_vec` of a suite id picks the batch.

Importing this module (it imports gymnasium) registers every task of `suite.ALL_TASKS`
under the id Shimmy gives it, `dm_control/<domain>-<task>-v0` (`env_id`), with this
module's `make_vector_env` as its `vector_entry_point`:

    envs = gymnasium.make_vec("dm_control/cartpole-swingup-v0", num_envs=256)

builds a `composer.batch.gym.BatchVectorEnv` over `suite_batch.load("cartpole", "swingup",
256)`: Gymnasium's `make_vec` uses a registered `vector_entry_point` unless told another
vectorization mode. Without importing this module first, write the id as
`"suite_batch.gym:dm_control/cartpole-swingup-v0"`, which imports it. Where Shimmy has
registered the id already, its `gymnasium.make` stays Shimmy's and only the vector entry
point is added; elsewhere `gymnasium.make(id)` gives one suite env through
`composer.gym.GymnasiumEnv`.

`reset(seed=s)` of the vector env seeds world i with `s + i`, so world i plays the episodes
of `suite.load(domain, task, task_kwargs={"random": s + i})`. Episodes end at the suite's
own time limit (truncated, discount 1) or at the task's termination (terminated, discount
0): no Gymnasium `TimeLimit` is added.
"""

import functools
from typing import Any

import gymnasium

from composer.batch.gym import BatchVectorEnv
from composer.episode_end import Autoreset
from composer.gym import GymnasiumEnv
from suite_batch import loading

__all__ = ["NAMESPACE", "env_id", "make_env", "make_vector_env", "register_all"]

#: Shimmy's namespace of the suite's ids.
NAMESPACE = "dm_control"


def env_id(domain_name: str, task_name: str) -> str:
    """The Gymnasium id of a suite task, as Shimmy names it: "dm_control/cartpole-swingup-v0"."""
    return f"{NAMESPACE}/{domain_name}-{task_name}-v0"


def make_vector_env(
    domain_name: str,
    task_name: str,
    num_envs: int,
    *,
    autoreset_mode: Any = "next_step",
    **kwargs: Any,
) -> BatchVectorEnv:
    """`num_envs` worlds of the suite task as one Gymnasium vector env.

    Args:
      domain_name, task_name: a pair of `suite.ALL_TASKS`.
      num_envs: the number of worlds.
      autoreset_mode: "next_step" or "same_step", or Gymnasium's `AutoresetMode` (NEXT_STEP
        or SAME_STEP).
      **kwargs: the other arguments of `suite_batch.load` (`task_kwargs`,
        `environment_kwargs`, `seed`, `threads`, ...).

    Returns:
      A `composer.batch.gym.BatchVectorEnv`.

    Raises:
      ValueError, ImportError, NotImplementedError: as `suite_batch.load`.
    """
    import suite_batch

    env = suite_batch.load(
        domain_name,
        task_name,
        num_envs,
        autoreset_mode=Autoreset.of(autoreset_mode).value,
        **kwargs,
    )
    return BatchVectorEnv(env)


def make_env(domain_name: str, task_name: str, **kwargs: Any) -> GymnasiumEnv:
    """One suite env (`suite.load(domain_name, task_name, **kwargs)`, through the redirect)
    through `composer.gym.GymnasiumEnv`; `reset(seed=s)` reseeds its task's generator, which
    then draws as `task_kwargs={"random": s}`'s."""
    env = loading.import_suite().load(domain_name, task_name, **kwargs)
    # GymnasiumEnv seeds an environment's `random_state`; a suite env's is its task's.
    env.random_state = env.task.random
    return GymnasiumEnv(env)


def register_all() -> None:
    """Registers every task of `suite.ALL_TASKS` (see the module docstring)."""
    suite = loading.import_suite()
    for domain_name, task_name in suite.ALL_TASKS:
        name = env_id(domain_name, task_name)
        # As Shimmy's entry points, the names are bound in, leaving the spec's kwargs free.
        vector_entry_point = functools.partial(make_vector_env, domain_name, task_name)
        if name in gymnasium.registry:
            spec = gymnasium.registry[name]
            if spec.vector_entry_point is None:
                spec.vector_entry_point = vector_entry_point
            continue
        gymnasium.register(
            id=name,
            entry_point=functools.partial(make_env, domain_name, task_name),
            vector_entry_point=vector_entry_point,
        )


register_all()
