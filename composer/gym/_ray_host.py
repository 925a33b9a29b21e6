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
"""

import pickle
import traceback
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import gymnasium

from composer.gym.sub_env_vector import SubEnvironmentError, check_spaces_match
from composer.gym.thread_pool import PinnedThreadPool

__all__ = ["HostSpec", "SubEnvFailure", "SubEnvHost", "pack", "unpack"]


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
        return HostSpec(
            first.observation_space, first.action_space, dict(first.metadata), first.render_mode
        )

    def map(self, call: bytes) -> bytes:
        """For `call` = pack((function, arguments)), returns pack({i: function(sub_env_i,
        *arguments[i])}), with a `SubEnvFailure` where it raised."""
        function, arguments = unpack(call)
        envs = self._envs
        try:
            return pack(
                self._pool.run(lambda i: _guarded(envs[i], function, arguments[i]), arguments)
            )
        except SubEnvironmentError as error:  # a worker thread died (`WorkerDiedError`)
            return pack({error.index: _failure(error.__cause__)})

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
