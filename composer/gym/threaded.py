"""`ThreadedVectorEnv`: sub-environments stepped in parallel by a pool of threads.

MuJoCo releases the GIL inside `mj_step` and the renderer, so threads step physics in
parallel; what runs in Python between those calls is serialised. Each sub-environment
lives on one thread for its whole life (it is built, stepped, rendered and closed
there), which an OpenGL context bound to a thread needs.
"""

import itertools
import numbers
import os
import queue
import threading
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import gymnasium
from gymnasium.vector import AutoresetMode

from composer.gym.batched import BatchedVectorEnv, SubEnvironmentError, check_spaces_match

__all__ = ["ThreadedVectorEnv"]


class _Worker:
    """A thread that runs the jobs put to it, in order, until it gets None."""

    def __init__(self, name: str):
        self._jobs: queue.SimpleQueue = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)
        self.thread.start()

    def submit(self, job: Callable[[], None] | None) -> None:
        self._jobs.put(job)

    def _run(self) -> None:
        while (job := self._jobs.get()) is not None:
            job()


class ThreadedVectorEnv(BatchedVectorEnv):
    """A `gymnasium.vector.VectorEnv` whose sub-environments run on a pool of threads.

    Sub-environment i is built by `env_fns[i]()` and always runs on thread
    `i % num_threads`. Batching, seeding and the autoreset modes are those of
    `BatchedVectorEnv`. `close()` closes the sub-environments and joins the threads.

    Args:
      env_fns: one callable per sub-environment, returning a `gymnasium.Env`; all must
        have equal observation and action spaces.
      num_threads: threads in the pool (at most one per sub-environment); None for one
        per CPU core.
      autoreset_mode: an `AutoresetMode` (or its value); NEXT_STEP by default.
      copy: return copies of the observation arrays (see `BatchedVectorEnv`).

    Raises:
      ValueError: for no `env_fns`, `num_threads` < 1, or sub-environments whose spaces
        differ from the first one's.
      SubEnvironmentError: if an `env_fns[i]()` raised.
    """

    def __init__(
        self,
        env_fns: Sequence[Callable[[], gymnasium.Env]],
        num_threads: int | None = None,
        *,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        copy: bool = True,
    ):
        env_fns = list(env_fns)
        if not env_fns:
            raise ValueError("env_fns: expected at least one environment factory, got none")
        if num_threads is None:
            num_threads = os.cpu_count() or 1
        if (
            isinstance(num_threads, bool)
            or not isinstance(num_threads, numbers.Integral)
            or num_threads < 1
        ):
            raise ValueError(f"num_threads: expected an integer >= 1 or None, got {num_threads!r}")
        self.num_threads = min(int(num_threads), len(env_fns))
        self._workers = [_Worker(f"ThreadedVectorEnv-{k}") for k in range(self.num_threads)]
        try:
            built = self._run_on_threads(lambda i: env_fns[i](), range(len(env_fns)))
        except BaseException:
            self._stop_workers()
            raise
        self._envs = [built[i] for i in range(len(env_fns))]
        first = self._envs[0]
        try:
            for i, env in enumerate(self._envs):
                check_spaces_match(i, env, first)
        except ValueError:
            self._run_on_threads(lambda i: self._envs[i].close(), range(len(env_fns)))
            self._stop_workers()
            raise
        super().__init__(
            first.observation_space,
            first.action_space,
            len(env_fns),
            autoreset_mode=autoreset_mode,
            metadata=dict(first.metadata),
            render_mode=first.render_mode,
            copy=copy,
        )

    @property
    def envs(self) -> tuple[gymnasium.Env, ...]:
        """The sub-environments (use them only between calls on this vector env)."""
        return tuple(self._envs)

    def _map(
        self,
        function: Callable[..., Any],
        arguments: dict[int, tuple],
        store: Callable[[int, Any], None] | None = None,
    ) -> dict[int, Any]:
        envs = self._envs
        if store is None:
            return self._run_on_threads(lambda i: function(envs[i], *arguments[i]), arguments)

        def run_and_store(i: int) -> Any:
            # Stored on the worker, while other workers are still stepping.
            result = function(envs[i], *arguments[i])
            store(i, result)
            return result

        return self._run_on_threads(run_and_store, arguments)

    def _run_on_threads(self, task: Callable[[int], Any], indices: Iterable[int]) -> dict[int, Any]:
        """Runs `task(i)` on sub-environment i's thread for each i; returns {i: result}.

        Raises:
          SubEnvironmentError: for the lowest i whose task raised, after all finished.
        """
        results: dict[int, Any] = {}
        errors: dict[int, BaseException] = {}
        by_worker: dict[int, list[int]] = {}
        for i in indices:
            by_worker.setdefault(i % self.num_threads, []).append(i)
        if not by_worker:
            return results
        # The last worker to finish wakes the caller, once: each wake-up costs a thread
        # switch. `next` on an itertools.count is atomic under the GIL.
        done: queue.SimpleQueue = queue.SimpleQueue()
        finished = itertools.count(1)
        last = len(by_worker)

        def job(assigned: list[int]) -> None:
            try:
                for i in assigned:
                    try:
                        results[i] = task(i)
                    except BaseException as error:  # re-raised in the caller
                        errors[i] = error
            finally:
                if next(finished) == last:
                    done.put(None)

        for worker_index, assigned in by_worker.items():
            self._workers[worker_index].submit(lambda assigned=assigned: job(assigned))
        done.get()
        if errors:
            index = min(errors)
            raise SubEnvironmentError(index, errors[index]) from errors[index]
        return results

    def close_extras(self, **kwargs: Any) -> None:
        """Closes the sub-environments, then stops and joins the threads."""
        if not self._workers:
            return
        try:
            super().close_extras(**kwargs)
        finally:
            self._stop_workers()

    def __del__(self):
        # Without close(), the threads would outlive the vector env; they are not
        # joined here because __del__ may run on one of them.
        for worker in getattr(self, "_workers", ()):
            worker.submit(None)

    def _stop_workers(self) -> None:
        for worker in self._workers:
            worker.submit(None)
        for worker in self._workers:
            worker.thread.join()
        self._workers = []
