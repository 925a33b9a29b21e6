"""`RayVectorEnv`: sub-environments in Ray actors, on one machine or a cluster.

Needs the optional extra `[ray]`; Ray is imported when a `RayVectorEnv` is made, never
when this module is imported. Each actor (a `composer.gym._ray_host.SubEnvHost`) holds
`envs_per_actor` consecutive sub-environments on its own threads, so one actor call per
vector step steps all of them. Batching, seeding and autoreset are `SubEnvVectorEnv`'s,
and the per-sub-environment functions are the same module functions the threaded
vector env runs, so with the same seeds and actions the results are bit-identical. On
each step the actions go to an actor, and its sub-environments' observations come back,
as one buffer of the space's `FlatLayout` each (see `composer.gym._ray_host`): actions
arrive in the action space's dtype (one of another dtype is cast to it), and the
observations are copied here into the batched arrays one leaf at a time.

Fault tolerance. An actor that dies (its process is killed or crashes, or its node is
removed) is replaced by a new one whose sub-environments are built afresh, at most
`max_restarts` times per actor; Ray places it on any node with a free CPU. When that
happens during `step`, the other actors' results of that step are kept, and each of the
dead actor's sub-environments reports its episode truncated, with reward 0 and
`info['restarted']` True:

- NEXT_STEP and DISABLED: the observation is the last one it returned; it is reset on
  the next step (NEXT_STEP) or by the caller (DISABLED), as after any truncation. A
  sub-environment that was due to be reset on this step is reset at once instead.
- SAME_STEP: the observation is the new episode's reset observation, and
  `info['final_obs']` holds the last observation it returned.

A `reset` resets the restarted sub-environments too (those outside its `reset_mask`
without a seed) and marks them with `info['restarted']`; any other call (`call`,
`render`, ...) is run again on the new actor. A sub-environment that raises is not
restarted: the call raises `SubEnvironmentError` with its index, as with the threaded
vector env, and the vector env can go on after a `reset`.

Bounded waits. Starting an actor (Ray placing it on a node, then it building its
sub-environments) may take at most `start_timeout` seconds, and every call at most
`call_timeout`; past either, the vector env kills its actors, closes itself and raises
`TimeoutError` saying what it waited for. That is what happens when a dead actor cannot be
placed again (no node has the CPUs it needs) or when the cluster is gone (its raylet died);
an actor that dies while starting raises `RuntimeError`, the vector env closed likewise.
"""

import functools
import math
import time
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple, NoReturn

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode

from composer.gym._ray_host import (
    HostSpec,
    StepCall,
    StepReply,
    SubEnvFailure,
    SubEnvHost,
    pack,
    unpack,
)
from composer.gym.flat_layout import FlatBatch, FlatLayout, leaves
from composer.gym.rows import read_row
from composer.gym.sub_env_vector import (
    SubEnvironmentError,
    SubEnvOutcome,
    SubEnvVectorEnv,
    check_spaces_match,
    reset_sub_env,
    step_sub_env,
)
from composer.utils import argument_checks

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
        argument_checks.integer(num_envs=num_envs)
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


class _Gathered(NamedTuple):
    """What a call on the actors brought back.

    `results` maps each sub-environment index whose actor replied to its result; `lost`
    lists every sub-environment of the actors that died during the call, which are
    replaced already, with new sub-environments.
    """

    results: dict[int, Any]
    lost: tuple[int, ...]


class _StepBuffers(NamedTuple):
    """What one actor's steps go through: `actions`, a `FlatBatch` of its
    sub-environments' actions (`StepCall.actions`); `observations`, where its
    `StepReply.observations` land, shaped as the actor's (sub-environments, row_bytes);
    `copies`, the (rows of a batched array, leaf of `observations`) pairs that move them
    into the batched observations."""

    actions: FlatBatch
    observations: np.ndarray
    copies: tuple[tuple[np.ndarray, np.ndarray], ...]


