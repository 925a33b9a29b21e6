"""`RayVectorEnv`: sub-environments in Ray actors, on one machine or a cluster.

Needs the optional extra `[ray]`; Ray is imported when a `RayVectorEnv` is made, never
when this module is imported. Each actor (a `composer.gym._ray_host.SubEnvHost`) holds
`envs_per_actor` consecutive sub-environments on its own threads, so one actor call per
vector step steps all of them. Batching, seeding and autoreset are `BatchedVectorEnv`'s,
and the per-sub-environment functions are the same module functions the threaded
vector env runs, so with the same seeds and actions the results are bit-identical.

Fault tolerance. An actor that dies (its process is killed or crashes) is replaced by a
new one whose sub-environments are built afresh, at most `max_restarts` times per actor.
When that happens during `step`, the other actors' results of that step are kept, and
each of the dead actor's sub-environments reports its episode truncated, with reward 0
and `info['restarted']` True:

- NEXT_STEP and DISABLED: the observation is the last one it returned; it is reset on
  the next step (NEXT_STEP) or by the caller (DISABLED), as after any truncation. A
  sub-environment that was due to be reset on this step is reset at once instead.
- SAME_STEP: the observation is the new episode's reset observation, and
  `info['final_obs']` holds the last observation it returned.

Any other call (`reset`, `call`, `render`, ...) is run again on the new actor; a reset
marks the restarted sub-environments with `info['restarted']` too. A sub-environment
that raises is not restarted: the call raises `SubEnvironmentError` with its index, as
with the threaded vector env, and the vector env can go on after a `reset`.
"""

import functools
import math
import numbers
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium
from gymnasium.vector import AutoresetMode

from composer.gym._ray_host import HostSpec, SubEnvFailure, SubEnvHost, pack, unpack
from composer.gym.batched import (
    BatchedVectorEnv,
    SubEnvironmentError,
    SubEnvOutcome,
    read_row,
    reset_sub_env,
    step_sub_env,
)

__all__ = ["RayVectorEnv"]


def _import_ray():
    try:
        import ray
    except ImportError as error:
        raise ImportError(
            "RayVectorEnv needs Ray: pip install 'mujoco-composer[ray]' (or pip install ray)"
        ) from error
    return ray


@functools.cache
def _host_actor_class():
    return _import_ray().remote(SubEnvHost)


def _env_fns_for(
    env_fns: Sequence[Callable[[], gymnasium.Env]] | str, num_envs: int | None
) -> list[Callable[[], gymnasium.Env]]:
    if isinstance(env_fns, str):
        if num_envs is None:
            raise ValueError(f"num_envs: expected an integer >= 1 for the id {env_fns!r}, got None")
        _check_count("num_envs", num_envs, minimum=1)
        # The spec (not the id) travels: its entry point imports the registering module
        # in the actor's process, where the id is not registered.
        return [functools.partial(gymnasium.make, gymnasium.spec(env_fns))] * num_envs
    env_fns = list(env_fns)
    if not env_fns:
        raise ValueError("env_fns: expected at least one environment factory, got none")
    if num_envs is not None and num_envs != len(env_fns):
        raise ValueError(
            f"num_envs: expected None or len(env_fns) = {len(env_fns)}, got {num_envs!r}"
        )
    return env_fns


def _check_count(name: str, value: Any, minimum: int) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {value!r}")


