"""Registers the manipulation tasks with Gymnasium as `composer/<name>-v0`.

Importing this module imports `gymnasium` and registers one id per name in
`manipulation.ALL`, e.g. `composer/lift_brick_features-v0`. Users need not import it:
`import manipulation` does when gymnasium is already imported, or else as soon as
gymnasium is (see `manipulation._gymnasium_hook`), and `gymnasium.make` imports
manipulation for an id written `manipulation:composer/<name>-v0`.

Each id's `max_episode_steps` is the number of control steps in the task's time limit (10 s
of 0.04 s steps: 250), after which the environment ends the episode itself (truncated);
Gymnasium's `TimeLimit`, which `gymnasium.make` adds for it, ends it at that same step.

`gymnasium.make(id, **kwargs)` builds `make_env(name, **kwargs)`;
`gymnasium.make_vec(id, num_envs=n, vectorization_mode='vector_entry_point', **kwargs)`
builds `make_vector_env(name, n, **kwargs)`: for the tasks of `manipulation.batch.BATCHED`
(all 26) a `composer.batch.gym.BatchVectorEnv`, every world in one batch (the CPU batch on
`mujoco.batch`, or MuJoCo Warp on a GPU; `device` chooses), unless an option of another
backend is given (below MuJoCo 4.0, which has no `mujoco.batch`, only when a `device` is);
else, or with `backend='threads'`, a `composer.gym.ThreadedVectorEnv`, and
with `backend='ray'` a `composer.gym.RayVectorEnv`. (Gymnasium 1.x refuses `vector_kwargs`
in this mode; the vector env's options go in `kwargs` with the sub-environments' ones.)
"""

import functools
import importlib.util
import inspect
import math
from typing import TYPE_CHECKING

import gymnasium
from gymnasium.vector import AutoresetMode

import manipulation
from manipulation.tasks import task_constants

if TYPE_CHECKING:
    from composer.batch.gym import BatchVectorEnv
    from composer.gym import GymnasiumEnv, RayVectorEnv, ThreadedVectorEnv

__all__ = [
    "MAX_EPISODE_STEPS",
    "NAMESPACE",
    "env_id",
    "make_env",
    "make_vector_env",
    "register_all",
]

NAMESPACE = "composer"
_VERSION = 0


def _episode_steps(time_limit: float, control_timestep: float) -> int:
    """The control steps of an episode: `composer.Environment` ends it at the first step
    whose time reaches the time limit (rounded to absorb the timesteps' float error)."""
    return math.ceil(round(time_limit / control_timestep, 6))


#: The steps after which every manipulation episode is truncated: all tasks share the
#: time limit and the control timestep.
MAX_EPISODE_STEPS = _episode_steps(task_constants.TIME_LIMIT, task_constants.CONTROL_TIMESTEP)


def env_id(environment_name: str) -> str:
    """The Gymnasium id of a manipulation task: 'composer/<name>-v0'."""
    return f"{NAMESPACE}/{environment_name}-v{_VERSION}"


def make_env(environment_name: str, **kwargs) -> "GymnasiumEnv":
    """Returns `manipulation.load(environment_name)` as a `GymnasiumEnv`, its
    observations without the leading buffer axis (`strip_singleton_obs_buffer_dim`).

    Args:
      environment_name: one of `manipulation.ALL`.
      **kwargs: passed to `GymnasiumEnv` (`render_mode`, `camera`, `width`, `height`,
        `flatten_observations`).
    """
    # Imported here: this module may run while composer.gym is being imported.
    from composer.gym import GymnasiumEnv

    env = manipulation.load(environment_name, strip_singleton_obs_buffer_dim=True)
    return GymnasiumEnv(env, **kwargs)


def _make_time_limited_env(environment_name: str, max_episode_steps: int, **kwargs):
    """`make_env(environment_name, **kwargs)` in Gymnasium's `TimeLimit`."""
    return gymnasium.wrappers.TimeLimit(make_env(environment_name, **kwargs), max_episode_steps)


def _shorter_episode_steps(max_episode_steps: int | None) -> int | None:
    """`max_episode_steps` if it ends episodes before the task's time limit does, None if
    it leaves them to it (None, -1 or `MAX_EPISODE_STEPS`).

    Raises:
      ValueError: for a value that is not -1, None or an int in [1, MAX_EPISODE_STEPS].
    """
    if max_episode_steps is None or max_episode_steps in (-1, MAX_EPISODE_STEPS):
        return None
    if (
        not isinstance(max_episode_steps, int)
        or isinstance(max_episode_steps, bool)
        or not 1 <= max_episode_steps < MAX_EPISODE_STEPS
    ):
        raise ValueError(
            f"max_episode_steps: expected an int from 1 to {MAX_EPISODE_STEPS} (the task's "
            f"time limit, {task_constants.TIME_LIMIT:g} s of "
            f"{task_constants.CONTROL_TIMESTEP:g} s steps, ends episodes there), -1 or "
            f"None, got {max_episode_steps!r}"
        )
    return max_episode_steps


