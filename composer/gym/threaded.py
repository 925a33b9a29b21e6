"""`ThreadedVectorEnv`: sub-environments stepped in parallel by a pool of threads.

MuJoCo releases the GIL inside `mj_step` and the renderer, so threads step physics in
parallel; what runs in Python between those calls is serialised. The threads are a
`PinnedThreadPool`: the calling thread steps one share of the sub-environments itself,
and each sub-environment lives on one thread for its whole life (it is built, stepped,
rendered and closed there), which an OpenGL context bound to a thread needs.
"""

from collections.abc import Callable, Sequence
from typing import Any

import gymnasium
from gymnasium.vector import AutoresetMode

from composer.gym.rows import attach_row
from composer.gym.sub_env_vector import SubEnvVectorEnv, advance_sub_env, check_spaces_match
from composer.gym.thread_pool import PinnedThreadPool

__all__ = ["ThreadedVectorEnv"]


class ThreadedVectorEnv(SubEnvVectorEnv):
    """A `gymnasium.vector.VectorEnv` whose sub-environments run on a pool of threads.

    Sub-environment i is built by `env_fns[i]()` and always runs on the same thread:
    the thread that made the vector env for i % num_threads == 0, worker thread
    i % num_threads otherwise (see `PinnedThreadPool`). So the vector env is used from
    the thread that made it; other threads get a RuntimeError. Batching, seeding and
    the autoreset modes are those of `SubEnvVectorEnv`. `close()` closes the
    sub-environments and joins the worker threads (waiting at most 10 s for them).

    Args:
      env_fns: one callable per sub-environment, returning a `gymnasium.Env`; all must
        have equal observation and action spaces.
      num_threads: threads stepping sub-environments, the calling one included (at most
        one per sub-environment); None for one per CPU core.
      autoreset_mode: an `AutoresetMode` (or its value); NEXT_STEP by default.
      copy: return copies of the observation arrays (see `SubEnvVectorEnv`).

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
        self._pool = PinnedThreadPool(len(env_fns), num_threads, name="ThreadedVectorEnv")
        self.num_threads = self._pool.num_threads
        try:
            built = self._pool.run(lambda i: env_fns[i](), range(len(env_fns)))
        except BaseException:
            self._pool.close()
            raise
        self._envs = [built[i] for i in range(len(env_fns))]
        first = self._envs[0]
        try:
            for i, env in enumerate(self._envs):
                check_spaces_match(i, env, first)
        except ValueError:
            self._pool.run(lambda i: self._envs[i].close(), range(len(env_fns)))
            self._pool.close()
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
        self._map(attach_row, {i: (row,) for i, row in enumerate(self._rows)})
        # What a step needs of the autoreset mode, decided once (see `_step_one`).
        self._resets_first = bool(self._autoreset.resets_before_step(True))
        self._resets_at_end = bool(self._autoreset.resets_after_step(True))
        self._step_actions: Sequence[Any] = ()

    @property
    def envs(self) -> tuple[gymnasium.Env, ...]:
        """The sub-environments (use them only between calls on this vector env).

        A `GymnasiumEnv` among them writes its observations into its row of the vector
        env's arrays (see `GymnasiumEnv.write_observations_to`).
        """
        return tuple(self._envs)

    def _map(
        self,
        function: Callable[..., Any],
        arguments: dict[int, tuple],
        store: Callable[[int, Any], None] | None = None,
    ) -> dict[int, Any]:
        envs = self._envs
        if store is None:
            return self._pool.run(lambda i: function(envs[i], *arguments[i]), arguments)

        def run_and_store(i: int) -> Any:
            # Stored on the sub-environment's thread, while others are still stepping.
            result = function(envs[i], *arguments[i])
            store(i, result)
            return result

        return self._pool.run(run_and_store, arguments)

    def _step_rows(self, rows: Sequence[Any]) -> dict[str, Any]:
        """Steps every sub-environment on its thread, each storing its own outcome."""
        self._step_actions = rows
        try:
            results = self._pool.run_all(self._step_one)
        finally:
            self._step_actions = ()
        return self._batched_infos(enumerate(results))

    def _step_one(self, index: int) -> tuple:
        """Steps (or autoresets) sub-environment `index` and stores its outcome, on its
        thread; no arguments are built per step (the pool calls this bound method)."""
        fields = advance_sub_env(
            self._envs[index],
            self._step_actions[index],
            self._episode_over[index] and self._resets_first,
            self._resets_at_end,
        )
        self._store(index, fields)
        return fields

    def close_extras(self, **kwargs: Any) -> None:
        """Closes the sub-environments, then stops and joins the worker threads."""
        if self._pool.closed:
            return
        try:
            super().close_extras(**kwargs)
        finally:
            self._pool.close()