class RayVectorEnv(BatchedVectorEnv):
    """A `gymnasium.vector.VectorEnv` whose sub-environments live in Ray actors.

    Actor k holds sub-environments k * envs_per_actor up to (k + 1) * envs_per_actor - 1
    (`actors[k]`) and steps them on min(envs_per_actor, max(1, floor(num_cpus_per_actor)))
    threads. See the module docstring for restarts after an actor dies. `close()` closes
    the sub-environments and kills the actors; it leaves Ray itself running.

    Args:
      env_fns: one picklable callable per sub-environment returning a `gymnasium.Env`
        (all with equal spaces), or a registered Gymnasium id, made with
        `gymnasium.make` in the actors.
      num_envs: the number of sub-environments; needed for an id, else None or
        len(env_fns).
      address: the Ray cluster to join when Ray is not initialised in this process yet:
        None starts (or joins) a local Ray, "auto" joins the cluster this machine is
        part of, "ray://host:10001" a remote one. If Ray is initialised, it is used as is.
      envs_per_actor: sub-environments per actor; None spreads them over the cluster's
        CPUs (ceil(num_envs / CPUs)).
      num_cpus_per_actor: CPUs Ray reserves for each actor; None for
        min(1, CPUs / actors), so that every actor fits on an idle cluster. Ray starts
        an actor only once that many CPUs are free, so with other actors about (another
        vector env on the same machine, say) pass less, or 0.
      max_restarts: how many times each actor may be replaced after dying.
      autoreset_mode: an `AutoresetMode` (or its value); NEXT_STEP by default.
      copy: return copies of the observation arrays (see `BatchedVectorEnv`).

    Raises:
      ImportError: if Ray is not installed.
      ValueError: for a bad argument, or sub-environments whose spaces differ.
      SubEnvironmentError: if a sub-environment's factory raised.
    """

    def __init__(
        self,
        env_fns: Sequence[Callable[[], gymnasium.Env]] | str,
        num_envs: int | None = None,
        *,
        address: str | None = None,
        envs_per_actor: int | None = None,
        num_cpus_per_actor: float | None = None,
        max_restarts: int = 10,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        copy: bool = True,
    ):
        env_fns = _env_fns_for(env_fns, num_envs)
        if envs_per_actor is not None:
            _check_count("envs_per_actor", envs_per_actor, minimum=1)
        if num_cpus_per_actor is not None and (
            isinstance(num_cpus_per_actor, bool)
            or not isinstance(num_cpus_per_actor, numbers.Real)
            or num_cpus_per_actor < 0
        ):
            raise ValueError(
                f"num_cpus_per_actor: expected a number >= 0 or None, got {num_cpus_per_actor!r}"
            )
        _check_count("max_restarts", max_restarts, minimum=0)
        ray = _import_ray()
        if not ray.is_initialized():
            ray.init(address=address)
        cpus = ray.cluster_resources().get("CPU", 1.0)
        if envs_per_actor is None:
            envs_per_actor = math.ceil(len(env_fns) / max(1, int(cpus)))
        self.envs_per_actor = min(int(envs_per_actor), len(env_fns))
        num_actors = math.ceil(len(env_fns) / self.envs_per_actor)
        if num_cpus_per_actor is None:
            num_cpus_per_actor = min(1.0, cpus / num_actors)
        self.num_cpus_per_actor = float(num_cpus_per_actor)
        self.max_restarts = int(max_restarts)
        self.restarts = [0] * num_actors
        self._ray = ray
        self._env_fns = env_fns
        self._actors: list | None = [None] * num_actors
        self._spec: HostSpec | None = None
        try:
            self._start_actors(range(num_actors))
        except BaseException:
            self._kill_actors()
            raise
        super().__init__(
            self._spec.observation_space,
            self._spec.action_space,
            len(env_fns),
            autoreset_mode=autoreset_mode,
            metadata=self._spec.metadata,
            render_mode=self._spec.render_mode,
            copy=copy,
        )

    @property
    def actors(self) -> tuple:
        """The Ray actor handles, actor k holding the sub-environments of `indices_of(k)`."""
        if self._actors is None:
            raise RuntimeError("this RayVectorEnv is closed")
        return tuple(self._actors)

    def indices_of(self, actor: int) -> range:
        """The indices of the sub-environments that actor number `actor` holds."""
        start = actor * self.envs_per_actor
        return range(start, min(start + self.envs_per_actor, len(self._env_fns)))

    def _start_actors(self, actors: Sequence[int] | range) -> None:
        """Starts (or replaces) the listed actors and builds their sub-environments.

        Raises:
          SubEnvironmentError: for the lowest index whose factory raised.
          ValueError: for spaces that differ from the first sub-environment's.
        """
        options = {"num_cpus": self.num_cpus_per_actor}
        threads = min(self.envs_per_actor, max(1, math.floor(self.num_cpus_per_actor)))
        actor_class = _host_actor_class()
        for k in actors:
            indices = self.indices_of(k)
            self._actors[k] = actor_class.options(**options).remote(
                [self._env_fns[i] for i in indices], threads
            )
        replies = self._ray.get([self._actors[k].build.remote() for k in actors])
        failures = {}
        for k, reply in zip(actors, replies):
            if isinstance(reply, HostSpec):
                self._check_spec(k, reply)
            else:
                start = self.indices_of(k).start
                failures.update({start + i: failure for i, failure in reply.items()})
        _raise_lowest(failures)

    def _check_spec(self, actor: int, spec: HostSpec) -> None:
        if self._spec is None:
            self._spec = spec
            return
        first = self.indices_of(actor).start
        for name in ("observation_space", "action_space"):
            if getattr(spec, name) != getattr(self._spec, name):
                raise ValueError(
                    f"sub-environment {first}: {name.replace('_', ' ')} {getattr(spec, name)} "
                    f"differs from sub-environment 0's {getattr(self._spec, name)}"
                )

    def _map(
        self,
        function: Callable[..., Any],
        arguments: dict[int, tuple],
        store: Callable[[int, Any], None] | None = None,
    ) -> dict[int, Any]:
        if self._actors is None:
            raise RuntimeError("this RayVectorEnv is closed")
        by_actor: dict[int, dict[int, tuple]] = {}
        for i, args in arguments.items():
            k = i // self.envs_per_actor
            by_actor.setdefault(k, {})[i - k * self.envs_per_actor] = args
        replies, dead = self._gather(
            {k: self._call(k, function, local) for k, local in by_actor.items()}, unpack
        )
        for k in dead:
            self._replace(k)
            replies[k] = self._rerun_on_restarted(k, function, by_actor[k])
        results: dict[int, Any] = {}
        failures: dict[int, SubEnvFailure] = {}
        for k, reply in replies.items():
            start = self.indices_of(k).start
            for local, result in reply.items():
                if isinstance(result, SubEnvFailure):
                    failures[start + local] = result
                    continue
                results[start + local] = result
                if store is not None:
                    store(start + local, result)
        _raise_lowest(failures)
        return results

    def _call(self, actor: int, function: Callable[..., Any], local: dict[int, tuple]):
        """Starts `function` on actor number `actor`'s sub-environments; returns the
        reference to its packed reply."""
        return self._actors[actor].map.remote(pack((function, local)))

    def _ray_get(self, reference) -> dict[int, Any]:
        return unpack(self._ray.get(reference))

    def _gather(
        self, pending: dict[int, Any], read: Callable[[Any], Any] = lambda reply: reply
    ) -> tuple[dict[int, Any], list[int]]:
        """Waits for every actor's reply; returns {actor: read(reply)} and the actors that
        died."""
        ray = self._ray
        try:
            return dict(zip(pending, map(read, ray.get(list(pending.values()))))), []
        except ray.exceptions.RayActorError:
            pass
        replies, dead = {}, []
        for k, reference in pending.items():
            try:
                replies[k] = read(ray.get(reference))
            except ray.exceptions.RayActorError:
                dead.append(k)
        return replies, dead

    def _replace(self, actor: int) -> None:
        """Replaces dead actor number `actor` by a new one with new sub-environments.

        Raises:
          RuntimeError: if the actor has died more than `max_restarts` times.
        """
        self.restarts[actor] += 1
        if self.restarts[actor] > self.max_restarts:
            indices = self.indices_of(actor)
            raise RuntimeError(
                f"the Ray actor of sub-environments {indices.start} to {indices.stop - 1} "
                f"died {self.restarts[actor]} times; max_restarts is {self.max_restarts}"
            )
        self._ray.kill(self._actors[actor], no_restart=True)
        self._start_actors([actor])

    def _rerun_on_restarted(
        self, actor: int, function: Callable[..., Any], local: dict[int, tuple]
    ) -> dict[int, Any]:
        """What the new actor's sub-environments report for the call their old one lost."""
        mode = self.autoreset_mode
        start = self.indices_of(actor).start
        if function is step_sub_env:
            # Only NEXT_STEP leaves an ended episode to be reset on the next step.
            due = {i for i, (_, _, episode_over) in local.items() if episode_over}
            to_reset = set(local) if mode is AutoresetMode.SAME_STEP else due
            resets = self._ray_get(
                self._call(actor, reset_sub_env, dict.fromkeys(to_reset, (None, None)))
            )
            last = {i: read_row(self._observations, start + i) for i in local}
            outcomes = {}
            for i in local:
                if i in due:
                    outcomes[i] = _mark_restarted(resets[i])
                elif mode is AutoresetMode.SAME_STEP:
                    outcomes[i] = _restarted_same_step(resets[i], last[i])
                else:
                    outcomes[i] = SubEnvOutcome(last[i], 0.0, False, True, {"restarted": True})
            return outcomes
        reply = self._ray_get(self._call(actor, function, local))
        if function is reset_sub_env:
            return {i: _mark_restarted(outcome) for i, outcome in reply.items()}
        return reply

    def close_extras(self, **kwargs: Any) -> None:
        """Closes the sub-environments and kills the actors (Ray keeps running)."""
        if self._actors is None:
            return
        try:
            self._gather({k: actor.close.remote() for k, actor in enumerate(self._actors)})
        finally:
            self._kill_actors()

    def _kill_actors(self) -> None:
        for actor in self._actors or ():
            if actor is not None:
                self._ray.kill(actor, no_restart=True)
        self._actors = None


def _mark_restarted(outcome: Any) -> Any:
    if isinstance(outcome, SubEnvOutcome):
        return outcome._replace(info={**outcome.info, "restarted": True})
    return outcome


def _restarted_same_step(reset: Any, last_observation: Any) -> Any:
    if isinstance(reset, SubEnvFailure):
        return reset
    return SubEnvOutcome(
        reset.observation,
        0.0,
        False,
        True,
        {**reset.info, "restarted": True},
        last_observation,
        {"restarted": True},
    )


def _raise_lowest(failures: dict[int, SubEnvFailure]) -> None:
    if not failures:
        return
    index = min(failures)
    error = failures[index].error
    if hasattr(error, "add_note"):
        error.add_note(f"raised in a Ray actor:\n{failures[index].remote_traceback}")
    raise SubEnvironmentError(index, error) from error
