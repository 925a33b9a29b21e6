"""PinnedThreadPool: fixed shares, the caller's share, errors, dead workers and closing."""

import ctypes
import threading
import time

import pytest

from composer.gym import SubEnvironmentError
from composer.gym.thread_pool import PinnedThreadPool, WorkerDiedError


def _thread_ids(pool, indices):
    return pool.run(lambda i: threading.get_ident(), indices)


def _pool_threads(name):
    return [thread for thread in threading.enumerate() if thread.name.startswith(name + "-")]


def test_slots_are_shared_out_round_robin_and_the_caller_runs_share_zero():
    pool = PinnedThreadPool(7, 3, name="RoundRobin")
    threads = _thread_ids(pool, range(7))
    me = threading.get_ident()
    assert [threads[i] for i in (0, 3, 6)] == [me] * 3
    assert threads[1] == threads[4] != me
    assert threads[2] == threads[5] != me
    assert threads[1] != threads[2]
    assert len(_pool_threads("RoundRobin")) == 2
    pool.close()


def test_a_slot_keeps_its_thread_across_calls_whatever_the_other_slots():
    pool = PinnedThreadPool(5, 2)
    first = _thread_ids(pool, range(5))
    for indices in ([3], [4, 1], [0, 2], range(5)):
        assert _thread_ids(pool, indices) == {i: first[i] for i in indices}
    assert pool.thread_of(3).ident == first[3]
    assert pool.thread_of(0) is threading.current_thread()
    pool.close()


@pytest.mark.parametrize(("size", "num_threads"), [(1, 4), (4, 1)])
def test_one_thread_runs_everything_on_the_caller_without_workers(size, num_threads):
    pool = PinnedThreadPool(size, num_threads, name="Alone")
    assert pool.num_threads == 1
    assert _pool_threads("Alone") == []
    assert set(_thread_ids(pool, range(size)).values()) == {threading.get_ident()}
    pool.close()


def test_default_is_one_thread_per_core_at_most_one_per_slot(monkeypatch):
    monkeypatch.setattr("os.cpu_count", lambda: 3)
    for size, expected in ((8, 3), (2, 2)):
        pool = PinnedThreadPool(size)
        assert pool.num_threads == expected
        pool.close()


def test_each_worker_is_woken_once_per_call_however_many_of_its_slots_run():
    # 10 slots on 3 threads: worker 1 has slots 1, 4, 7; worker 2 has 2, 5, 8; the
    # caller runs 0, 3, 6, 9 itself and wakes nobody for them.
    pool = PinnedThreadPool(10, 3)
    woken = []
    for indices in (range(10), [0, 3, 9], [1, 4, 7], [2, 1], [5]):
        before = pool.hand_offs
        pool.run(lambda i: i, indices)
        woken.append(pool.hand_offs - before)
    assert woken == [2, 0, 1, 2, 1]
    pool.close()


def test_a_call_returns_only_once_every_worker_has_finished_whichever_is_last():
    # Workers finish in a different order on each call, one of them after more than the
    # caller's 0.25 s liveness poll: every task must have returned when `run` does.
    pool = PinnedThreadPool(12, 6)
    for call, last in enumerate((5, 1, 3, 2, 4)):
        finished = [False] * 12

        def task(i, last=last, finished=finished):
            time.sleep(0.3 if i % 6 == last else 0.001 * (i % 6))
            finished[i] = True
            return i

        assert pool.run(task, range(12)) == {i: i for i in range(12)}, call
        assert all(finished), call
    pool.close()


@pytest.mark.parametrize("num_threads", [1, 2])
def test_results_come_back_by_slot_and_only_for_the_slots_asked(num_threads):
    pool = PinnedThreadPool(6, num_threads)
    assert pool.run(lambda i: i * 10, [5, 0, 3]) == {5: 50, 0: 0, 3: 30}
    assert pool.run(lambda i: -i, []) == {}
    pool.close()


@pytest.mark.parametrize("num_threads", [1, 2])
@pytest.mark.parametrize("every_slot", [False, True], ids=["run", "run_all"])
def test_an_exception_names_the_lowest_failing_slot_after_every_slot_ran(num_threads, every_slot):
    pool = PinnedThreadPool(4, num_threads)
    ran = []

    def task(i):
        ran.append(i)
        if i in (3, 1):
            raise ValueError(f"slot {i} is broken")
        return i

    with pytest.raises(SubEnvironmentError, match="sub-environment 1 raised ValueError") as info:
        pool.run_all(task) if every_slot else pool.run(task, range(4))
    assert info.value.index == 1
    assert str(info.value.__cause__) == "slot 1 is broken"
    assert sorted(ran) == [0, 1, 2, 3]
    # The pool goes on, with nothing left over from the failed call: only the slots
    # asked for run, and no result or error is left behind.
    ran.clear()
    assert pool.run(lambda i: ran.append(i) or i, [2, 3]) == {2: 2, 3: 3}
    assert sorted(ran) == [2, 3]
    assert pool.run_all(lambda i: -i) == [0, -1, -2, -3]
    pool.close()


def test_an_exception_in_the_callers_share_names_its_slot():
    pool = PinnedThreadPool(2, 2)
    with pytest.raises(SubEnvironmentError, match="sub-environment 0 raised KeyError"):
        pool.run(lambda i: {}["missing"] if i == 0 else i, range(2))
    pool.close()


