"""What runs inside one `RayVectorEnv` actor: a few sub-environments on a thread pool.

`SubEnvHost` is plain Python (this module never imports Ray); `RayVectorEnv` turns it
into a Ray actor with `ray.remote`. The host keeps its sub-environments on a
`PinnedThreadPool` (the actor's own thread steps one share), so that one actor call
steps all of them and Ray's per-call cost is paid once per actor, not per
sub-environment. A sub-environment that raises does not stop the others: its error
comes back, in place of its result, as a `SubEnvFailure`, which the caller raises as a
`SubEnvironmentError`.

A call's arguments and results cross the process boundary as one pickled `bytes` each
(`pack`, `unpack`): Ray hands a `bytes` over as it is, where it would serialise each of
the many small observation arrays on its own, which costs more than the pickling.
`step`, the call made on every vector step, pickles no arrays at all (each costs more to
pickle than the plain values of a whole step): its actions arrive as the bytes of one
buffer of the action space's `FlatLayout` (`StepCall`); the sub-environments write their
observations into one buffer of the observation space's (a `GymnasiumEnv` straight into
its row, see `rows.attach_row`), and the reply carries that buffer's bytes and the rest of
each outcome as a plain tuple (`StepReply`).
"""

import pickle
import traceback
from collections.abc import Callable, Collection, Sequence
from typing import Any, NamedTuple

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode

from composer.gym.flat_layout import FlatBatch, FlatLayout
from composer.gym.rows import attach_row
from composer.gym.sub_env_vector import (
    SubEnvironmentError,
    check_spaces_match,
    step_sub_env,
)
from composer.gym.thread_pool import PinnedThreadPool

__all__ = [
    "HostSpec",
    "StepCall",
    "StepReply",
    "SubEnvFailure",
    "SubEnvHost",
    "pack",
    "unpack",
]


def pack(value: Any) -> bytes:
    """`value` pickled; through cloudpickle where pickle cannot (a lambda, say)."""
    try:
        return pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, AttributeError, TypeError):
        from ray import cloudpickle  # only ever called where Ray runs

        return cloudpickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)


def unpack(data: bytes) -> Any:
    """The value that `pack` pickled."""
    return pickle.loads(data)


class SubEnvFailure(NamedTuple):
    """A sub-environment's call raised `error`; `remote_traceback` is where, as text."""

    error: BaseException
    remote_traceback: str


class HostSpec(NamedTuple):
    """What the caller needs from the host's first sub-environment to batch results."""

    observation_space: gymnasium.Space
    action_space: gymnasium.Space
    metadata: dict[str, Any]
    render_mode: str | None


class StepCall(NamedTuple):
    """What `SubEnvHost.step` is called with (packed): the sub-environments to step, in
    order; their actions, the bytes of a (len(indices), row_bytes) buffer of the action
    space's `FlatLayout`; the `AutoresetMode`'s value; whether each one's episode was
    over (see `step_sub_env`)."""

    indices: list[int]
    actions: bytes
    autoreset_mode: str
    episode_over: list[bool]


class StepReply(NamedTuple):
    """What `SubEnvHost.step` returns (packed).

    `observations` is the bytes of the host's (sub-environments, row_bytes) buffer of
    the observation space's `FlatLayout`, each stepped sub-environment's observation in
    its row; `outcomes` maps each stepped one to its `SubEnvOutcome` less the
    observation, as a plain tuple (reward, terminated, truncated, info,
    final_observation, final_info), or to a `SubEnvFailure`.
    """

    observations: bytes
    outcomes: dict[int, tuple | SubEnvFailure]


def _portable(error: BaseException) -> BaseException:
    """`error` if it pickles (to cross the process boundary), else a RuntimeError saying it."""
    try:
        pickle.dumps(error)
    except Exception:
        return RuntimeError(f"{type(error).__name__}: {error}")
    return error


def _failure(error: BaseException) -> SubEnvFailure:
    text = "".join(traceback.format_exception(type(error), error, error.__traceback__))
    return SubEnvFailure(_portable(error), text)


def _guarded(env: gymnasium.Env, function: Callable[..., Any], arguments: tuple) -> Any:
    """`function(env, *arguments)`, or a `SubEnvFailure` if it raised."""
    try:
        return function(env, *arguments)
    except BaseException as error:  # returned to the caller, raised there
        return _failure(error)


