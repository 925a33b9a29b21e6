"""dm_control's Control Suite batched: many worlds of one suite task on `mujoco.batch`.

`load(domain_name, task_name, num_envs)` mirrors `dm_control.suite.load` and returns a
`SuiteBatchEnvironment` whose world i is, bit for bit, the episode of
`suite.load(domain_name, task_name, task_kwargs={"random": seed_i})` (world i's seed by
the batch's rule, `composer.batch.environment.world_random_states`). The suite's code and
models come from the installed dm_control at run time, through this project's redirect;
dm_control is not a dependency of this project (`pip install dm-control --no-deps scipy`).

The array code lives in `suite_batch.domains`, one module per domain (`BATCHED` lists the
suite task classes it covers); a task without it raises NotImplementedError naming it.
"""

import importlib
import pkgutil
from collections.abc import Mapping, Sequence

import numpy as np

from composer.batch.environment import world_random_states
from composer.batch.variations import PROBE_SEEDS
from suite_batch import domains, loading, tasks
from suite_batch.environment import SuiteBatchEnvironment
from suite_batch.episode_starts import seeded_model_fields

__all__ = ["BATCHED", "SuiteBatchEnvironment", "load"]

for _module in pkgutil.iter_modules(domains.__path__):
    importlib.import_module(f"{domains.__name__}.{_module.name}")

#: The suite task classes with array code ("dm_control.suite.cartpole.Balance"), each
#: with its `SuiteBatchTask`.
BATCHED: Mapping[str, type[tasks.SuiteBatchTask]] = tasks.registered()


def load(
    domain_name: str,
    task_name: str,
    num_envs: int,
    *,
    task_kwargs: Mapping | None = None,
    environment_kwargs: Mapping | None = None,
    seed: int | np.random.RandomState | None = None,
    random_states: Sequence[int | np.random.RandomState] | None = None,
    threads: int | None = None,
    autoreset_mode: str = "next_step",
    slots_per_world: int = 3,
    refill_interval: int = 8,
) -> SuiteBatchEnvironment:
    """`num_envs` worlds of the suite task `domain_name`-`task_name`, batched.

    Args:
      domain_name, task_name: as `suite.load`'s (a pair of `suite.ALL_TASKS`).
      num_envs: the number of worlds (>= 1).
      task_kwargs: as `suite.load`'s (`time_limit`, ...), without `random`: each world's
        generator comes from `seed` or `random_states`.
      environment_kwargs: as `suite.load`'s (`n_sub_steps`, `flat_observation`, ...).
      seed: an int seed or generator from which each world's generator is seeded
        (ignored when `random_states` is given).
      random_states: one int seed or `np.random.RandomState` per world.
      threads: the C threads that step the worlds (None: the cores this process may use).
      autoreset_mode: "next_step" or "same_step", as in `SuiteBatchEnvironment`.
      slots_per_world, refill_interval: how far ahead the producer thread makes episode
        starts, as in `SuiteBatchEnvironment`.

    Returns:
      A `SuiteBatchEnvironment`.

    Raises:
      ImportError: without dm_control installed, saying what to install.
      ValueError: for an unknown domain or task (naming the closest ones), a `random` in
        `task_kwargs`, or a bad `num_envs`, `random_states`, `threads`, `autoreset_mode`,
        `slots_per_world` or `refill_interval`.
      NotImplementedError: for a task without array code yet, or one whose episode starts
        vary a model field the batch cannot give each world.
    """
    suite = loading.import_suite()
    loading.check_task_name(suite, domain_name, task_name)
    if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
        raise ValueError(f"num_envs: expected an integer >= 1, got {num_envs!r}")
    task_kwargs = dict(task_kwargs or {})
    if "random" in task_kwargs:
        raise ValueError(
            "task_kwargs: 'random' seeds one environment; pass seed= or random_states= (one "
            "per world) instead"
        )
    env = suite.load(domain_name, task_name, task_kwargs, environment_kwargs)
    batch_task_type = tasks.for_task(env.task)
    if batch_task_type is None:
        env.close()
        raise NotImplementedError(
            f"{domain_name}-{task_name} ({type(env.task).__qualname__}): no array code yet; "
            f"batched domains: {', '.join(tasks.batched_domains())}"
        )
    generators = world_random_states(int(num_envs), seed, random_states)

    def seeded(random_state):
        return suite.load(
            domain_name, task_name, {**task_kwargs, "random": random_state}, environment_kwargs
        )

    # A task whose model is drawn from its seed (lqr's) compiles differently per seed: each
    # world then starts on its own CPU environment, and gets its row of those fields.
    probe = seeded(np.random.RandomState(PROBE_SEEDS[0]))
    try:
        seeded_fields = seeded_model_fields(
            env.physics.model.ptr, probe.physics.model.ptr, f"{domain_name}-{task_name}"
        )
    finally:
        probe.close()
    world_envs = [seeded(generator) for generator in generators] if seeded_fields else None
    return SuiteBatchEnvironment(
        env,
        batch_task_type,
        generators,
        world_envs=world_envs,
        seeded_fields=seeded_fields,
        threads=threads,
        autoreset_mode=autoreset_mode,
        slots_per_world=slots_per_world,
        refill_interval=refill_interval,
    )
