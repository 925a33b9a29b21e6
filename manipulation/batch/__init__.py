"""The manipulation tasks batched on MuJoCo Warp: `load(name, num_envs)`.

Every environment of the suite has a batched version (`BATCHED`): the '<task>_features' ones
(`BATCHED_FEATURES`) and the '<task>_vision' ones (`BATCHED_VISION`), whose 'front_close'
camera renders for every world (OpenGL on the CPU batch, `composer.batch.gl_cameras`;
MuJoCo Warp's ray tracer on Warp, `composer.batch.cameras`). Each task
family registers its `composer.batch.BatchTask` in a module of its own (`reach`, `lift`,
`place`, `stack`, `reassemble`); `arm_observables` registers the batched readers of the arm's
observables, `seating` and `brick_tower` hold what the place, stack and reassemble tasks
share, `reward_kernels` the rewards written as Warp kernels (lift's). Rewards, observations
and initial states are those of the CPU tasks: the initial states come from the CPU task's own
initializers (`composer.batch.InitialStateSource.CPU_TASK`), the
rewards are the same formulas on arrays. Needs the extra `[warp]` to build an environment;
importing this package does not import Warp.
"""

import functools

from composer import batch
from manipulation.batch import arm_observables  # noqa: F401  (registers the arm's readers)
from manipulation.batch.lift import BatchLift
from manipulation.batch.place import BatchPlace
from manipulation.batch.reach import BatchReach
from manipulation.batch.reassemble import BatchReassemble
from manipulation.batch.stack import BatchStack
from manipulation.tasks import registry
from manipulation.tasks import task_constants as tc

__all__ = [
    "BATCHED",
    "BATCHED_FEATURES",
    "BATCHED_VISION",
    "BatchLift",
    "BatchPlace",
    "BatchReach",
    "BatchReassemble",
    "BatchStack",
    "load",
    "make_vector_env",
]

#: The environment names whose observations are ground-truth features.
BATCHED_FEATURES = registry.names_with_tag("features")
#: The environment names whose observations include the 'front_close' camera's images.
BATCHED_VISION = registry.names_with_tag("vision")
#: The environment names with a batched version: every environment of the suite.
BATCHED = BATCHED_FEATURES + BATCHED_VISION


def _check_batched(environment_name: str) -> None:
    """Raises ValueError, listing the batched names, for a name without a batched version."""
    if environment_name not in BATCHED:
        raise ValueError(
            f"environment_name: expected one of {list(BATCHED)} (the batched tasks), got "
            f"{environment_name!r}"
        )


def load(environment_name: str, num_envs: int, *, seed=None, **kwargs) -> batch.BatchEnvironment:
    """Returns `num_envs` worlds of the manipulation task `environment_name`, batched.

    Args:
      environment_name: one of `BATCHED`.
      num_envs: the number of worlds.
      seed: an int, a `np.random.RandomState` or None; seeds each world's generator.
      **kwargs: passed to `composer.batch.BatchEnvironment` (`device`, `random_states`,
        `array_type`, `autoreset_mode`, `state_workers`, `time_limit`: the CPU task's
        10 s unless given, ...). Initial-state producers build their tasks by name.

    Returns:
      A `composer.batch.BatchEnvironment` whose worlds each match
      `manipulation.load(environment_name)` seeded alike.

    Raises:
      ValueError: if the name is not one of `BATCHED`.
    """
    _check_batched(environment_name)
    task = registry.build_task(environment_name)
    kwargs.setdefault("time_limit", tc.TIME_LIMIT)
    kwargs.setdefault("task_factory", functools.partial(registry.build_task, environment_name))
    return batch.BatchEnvironment(task, num_envs, random_state=seed, **kwargs)


def make_vector_env(
    environment_name: str, num_envs: int, device: str | None, autoreset_mode, **kwargs
):
    """`load(...)` as a `composer.batch.gym.BatchVectorEnv` (`gymnasium.make_vec`'s backend
    'batch', with Gymnasium's NEXT_STEP or SAME_STEP autoreset); imports gymnasium.

    Raises:
      ValueError: for Gymnasium's DISABLED autoreset mode.
    """
    from composer.batch.gym import BatchVectorEnv, autoreset_mode_name

    mode = autoreset_mode_name(autoreset_mode)
    env = load(environment_name, num_envs, device=device, autoreset_mode=mode, **kwargs)
    return BatchVectorEnv(env)