def make_vector_env(
    environment_name: str,
    num_envs: int,
    *,
    backend: str | None = None,
    num_threads: int | None = None,
    address: str | None = None,
    envs_per_actor: int | None = None,
    num_cpus_per_actor: float | None = None,
    max_restarts: int | None = None,
    start_timeout: float | None = None,
    call_timeout: float | None = None,
    autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
    copy: bool = True,
    device: str | None = None,
    max_episode_steps: int | None = None,
    **kwargs,
) -> "BatchVectorEnv | ThreadedVectorEnv | RayVectorEnv":
    """Returns a vector env of `num_envs` worlds or copies of `make_env(environment_name)`.

    Args:
      backend: "batch" for a `BatchVectorEnv`: all worlds in one
        `composer.batch.BatchEnvironment` on `device` (by default CUDA when MuJoCo Warp
        sees a GPU, else the CPU batch on `mujoco.batch`), each world the episode of the
        CPU environment seeded alike; kwargs go to the `BatchEnvironment` ("warp" is its
        old name). "threads" for a `ThreadedVectorEnv` (takes `num_threads`), "ray" for a
        `RayVectorEnv` (takes `address`, `envs_per_actor`, `num_cpus_per_actor`,
        `max_restarts`, `start_timeout`, `call_timeout`, defaults as there; needs the extra
        `[ray]`). None picks "batch" for a task of `manipulation.batch.BATCHED` on a MuJoCo
        with `mujoco.batch` when no option of the others is given (those above, shorter
        `max_episode_steps`, or a `GymnasiumEnv` option such as `render_mode` or
        `flatten_observations`), else "threads".
      autoreset_mode, copy: passed to either (the batch hands out new arrays each step).
      max_episode_steps: what `gymnasium.make_vec` passes on (the id's, 250, unless given):
        fewer steps than the task's time limit end each sub-environment's episodes after
        that many steps (truncated, as Gymnasium's `TimeLimit` does), except on "batch"
        (pass `time_limit` there); None, -1 or 250 leave them to the time limit.
      **kwargs: passed to each sub-environment's `GymnasiumEnv`, or to the
        `BatchEnvironment`.

    Raises:
      ValueError: for an unknown backend, an option the backend does not take, or a
        `max_episode_steps` above the task's own (episodes cannot be made longer).
    """
    shorter_episodes = _shorter_episode_steps(max_episode_steps)
    other_options = {
        "num_threads": num_threads,
        "address": address,
        "envs_per_actor": envs_per_actor,
        "num_cpus_per_actor": num_cpus_per_actor,
        "max_restarts": max_restarts,
        "start_timeout": start_timeout,
        "call_timeout": call_timeout,
    }
    given = [name for name, value in other_options.items() if value is not None]
    if backend is None:
        backend = _default_backend(environment_name, given, shorter_episodes, device, kwargs)
    if backend in ("batch", "warp"):
        from manipulation import batch

        if given:
            raise ValueError(f"{given[0]}: not an option of backend={backend!r}")
        if shorter_episodes is not None:
            raise ValueError(
                f"max_episode_steps={max_episode_steps}: not an option of backend={backend!r}; "
                "pass time_limit (seconds) instead"
            )
        kwargs.setdefault("strip_singleton_obs_buffer_dim", True)
        return batch.make_vector_env(environment_name, num_envs, device, autoreset_mode, **kwargs)
    if device is not None:
        raise ValueError(f"device: an option of backend='batch', but backend is {backend!r}")
    from composer.gym import RayVectorEnv, ThreadedVectorEnv

    if shorter_episodes is None:
        env_fn = functools.partial(make_env, environment_name, **kwargs)
    else:
        env_fn = functools.partial(
            _make_time_limited_env, environment_name, shorter_episodes, **kwargs
        )
    if backend == "threads":
        if given and given != ["num_threads"]:
            name = next(name for name in given if name != "num_threads")
            raise ValueError(f"{name}: an option of backend='ray', but backend is 'threads'")
        return ThreadedVectorEnv(
            [env_fn] * num_envs, num_threads, autoreset_mode=autoreset_mode, copy=copy
        )
    if backend == "ray":
        if num_threads is not None:
            raise ValueError(
                "num_threads: an option of backend='threads', but backend is 'ray' (use "
                "envs_per_actor and num_cpus_per_actor)"
            )
        ray_options = {name: other_options[name] for name in given}
        return RayVectorEnv(
            [env_fn] * num_envs,
            **ray_options,
            autoreset_mode=autoreset_mode,
            copy=copy,
        )
    raise ValueError(f"backend: expected 'batch', 'threads', 'ray' or None, got {backend!r}")


def _default_backend(
    environment_name: str,
    given: list[str],
    shorter_episodes: int | None,
    device: str | None,
    kwargs: dict,
) -> str:
    """`make_vector_env`'s backend for None: "batch" where the batch runs the task and
    nothing given asks for a sub-environment backend, else "threads"."""
    from composer.gym import GymnasiumEnv
    from manipulation import batch

    if environment_name not in batch.BATCHED or given or shorter_episodes is not None:
        return "threads"
    if set(kwargs) & set(inspect.signature(GymnasiumEnv).parameters):
        return "threads"
    if device is None and importlib.util.find_spec("mujoco.batch") is None:
        return "threads"
    return "batch"


def register_all() -> None:
    """Registers every task of `manipulation.ALL` that is not registered yet."""
    for name in manipulation.ALL:
        if env_id(name) in gymnasium.registry:
            continue
        gymnasium.register(
            id=env_id(name),
            entry_point=f"{__name__}:make_env",
            vector_entry_point=f"{__name__}:make_vector_env",
            max_episode_steps=MAX_EPISODE_STEPS,
            kwargs={"environment_name": name},
        )


register_all()