class RayVectorEnv(SubEnvVectorEnv):
    """A `gymnasium.vector.VectorEnv` whose sub-environments live in Ray actors.

    Actor k holds sub-environments k * envs_per_actor up to (k + 1) * envs_per_actor - 1
    (`actors[k]`) and steps them on min(envs_per_actor, max(1, floor(num_cpus_per_actor)))
    threads. Actors are spread over the cluster's nodes (Ray's "SPREAD" scheduling). See
    the module docstring for restarts after an actor dies and for the bounded waits.
    `close()` closes the sub-environments and kills the actors; it leaves Ray itself
    running.

    Args:
      env_fns: one picklable callable per sub-environment returning a `gymnasium.Env`
        (all with equal spaces), or a registered Gymnasium id, made with
        `gymnasium.make` in the actors.
      num_envs: the number of sub-environments; needed for an id, else None or
        len(env_fns).
      address: the Ray cluster to join when Ray is not initialised in this process yet:
        None starts a new local Ray (Ray's address "local"), whatever an earlier Ray left
        behind (`RAY_ADDRESS`, a dead cluster's address file); "auto" joins the cluster
        this machine is part of, "host:6379" or "ray://host:10001" a given one. If Ray is
        initialised, it is used as is.
      envs_per_actor: sub-environments per actor; None spreads them over the cluster's
        CPUs (ceil(num_envs / CPUs)).
      num_cpus_per_actor: CPUs Ray reserves for each actor; None for
        min(1, CPUs / actors), so that every actor fits on an idle cluster. Ray starts
        an actor only once that many CPUs are free on one node, so with other actors
        about (another vector env on the same machine, say) pass less, or 0.
      max_restarts: how many times each actor may be replaced after dying.
      start_timeout: the longest wait, in seconds, for actors to start (be placed on a
        node and build their sub-environments), when made and when replaced.
      call_timeout: the longest wait, in seconds, for the actors' replies to one call
        (`reset`, `step`, `call`, `render`, `close`, ...).
      autoreset_mode: an `AutoresetMode` (or its value); NEXT_STEP by default.
      copy: return copies of the observation arrays (see `SubEnvVectorEnv`).

    Raises:
      ImportError: if Ray is not installed.
      ValueError: for a bad argument, or sub-environments whose spaces differ.
      SubEnvironmentError: if a sub-environment's factory raised.
      TimeoutError: if the actors did not start within `start_timeout`.
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
        start_timeout: float = 120.0,
        call_timeout: float = 120.0,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        copy: bool = True,
    ):
        env_fns = _env_fns_for(env_fns, num_envs)
        if envs_per_actor is not None:
            argument_checks.integer(envs_per_actor=envs_per_actor)
        argument_checks.number(at_least=0, or_none=True, num_cpus_per_actor=num_cpus_per_actor)
        argument_checks.integer(0, max_restarts=max_restarts)
        argument_checks.number(above=0, unit="seconds", start_timeout=start_timeout)
        argument_checks.number(above=0, unit="seconds", call_timeout=call_timeout)
        ray = _import_ray()
        if not ray.is_initialized():
            ray.init(address="local" if address is None else address)
        cpus = ray.cluster_resources().get("CPU", 1.0)
        if envs_per_actor is None:
            envs_per_actor = math.ceil(len(env_fns) / max(1, int(cpus)))
        self.envs_per_actor = min(int(envs_per_actor), len(env_fns))
        num_actors = math.ceil(len(env_fns) / self.envs_per_actor)
        if num_cpus_per_actor is None:
            num_cpus_per_actor = min(1.0, cpus / num_actors)
        self.num_cpus_per_actor = float(num_cpus_per_actor)
        self.max_restarts = int(max_restarts)
        self.start_timeout = float(start_timeout)
        self.call_timeout = float(call_timeout)
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
        self._step_buffers = self._make_step_buffers()

    @property
    def actors(self) -> tuple:
        """The Ray actor handles, actor k holding the sub-environments of `indices_of(k)`.

        Raises:
          gymnasium.error.ClosedEnvironmentError: if the vector env is closed.
        """
        self._check_open()
        return tuple(self._actors)

    def indices_of(self, actor: int) -> range:
        """The indices of the sub-environments that actor number `actor` holds."""
        start = actor * self.envs_per_actor
        return range(start, min(start + self.envs_per_actor, len(self._env_fns)))

    def _make_step_buffers(self) -> list[_StepBuffers]:
        """One `_StepBuffers` per actor."""
        observation_layout = FlatLayout(self.single_observation_space)
        action_layout = FlatLayout(self.single_action_space)
        batch_leaves = leaves(self._observations)
        buffers = []
        for k in range(len(self._actors)):
            indices = self.indices_of(k)
            observations = observation_layout.allocate(len(indices))
            rows = [leaf[indices.start : indices.stop] for leaf in batch_leaves]
            copies = tuple(zip(rows, leaves(observation_layout.views(observations))))
            buffers.append(
                _StepBuffers(FlatBatch(action_layout, len(indices)), observations, copies)
            )
        return buffers

    def _start_actors(self, actors: Sequence[int] | range) -> None:
        """Starts (or replaces) the listed actors and builds their sub-environments.

        Raises:
          SubEnvironmentError: for the lowest index whose factory raised.
          ValueError: for spaces that differ from the first sub-environment's.
          TimeoutError: if an actor did not start within `start_timeout`.
          RuntimeError: if an actor died while starting (the vector env is closed).
        """
        options = {"num_cpus": self.num_cpus_per_actor, "scheduling_strategy": "SPREAD"}
        threads = min(self.envs_per_actor, max(1, math.floor(self.num_cpus_per_actor)))
        actor_class = _host_actor_class()
        for k in actors:
            indices = self.indices_of(k)
            self._actors[k] = actor_class.options(**options).remote(
                [self._env_fns[i] for i in indices], threads
            )
        pending = {k: self._actors[k].build.remote() for k in actors}
        replies = self._wait(pending, self.start_timeout, self._start_timeout_message)
        failures = {}
        for k in actors:
            try:
                reply = self._ray.get(replies[k])
            except self._ray.exceptions.RayActorError as error:
                self._give_up(
                    RuntimeError(
                        f"RayVectorEnv: the Ray actor of {self._sub_envs_of([k])} died while "
                        f"starting ({type(error).__name__}): its node may be gone, or the "
                        "cluster (a raylet died). The vector env is closed."
                    )
                )
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
        check_spaces_match(self.indices_of(actor).start, spec, self._spec)

    def _map(
        self,
        function: Callable[..., Any],
        arguments: dict[int, tuple],
        store: Callable[[int, Any], None] | None = None,
    ) -> dict[int, Any]:
        return self._run(function, arguments, store).results

    def _reset_sub_envs(self, arguments: dict[int, tuple]) -> dict[int, SubEnvOutcome]:
        outcomes, restarted = self._run(reset_sub_env, arguments, self._store, every_lost=True)
        for i in restarted:
            outcomes[i] = outcomes[i]._replace(info={**outcomes[i].info, "restarted": True})
        return outcomes

    def _step_sub_envs(self, arguments: dict[int, tuple]) -> dict[int, SubEnvOutcome]:
        outcomes, lost = self._transport(step_sub_env, arguments, self._store)
        if lost:
            outcomes.update(self._restarted_step_outcomes(lost))
        return outcomes

    def _restarted_step_outcomes(self, lost: Sequence[int]) -> dict[int, SubEnvOutcome]:
        """The outcomes of a step whose actors died, for their new sub-environments `lost`
        (see the module docstring), stored in the batched arrays."""
        same_step = self.autoreset_mode is AutoresetMode.SAME_STEP
        # `_episode_over` still holds the lost rows' state from before this step.
        due = {i for i in lost if self._episode_over[i]}
        to_reset = set(lost) if same_step else due
        resets = self._run(reset_sub_env, dict.fromkeys(sorted(to_reset), (None, None))).results
        outcomes = {}
        for i in lost:
            last_observation = read_row(self._observations, i)
            if i in due:
                outcome = resets[i]._replace(info={**resets[i].info, "restarted": True})
            elif same_step:
                outcome = SubEnvOutcome(
                    observation=resets[i].observation,
                    reward=0.0,
                    terminated=False,
                    truncated=True,
                    info={**resets[i].info, "restarted": True},
                    final_observation=last_observation,
                    final_info={"restarted": True},
                )
            else:
                outcome = SubEnvOutcome(
                    observation=last_observation,
                    reward=0.0,
                    terminated=False,
                    truncated=True,
                    info={"restarted": True},
                )
            self._store(i, outcome)
            outcomes[i] = outcome
        return outcomes

    def _run(
        self,
        function: Callable[..., Any],
        arguments: dict[int, tuple],
        store: Callable[[int, Any], None] | None = None,
        *,
        every_lost: bool = False,
    ) -> _Gathered:
        """Runs `function` on the listed sub-environments, again on restarted ones.

        Returns:
          Every result, and in `lost` all the sub-environments restarted meanwhile. With
          `every_lost`, those outside `arguments` (the dead actors' other
          sub-environments) run too, with the arguments (None, None).
        """
        results, lost = self._transport(function, arguments, store)
        restarted: set[int] = set()
        while lost:
            restarted.update(lost)
            again = {
                i: arguments.get(i, (None, None)) for i in lost if every_lost or i in arguments
            }
            more, lost = self._transport(function, again, store)
            results.update(more)
        return _Gathered(results, tuple(sorted(restarted)))

    def _transport(
        self,
        function: Callable[..., Any],
        arguments: dict[int, tuple],
        store: Callable[[int, Any], None] | None = None,
    ) -> _Gathered:
        """Runs `function(sub_env_i, *arguments[i])` on the actors, one call per actor;
        replaces the actors that died meanwhile.

        Raises:
          SubEnvironmentError: for the lowest index whose call raised.
          RuntimeError: if an actor died more than `max_restarts` times.
          TimeoutError: if an actor did not reply within `call_timeout` (or a
            replacement did not start within `start_timeout`).
        """
        by_actor: dict[int, dict[int, tuple]] = {}
        for i, args in arguments.items():
            k = i // self.envs_per_actor
            by_actor.setdefault(k, {})[i - k * self.envs_per_actor] = args
        pending = {k: self._send(k, function, local) for k, local in by_actor.items()}
        replies, dead = self._gather(pending)
        for k in dead:
            self._replace(k)
        results: dict[int, Any] = {}
        failures: dict[int, SubEnvFailure] = {}
        for k, reply in replies.items():
            start = self.indices_of(k).start
            for local, result in self._received(k, function, reply).items():
                if isinstance(result, SubEnvFailure):
                    failures[start + local] = result
                    continue
                results[start + local] = result
                if store is not None:
                    store(start + local, result)
        _raise_lowest(failures)
        return _Gathered(results, tuple(i for k in dead for i in self.indices_of(k)))

    def _send(self, actor: int, function: Callable[..., Any], arguments: dict[int, tuple]):
        """Calls actor number `actor` with {its index i: arguments}: its `step` with a
        `StepCall` for `step_sub_env`, its `map` for any other function; returns the
        reply's reference."""
        if function is not step_sub_env:
            return self._actors[actor].map.remote(pack((function, arguments)))
        actions = self._step_buffers[actor].actions
        episode_over = []
        for position, (action, _, over) in enumerate(arguments.values()):
            actions.write(position, action)
            episode_over.append(over)
        mode = self.autoreset_mode.value
        call = StepCall(
            list(arguments), actions.buffer[: len(arguments)].tobytes(), mode, episode_over
        )
        return self._actors[actor].step.remote(pack(call))

    def _received(self, actor: int, function: Callable[..., Any], reply: bytes) -> dict[int, Any]:
        """The results in actor number `actor`'s `reply`, by its own indices; a step's
        observations are copied into the batched arrays, and its outcomes hold the rows."""
        if function is not step_sub_env:
            return unpack(reply)
        step_reply: StepReply = unpack(reply)
        buffers = self._step_buffers[actor]
        observations = buffers.observations
        observations[...] = np.frombuffer(step_reply.observations, np.uint8).reshape(
            observations.shape
        )
        for rows, received in buffers.copies:
            rows[...] = received
        start, batch_rows = self.indices_of(actor).start, self._rows
        return {
            local: fields
            if isinstance(fields, SubEnvFailure)
            else SubEnvOutcome(batch_rows[start + local], *fields)
            for local, fields in step_reply.outcomes.items()
        }

    def _gather(self, pending: dict[int, Any]) -> tuple[dict[int, Any], list[int]]:
        """Waits for every actor's reply; returns {actor: reply} and the actors that died.

        Raises:
          TimeoutError: if an actor did not reply within `call_timeout`.
        """
        ray = self._ray
        deadline = time.monotonic() + self.call_timeout
        try:
            values = ray.get(list(pending.values()), timeout=self.call_timeout)
            return dict(zip(pending, values)), []
        except (ray.exceptions.RayActorError, ray.exceptions.GetTimeoutError):
            pass
        remaining = max(0.0, deadline - time.monotonic())
        replies, dead = {}, []
        for k, reference in self._wait(pending, remaining, self._call_timeout_message).items():
            try:
                replies[k] = ray.get(reference)
            except ray.exceptions.RayActorError:
                dead.append(k)
        return replies, dead

    def _wait(
        self, pending: dict[int, Any], timeout: float, message: Callable[[list[int]], str]
    ) -> dict[int, Any]:
        """Waits up to `timeout` seconds for every reference in `pending` to be ready.

        Raises:
          TimeoutError: `message(actors not ready)`, after killing the actors and closing
            the vector env.
        """
        references = list(pending.values())
        _, not_ready = self._ray.wait(references, num_returns=len(references), timeout=timeout)
        if not not_ready:
            return pending
        late = [k for k, reference in pending.items() if reference in not_ready]
        self._give_up(TimeoutError(message(late)))

    def _give_up(self, error: Exception) -> NoReturn:
        """Kills the actors, closes the vector env and raises `error`."""
        self._kill_actors()
        self.closed = True
        raise error

    def _start_timeout_message(self, actors: list[int]) -> str:
        ray = self._ray
        free = ray.available_resources().get("CPU", 0.0)
        total = ray.cluster_resources().get("CPU", 0.0)
        nodes = sum(node["Alive"] for node in ray.nodes())
        return (
            f"RayVectorEnv: the Ray actors of {self._sub_envs_of(actors)} did not start "
            f"within start_timeout={self.start_timeout:g} s; each needs "
            f"{self.num_cpus_per_actor:g} CPU on one node, and the cluster reports {free:g} "
            f"of {total:g} CPUs free on {nodes} live node(s). Free CPUs or add a node, or "
            "pass a smaller num_cpus_per_actor; if the cluster is gone (a raylet died), start "
            "a new one; if building the sub-environments is slow, pass a longer "
            "start_timeout. The vector env is closed."
        )

    def _call_timeout_message(self, actors: list[int]) -> str:
        return (
            f"RayVectorEnv: no reply within call_timeout={self.call_timeout:g} s from the Ray "
            f"actors of {self._sub_envs_of(actors)}: the Ray cluster may be gone (its raylet "
            "or head node died), or the call is slower than that (pass a longer "
            "call_timeout). The vector env is closed."
        )

    def _sub_envs_of(self, actors: list[int]) -> str:
        named = []
        for k in actors:
            first, last = self.indices_of(k)[0], self.indices_of(k)[-1]
            named.append(
                f"sub-environment {first}"
                if first == last
                else f"sub-environments {first} to {last}"
            )
        return ", ".join(named)

    def _replace(self, actor: int) -> None:
        """Replaces dead actor number `actor` by a new one with new sub-environments.

        Raises:
          RuntimeError: if the actor has died more than `max_restarts` times.
          TimeoutError: if the new actor did not start within `start_timeout`.
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


def _raise_lowest(failures: dict[int, SubEnvFailure]) -> None:
    if not failures:
        return
    index = min(failures)
    error = failures[index].error
    if hasattr(error, "add_note"):
        error.add_note(f"raised in a Ray actor:\n{failures[index].remote_traceback}")
    raise SubEnvironmentError(index, error) from error
