"""`PinnedThreadPool`: runs one task per slot, each slot always on the same thread.

A pool of `size` slots (one per sub-environment) and k = min(threads, size) threads.
Slot i belongs to share `i % k`; share 0 is run by the thread that made the pool, inside
`run`, and shares 1..k-1 each by a worker thread of their own. So a slot's thread never
changes (what an OpenGL context bound to a thread needs), at k = 1 nothing is handed to
another thread at all, and the calling thread steps a share instead of waiting idle.

A call hands off once per worker, whatever the number of slots in its share: the
worker runs all of its selected slots per wake-up (`hand_offs` counts the wake-ups).
The hand-off is the cheapest of those `benchmarks/thread_pool.py` compares (a
`threading.Barrier`, per-worker `threading.Event`s, spinning before sleeping, the queues
this pool replaced): each worker sleeps on a `threading.Lock` of its own, which the
caller releases to start it. The end of a call is one lock for all workers: each worker
takes a ticket when its share is done and the last one releases it, so the caller,
whatever the number of workers, sleeps and wakes (and takes the interpreter lock back)
at most once per call rather than once per worker. Only workers with a slot in the call
are woken. The state shared with the workers is allocated once; a call makes no queue,
job or closure, only the dict of results it returns and one ticket counter.
"""

import itertools
import math
import os
import threading
import time
from collections.abc import Callable, Collection
from typing import Any

from composer.gym.sub_env_vector import SubEnvironmentError
from composer.utils import argument_checks

__all__ = ["PinnedThreadPool", "WorkerDiedError"]

# How often a caller waiting for a worker checks that the worker's thread is alive.
_LIVENESS_POLL_S = 0.25
# How long `close` waits, by default, for the workers to end.
_CLOSE_TIMEOUT_S = 10.0


class WorkerDiedError(RuntimeError):
    """A worker thread ended without finishing its share; set as a sub-environment's error."""


class _Call:
    """The state the caller shares with the workers, allocated once per pool.

    A worker reads it between acquiring its start lock and taking its ticket; the caller
    writes it only while no worker of the call is running.
    """

    __slots__ = (
        "task",
        "selected",
        "results",
        "errors",
        "failed",
        "stopping",
        "tickets",
        "started",
        "all_done",
    )

    def __init__(self, size: int):
        self.task: Callable[[int], Any] | None = None
        self.selected = [False] * size
        self.results: list[Any] = [None] * size
        self.errors: list[BaseException | None] = [None] * size
        self.failed = False
        self.stopping = False
        # A worker done with its share takes the next ticket (`next` on an
        # `itertools.count` is one step under the interpreter lock: no two workers get
        # the same); the one whose ticket is `started`, the last, releases `all_done`.
        self.tickets = itertools.count(1)
        self.started = 0
        self.all_done = threading.Lock()
        self.all_done.acquire()


class _Worker:
    """A thread that runs the selected slots of `share` each time `start` is released."""

    def __init__(self, name: str, share: range, call: _Call):
        self.share = share
        self.start = threading.Lock()
        self.start.acquire()
        self.running = False  # started and not yet waited for (by the caller only)
        self.finished = False  # took its ticket in the call under way
        self.dead = False
        # The thread holds the worker and the call, never the pool, so that a pool
        # nobody refers to any more is collected and stops its threads.
        self.thread = threading.Thread(target=_serve, args=(self, call), name=name, daemon=True)
        self.thread.start()


def _serve(worker: _Worker, call: _Call) -> None:
    start, share = worker.start, worker.share
    selected, results, errors = call.selected, call.results, call.errors
    while True:
        start.acquire()
        if call.stopping:
            return
        task = call.task
        for i in share:
            if selected[i]:
                try:
                    results[i] = task(i)
                except BaseException as error:  # raised in the caller, with the slot
                    errors[i] = error
                    call.failed = True
        # Marked before the ticket: once the last ticket is taken the caller may start
        # the next call, which clears the mark.
        worker.finished = True
        if next(call.tickets) == call.started:
            call.all_done.release()
        if call.stopping:  # `close` gave up waiting for this call
            return