def test_a_call_from_another_thread_is_refused_naming_the_owner():
    pool = PinnedThreadPool(2, 2)
    errors = []

    def call():
        try:
            pool.run(lambda i: i, range(2))
        except RuntimeError as error:
            errors.append(str(error))

    other = threading.Thread(target=call, name="Intruder")
    other.start()
    other.join()
    assert len(errors) == 1
    assert "'Intruder'" in errors[0] and "'MainThread'" in errors[0]
    pool.close()


@pytest.mark.parametrize("num_threads", [1, 2])
def test_an_index_outside_the_slots_is_rejected_and_the_pool_goes_on(num_threads):
    pool = PinnedThreadPool(3, num_threads)
    ran = []
    with pytest.raises(IndexError, match=r"expected slots in range\(0, 3\), got 3"):
        pool.run(ran.append, [0, 3])
    assert ran == []  # nothing runs when an index is bad
    assert pool.run(lambda i: i, range(3)) == {0: 0, 1: 1, 2: 2}
    pool.close()


@pytest.mark.filterwarnings("ignore::pytest.PytestUnhandledThreadExceptionWarning")
def test_a_worker_thread_that_dies_fails_its_slots_instead_of_hanging():
    pool = PinnedThreadPool(4, 2, name="Doomed")
    pool.run(lambda i: i, range(4))
    worker = pool.thread_of(1)
    # An exception sent to the idle worker ends it outside any task.
    ctypes.pythonapi.PyThreadState_SetAsyncExc(
        ctypes.c_ulong(worker.ident), ctypes.py_object(SystemExit)
    )
    with pytest.raises(
        SubEnvironmentError, match="sub-environment 1 raised WorkerDiedError"
    ) as info:
        pool.run(lambda i: i, range(4))
    assert isinstance(info.value.__cause__, WorkerDiedError)
    assert not worker.is_alive()
    with pytest.raises(SubEnvironmentError) as info:
        pool.run(lambda i: i, [2, 3])
    assert info.value.index == 3
    assert "'Doomed-1', which runs slots [1, 3], has ended" in str(info.value)
    assert pool.run(lambda i: i, [0, 2]) == {0: 0, 2: 2}
    pool.close()


def test_an_interrupted_call_is_finished_by_the_next_one():
    pool = PinnedThreadPool(2, 2)
    release = threading.Event()

    def task(i):
        if i == 0:
            raise KeyboardInterrupt
        release.wait(timeout=30)
        return "late"

    with pytest.raises(KeyboardInterrupt):
        pool.run(task, range(2))
    release.set()
    assert pool.run(lambda i: i, range(2)) == {0: 0, 1: 1}
    pool.close()


def test_close_joins_the_workers_and_refuses_later_calls():
    pool = PinnedThreadPool(3, 3, name="Closing")
    pool.run(lambda i: i, range(3))
    workers = _pool_threads("Closing")
    assert len(workers) == 2
    pool.close()
    assert pool.closed
    assert not any(thread.is_alive() for thread in workers)
    pool.close()  # twice does nothing
    with pytest.raises(RuntimeError, match="PinnedThreadPool is closed"):
        pool.run(lambda i: i, range(3))


def test_close_gives_up_on_a_stuck_worker_after_its_timeout():
    pool = PinnedThreadPool(2, 2, name="Stuck")
    release = threading.Event()

    def task(i):
        if i == 0:
            raise KeyboardInterrupt
        release.wait(timeout=60)

    with pytest.raises(KeyboardInterrupt):
        pool.run(task, range(2))
    outcome = []

    def close():
        try:
            pool.close(timeout=0.2)
        except RuntimeError as error:
            outcome.append(str(error))

    closer = threading.Thread(target=close)
    closer.start()
    closer.join(timeout=30)
    stuck_alive = closer.is_alive()
    release.set()
    assert not stuck_alive, "close() did not return"
    assert outcome == [
        "PinnedThreadPool.close: workers ['Stuck-1'] did not end within 0.2 s; "
        "they are still running a task"
    ]
    pool.thread_of(1).join(timeout=30)
    assert not pool.thread_of(1).is_alive()


def test_a_pool_nobody_refers_to_stops_its_workers():
    pool = PinnedThreadPool(2, 2, name="Forgotten")
    pool.run(lambda i: i, range(2))
    (worker,) = _pool_threads("Forgotten")
    del pool
    worker.join(timeout=30)
    assert not worker.is_alive()


@pytest.mark.parametrize(
    ("size", "num_threads", "message"),
    [
        (0, 2, "size: expected an integer >= 1, got 0"),
        (2, 0, "num_threads: expected an integer >= 1 or None, got 0"),
        (2, 1.5, "num_threads: expected an integer >= 1 or None, got 1.5"),
    ],
)
def test_bad_sizes_are_rejected_naming_the_argument(size, num_threads, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        PinnedThreadPool(size, num_threads)


@pytest.mark.parametrize(("size", "num_threads"), [(5, 2), (3, 1)])
def test_run_all_returns_every_slots_result_in_order_each_on_its_thread(size, num_threads):
    pool = PinnedThreadPool(size, num_threads)
    threads = _thread_ids(pool, range(size))
    assert pool.run_all(lambda i: (i * 10, threading.get_ident())) == [
        (i * 10, threads[i]) for i in range(size)
    ]
    pool.close()