class SubEnvHost:
    """Builds `env_fns` on `num_threads` threads and runs functions on the sub-envs.

    Sub-environments are numbered 0..len(env_fns)-1 within the host. Ray runs every
    method of an actor on one thread, the pool's owner.
    """

    def __init__(self, env_fns: Sequence[Callable[[], gymnasium.Env]], num_threads: int):
        self._env_fns = list(env_fns)
        self._num_threads = num_threads
        self._pool: PinnedThreadPool | None = None
        self._envs: list[gymnasium.Env] = []
        self._observations: FlatBatch | None = None  # as `StepReply` says
        self._actions: FlatBatch | None = None  # as `StepCall` says

    def build(self) -> HostSpec | dict[int, SubEnvFailure]:
        """Builds the sub-environments; returns their spaces, or {index: failure} for the
        first factory that raised (other errors, such as spaces that differ, raise)."""
        env_fns = self._env_fns
        self._pool = PinnedThreadPool(len(env_fns), self._num_threads, name="SubEnvHost")
        try:
            built = self._pool.run(lambda i: env_fns[i](), range(len(env_fns)))
        except SubEnvironmentError as error:  # the caller raises it, with the global index
            self.close()
            return {error.index: _failure(error.__cause__)}
        self._envs = [built[i] for i in range(len(env_fns))]
        try:
            for i, env in enumerate(self._envs):
                check_spaces_match(i, env, self._envs[0])
        except ValueError:
            self.close()
            raise
        first = self._envs[0]
        size = len(self._envs)
        self._observations = FlatBatch(FlatLayout(first.observation_space), size)
        self._actions = FlatBatch(FlatLayout(first.action_space), size)
        rows = self._observations.rows
        self._pool.run(lambda i: attach_row(self._envs[i], rows[i]), range(size))
        return HostSpec(
            first.observation_space, first.action_space, dict(first.metadata), first.render_mode
        )

    def map(self, call: bytes) -> bytes:
        """For `call` = pack((function, arguments)), returns pack({i: function(sub_env_i,
        *arguments[i])}), with a `SubEnvFailure` where it raised."""
        function, arguments = unpack(call)
        envs = self._envs
        return pack(self._run(lambda i: _guarded(envs[i], function, arguments[i]), arguments))

    def step(self, call: bytes) -> bytes:
        """For `call` = pack(`StepCall`), runs `step_sub_env` on those sub-environments
        and returns pack(`StepReply`)."""
        step_call: StepCall = unpack(call)
        indices, actions = step_call.indices, self._actions
        actions.buffer[indices] = np.frombuffer(step_call.actions, np.uint8).reshape(
            len(indices), actions.buffer.shape[1]
        )
        mode = AutoresetMode(step_call.autoreset_mode)
        over = dict(zip(indices, step_call.episode_over))
        outcomes = self._run(lambda i: self._step_into_row(i, mode, over[i]), indices)
        return pack(StepReply(self._observations.buffer.tobytes(), outcomes))

    def _step_into_row(
        self, index: int, mode: AutoresetMode, episode_over: bool
    ) -> tuple | SubEnvFailure:
        arguments = (self._actions.rows[index], mode, episode_over)
        outcome = _guarded(self._envs[index], step_sub_env, arguments)
        if isinstance(outcome, SubEnvFailure):
            return outcome
        self._observations.write(index, outcome.observation)
        return tuple(outcome)[1:]

    def _run(self, task: Callable[[int], Any], indices: Collection[int]) -> dict[int, Any]:
        """`self._pool.run(task, indices)`, with a dead worker thread's slots failed."""
        try:
            return self._pool.run(task, indices)
        except SubEnvironmentError as error:  # a worker thread died (`WorkerDiedError`)
            return {error.index: _failure(error.__cause__)}

    def close(self) -> None:
        """Closes the sub-environments and stops the threads."""
        if self._pool is None:
            return
        envs, pool = self._envs, self._pool
        self._envs, self._pool = [], None
        try:
            if envs:
                pool.run(lambda i: envs[i].close(), range(len(envs)))
        finally:
            pool.close()