class PinnedThreadPool:
    """Runs `task(i)` for slots i of `range(size)`, slot i always on the same thread.

    The pool has `num_threads` = min(`num_threads` or the CPU count, `size`) threads:
    the one that made it (the owner), which runs slots 0, k, 2k, ... itself inside
    `run`, and k - 1 workers, worker s running slots s, s + k, s + 2k, ... Calls are made
    from the owner thread only, one at a time.

    Args:
      size: the number of slots.
      num_threads: threads, the owner's included; None for one per CPU core.
      name: the workers' thread names are `f"{name}-{s}"`.

    Raises:
      ValueError: for `size` or `num_threads` not an integer >= 1.
    """

    def __init__(
        self, size: int, num_threads: int | None = None, *, name: str = "PinnedThreadPool"
    ):
        self.size = argument_checks.integer(size=size)
        num_threads = argument_checks.integer(or_none=True, num_threads=num_threads)
        self.num_threads = min(num_threads or os.cpu_count() or 1, self.size)
        self.owner = threading.current_thread()
        self._owner_ident = self.owner.ident
        self._call = _Call(size)
        self._own_share = range(0, size, self.num_threads)
        self._workers = [
            _Worker(f"{name}-{s}", range(s, size, self.num_threads), self._call)
            for s in range(1, self.num_threads)
        ]
        self._wanted = [False] * self.num_threads
        # Slice-assigned to select or clear every slot (or share) at once.
        self._every_slot, self._no_slot = [True] * size, [False] * size
        self._no_result = [None] * size
        self._every_index = range(size)
        self._every_share, self._no_share = [True] * self.num_threads, [False] * self.num_threads
        self._hand_offs = 0
        self._busy = False  # a call is under way, or one was left unfinished
        self._closed = False

    @property
    def closed(self) -> bool:
        """Whether `close` was called."""
        return self._closed

    @property
    def hand_offs(self) -> int:
        """Worker wake-ups since the pool was made: one per worker with a selected slot
        per `run`, however many of its slots it runs (the owner's own share is none)."""
        return self._hand_offs

    def thread_of(self, index: int) -> threading.Thread:
        """The thread that runs slot `index`."""
        share = index % self.num_threads
        return self.owner if share == 0 else self._workers[share - 1].thread

    def run(self, task: Callable[[int], Any], indices: Collection[int]) -> dict[int, Any]:
        """Runs `task(i)` for each i in `indices`, each on slot i's thread; waits for all.

        The owner thread runs its own slots while the workers run theirs. Every listed
        slot runs even when another one raises. `run` returns once every task has
        returned: it bounds no task's time, but notices within 0.25 s a worker thread
        that ended (which only an exception outside any task can make it do, such as
        one sent with `PyThreadState_SetAsyncExc`) and reports that worker's slots as
        failed with a `WorkerDiedError`, in this call and at once in later ones.

        If the owner thread is interrupted (KeyboardInterrupt) while workers are running,
        the next call (or `close`) first waits for them, and drops their results.

        Args:
          task: called with a slot index; it must be safe to call for different slots
            on different threads at once.
          indices: distinct slot indices (iterated more than once).

        Returns:
          {i: task(i)} for each i in `indices`.

        Raises:
          RuntimeError: if the pool is closed, or `run` is called from a thread other
            than the owner.
          IndexError: for an index outside `range(size)`.
          SubEnvironmentError: for the lowest index whose task raised (the error is its
            `__cause__`), once all have finished.
        """
        if self._closed or threading.get_ident() != self._owner_ident:
            self._check_caller()
        if not self._workers:
            return dict(zip(indices, self._run_alone(task, indices)))
        if self._busy:
            self._finish_interrupted()
        call, wanted, k = self._call, self._wanted, self.num_threads
        selected = call.selected
        # Busy until the call is done: an interrupted call is cleaned up by the next one.
        self._busy = True
        for i in indices:
            if not 0 <= i < self.size:
                self._finish_interrupted()
                self._check_index(i)
            selected[i] = True
            wanted[i % k] = True
        self._execute(task)
        results = call.results
        out = {i: results[i] for i in indices}
        self._finish(indices)
        return out

    def run_all(self, task: Callable[[int], Any]) -> list[Any]:
        """`run(task, range(size))`, its results as a list in slot order.

        The way a vector step calls: every slot is selected without a loop over the
        indices, and the results are copied out as one list.

        Raises:
          What `run` raises.
        """
        if self._closed or threading.get_ident() != self._owner_ident:
            self._check_caller()
        if not self._workers:
            return self._run_alone(task, self._every_index)
        if self._busy:
            self._finish_interrupted()
        call = self._call
        self._busy = True
        call.selected[:] = self._every_slot
        self._wanted[:] = self._every_share
        self._execute(task)
        out = call.results.copy()
        self._finish(None)
        return out

    def _execute(self, task: Callable[[int], Any]) -> None:
        """Runs `task` on the selected slots: the workers', then the owner's share, and
        waits for the workers."""
        call = self._call
        call.task = task
        self._start_workers()
        self._run_own_share(task)
        self._wait_for_workers()
        self._busy = False
        call.task = None

    def _finish(self, indices: Collection[int] | None) -> None:
        """Clears the call's slots (`indices`, or None for all) and raises the error of
        the lowest failed one, if any."""
        call = self._call
        if call.failed:
            errors = call.errors
            lowest = min(
                i
                for i in (self._every_index if indices is None else indices)
                if errors[i] is not None
            )
            error = errors[lowest]
            self._clear(indices)
            raise SubEnvironmentError(lowest, error) from error
        self._clear(indices)

    def _run_alone(self, task: Callable[[int], Any], indices: Collection[int]) -> list[Any]:
        """`run` for a pool of one thread: the owner runs every task, nothing is shared.

        Returns:
          The results in the order of `indices`.
        """
        size = self.size
        for i in indices:
            if not 0 <= i < size:
                self._check_index(i)
        results = []
        lowest, lowest_error = size, None
        for i in indices:
            try:
                results.append(task(i))
            except Exception as error:  # KeyboardInterrupt and the like propagate
                results.append(None)
                if i < lowest:
                    lowest, lowest_error = i, error
        if lowest_error is not None:
            raise SubEnvironmentError(lowest, lowest_error) from lowest_error
        return results

    def _check_index(self, index: int) -> None:
        if not 0 <= index < self.size:
            raise IndexError(f"indices: expected slots in range(0, {self.size}), got {index}")

    def _check_caller(self) -> None:
        if self._closed:
            raise RuntimeError(f"this {type(self).__name__} is closed")
        if threading.get_ident() != self._owner_ident:
            raise RuntimeError(
                f"run() called from thread {threading.current_thread().name!r}; the pool "
                f"runs slots on its owner thread {self.owner.name!r} (the one that made "
                "it), so it must be called from there"
            )

    def _start_workers(self) -> None:
        wanted, call = self._wanted, self._call
        starting = []
        for s, worker in enumerate(self._workers, start=1):
            if not wanted[s]:
                continue
            if worker.dead:
                self._fail_share(worker)
                continue
            starting.append(worker)
        call.tickets = itertools.count(1)
        call.started = len(starting)
        self._hand_offs += len(starting)
        for worker in starting:
            worker.running = True
            worker.finished = False
            worker.start.release()

    def _run_own_share(self, task: Callable[[int], Any]) -> None:
        call = self._call
        selected, results, errors = call.selected, call.results, call.errors
        for i in self._own_share:
            if selected[i]:
                try:
                    results[i] = task(i)
                except Exception as error:  # KeyboardInterrupt and the like propagate
                    errors[i] = error
                    call.failed = True

    def _wait_for_workers(self, deadline: float = math.inf) -> None:
        """Waits for the running workers (until `deadline`, a `time.monotonic()`).

        The last worker to finish releases `all_done`. A worker whose thread ended
        before finishing took no ticket, so that release never comes: its share is
        failed, and the wait ends once every other running worker has finished.
        """
        running = [worker for worker in self._workers if worker.running]
        if not running:
            return
        all_done = self._call.all_done
        while not all_done.acquire(
            timeout=min(_LIVENESS_POLL_S, max(0.0, deadline - time.monotonic()))
        ):
            for worker in running:
                if not worker.finished and not worker.dead and not worker.thread.is_alive():
                    worker.dead = True
                    self._fail_share(worker)
            # Only with a worker dead: otherwise the last ticket, and the release, may
            # still be on their way, and must not be left for the next call to find.
            if any(worker.dead for worker in running) and all(
                worker.finished or worker.dead for worker in running
            ):
                break
            if time.monotonic() >= deadline:
                return
        for worker in running:
            worker.running = False

    def _fail_share(self, worker: _Worker) -> None:
        call = self._call
        for i in worker.share:
            if call.selected[i]:
                call.errors[i] = WorkerDiedError(
                    f"thread {worker.thread.name!r}, which runs slots {list(worker.share)}, "
                    "has ended"
                )
                call.failed = True

    def _finish_interrupted(self) -> None:
        """Waits for the workers of a call left unfinished (the owner was interrupted, or
        an index was bad), and drops its results."""
        self._wait_for_workers()
        self._busy = False
        self._call.task = None
        self._clear(None)

    def _clear(self, indices: Collection[int] | None) -> None:
        """Unselects `indices` (None: every slot) and drops their results and errors."""
        call = self._call
        if indices is None:
            call.selected[:] = self._no_slot
            call.results[:] = self._no_result
            call.errors[:] = self._no_result
        else:
            selected, results, errors = call.selected, call.results, call.errors
            for i in indices:
                selected[i] = False
                results[i] = None
                errors[i] = None
        call.failed = False
        self._wanted[:] = self._no_share

    def close(self, *, timeout: float = _CLOSE_TIMEOUT_S) -> None:
        """Stops the workers and joins them, waiting at most `timeout` seconds in all.

        Closing twice does nothing. It may be called from any thread.

        Raises:
          RuntimeError: naming the workers still running after `timeout` (each is
            stuck in a task; they are daemon threads, so they do not keep the process
            alive).
        """
        if self._closed:
            return
        self._closed = True
        deadline = time.monotonic() + timeout
        # Workers still in a call the owner was interrupted in finish it first.
        self._wait_for_workers(deadline)
        self._stop()
        for worker in self._workers:
            worker.thread.join(max(0.0, deadline - time.monotonic()))
        stuck = [worker.thread.name for worker in self._workers if worker.thread.is_alive()]
        if stuck:
            raise RuntimeError(
                f"{type(self).__name__}.close: workers {stuck} did not end within "
                f"{timeout} s; they are still running a task"
            )

    def _stop(self) -> None:
        self._call.stopping = True
        for worker in self._workers:
            if not worker.running and not worker.dead:
                worker.start.release()

    def __del__(self):
        # Not joined: __del__ may run on any thread, a worker's included.
        if not getattr(self, "_closed", True):
            self._closed = True
            self._stop()
