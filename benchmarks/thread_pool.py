"""Hand-offs for a lock-step thread pool, and `mujoco.rollout`, as ratios from one run.

What `composer.gym.thread_pool.PinnedThreadPool` chose its wake-up from. Each way below
steps N `MjData` of manipulation's `lift_brick_features` model by one control step
(`mj_step(model, data, 20)`) per call, on k = min(N, cores) threads, each thread a fixed
share; the table gives its speed / the same `mj_step` calls on one thread (higher is
better), medians of per-trial ratios:

  pool: `PinnedThreadPool.run` (caller steps one share; a start and a done
    `threading.Lock` per worker).
  barrier: the caller and k - 1 threads meet at two `threading.Barrier` waits.
  events: a start and a done `threading.Event` per worker, caller steps one share.
  spin: as "pool", but workers first poll their start lock 1000 times before blocking.
  queues: the previous design: k workers fed through `queue.SimpleQueue`s, the caller
    waiting on one more queue and stepping nothing.
  rollout: `mujoco.rollout.Rollout(nthread=k)` stepping the N datas (its own C++
    threads, no Python between sub-steps; it also copies the initial state in and
    records every sub-step's state out).

Last, the cost of one call with nothing to step (k = cores, N = k), in microseconds:
the hand-off alone (not for rollout, whose hand-off happens in C).

Usage: python benchmarks/thread_pool.py [--steps N] [--repeats K] [--sizes 1,2,4,8]
"""

import argparse
import os
import pathlib
import queue
import statistics
import sys
import threading
import time

# `import manipulation` finds the package rather than benchmarks/manipulation.py.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mujoco import rollout  # noqa: E402

import manipulation  # noqa: E402
from composer.gym.thread_pool import PinnedThreadPool  # noqa: E402

_TASK = "lift_brick_features"
_SPINS = 1000


class _Stepper:
    """Steps `datas[i]` by `sub_steps` (nothing when `sub_steps` is 0)."""

    def __init__(self, model, datas, sub_steps: int, threads: int):
        self.model, self.datas, self.sub_steps, self.k = model, datas, sub_steps, threads
        self.shares = [datas[s::threads] for s in range(threads)]

    def step_share(self, share) -> None:
        if self.sub_steps:
            for data in share:
                mujoco.mj_step(self.model, data, self.sub_steps)

    def _start_threads(self, arguments) -> None:
        """Starts a daemon thread running `self._serve(*args)` for each args of `arguments`."""
        self.threads = [
            threading.Thread(target=self._serve, args=args, daemon=True) for args in arguments
        ]
        for thread in self.threads:
            thread.start()

    def close(self) -> None:
        pass


class _Pool(_Stepper):
    def __init__(self, *args):
        super().__init__(*args)
        self.pool = PinnedThreadPool(len(self.datas), self.k)
        self.indices = range(len(self.datas))
        model, datas, n = self.model, self.datas, self.sub_steps
        self.task = (lambda i: mujoco.mj_step(model, datas[i], n)) if n else (lambda i: None)

    def step(self) -> None:
        self.pool.run(self.task, self.indices)

    def close(self) -> None:
        self.pool.close()


class _Barrier(_Stepper):
    def __init__(self, *args):
        super().__init__(*args)
        self.begin, self.end = threading.Barrier(self.k), threading.Barrier(self.k)
        self.stopping = False
        self._start_threads((share,) for share in self.shares[1:])

    def _serve(self, share) -> None:
        while True:
            self.begin.wait()
            if self.stopping:
                return
            self.step_share(share)
            self.end.wait()

    def step(self) -> None:
        self.begin.wait()
        self.step_share(self.shares[0])
        self.end.wait()

    def close(self) -> None:
        self.stopping = True
        if self.threads:
            self.begin.wait()
        for thread in self.threads:
            thread.join()


class _Events(_Stepper):
    def __init__(self, *args):
        super().__init__(*args)
        self.starts = [threading.Event() for _ in self.shares[1:]]
        self.dones = [threading.Event() for _ in self.shares[1:]]
        self.stopping = False
        self._start_threads(zip(self.shares[1:], self.starts, self.dones))

    def _serve(self, share, start, done) -> None:
        while True:
            start.wait()
            start.clear()
            if self.stopping:
                return
            self.step_share(share)
            done.set()

    def step(self) -> None:
        for start in self.starts:
            start.set()
        self.step_share(self.shares[0])
        for done in self.dones:
            done.wait()
            done.clear()

    def close(self) -> None:
        self.stopping = True
        for start in self.starts:
            start.set()
        for thread in self.threads:
            thread.join()


class _Spin(_Stepper):
    def __init__(self, *args):
        super().__init__(*args)
        self.starts = [threading.Lock() for _ in self.shares[1:]]
        self.dones = [threading.Lock() for _ in self.shares[1:]]
        for lock in self.starts + self.dones:
            lock.acquire()
        self.stopping = False
        self._start_threads(zip(self.shares[1:], self.starts, self.dones))

    def _serve(self, share, start, done) -> None:
        while True:
            for _ in range(_SPINS):
                if start.acquire(blocking=False):
                    break
            else:
                start.acquire()
            if self.stopping:
                return
            self.step_share(share)
            done.release()

    def step(self) -> None:
        for start in self.starts:
            start.release()
        self.step_share(self.shares[0])
        for done in self.dones:
            done.acquire()

    def close(self) -> None:
        self.stopping = True
        for start in self.starts:
            start.release()
        for thread in self.threads:
            thread.join()


class _Queues(_Stepper):
    def __init__(self, *args):
        super().__init__(*args)
        self.inboxes = [queue.SimpleQueue() for _ in self.shares]
        self.finished: queue.SimpleQueue = queue.SimpleQueue()
        self._start_threads(zip(self.shares, self.inboxes))

    def _serve(self, share, inbox) -> None:
        while inbox.get():
            self.step_share(share)
            self.finished.put(None)

    def step(self) -> None:
        for inbox in self.inboxes:
            inbox.put(True)
        for _ in self.inboxes:
            self.finished.get()

    def close(self) -> None:
        for inbox in self.inboxes:
            inbox.put(False)
        for thread in self.threads:
            thread.join()


class _Rollout(_Stepper):
    def __init__(self, *args):
        super().__init__(*args)
        n = len(self.datas)
        # The physics state goes in and out; the controls are held for the control step.
        self.spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        self.state = np.empty((n, mujoco.mj_stateSize(self.model, self.spec)))
        self.control = np.empty((n, max(1, self.sub_steps), self.model.nu))
        steps = max(1, self.sub_steps)
        self.out = np.empty((n, steps, self.state.shape[1]))
        self.sensors = np.empty((n, steps, self.model.nsensordata))
        self.runner = rollout.Rollout(nthread=self.k if self.k > 1 else 0)
        self.models = [self.model] * n
        self.scratch = [mujoco.MjData(self.model) for _ in range(self.k)]

    def step(self) -> None:
        if not self.sub_steps:
            return
        for i, data in enumerate(self.datas):
            mujoco.mj_getState(self.model, data, self.state[i], self.spec)
            self.control[i] = data.ctrl  # each sub-step
        self.runner.rollout(
            self.models,
            self.scratch,
            self.state,
            self.control,
            nstep=self.sub_steps,
            state=self.out,
            sensordata=self.sensors,
            skip_checks=True,
        )
        for i, data in enumerate(self.datas):
            mujoco.mj_setState(self.model, data, self.out[i, -1], self.spec)

    def close(self) -> None:
        self.runner.close()


_WAYS = {
    "pool": _Pool,
    "barrier": _Barrier,
    "events": _Events,
    "spin": _Spin,
    "queues": _Queues,
    "rollout": _Rollout,
}


def _time(stepper: _Stepper, steps: int) -> float:
    start = time.perf_counter()
    for _ in range(steps):
        stepper.step()
    return time.perf_counter() - start


def _one_thread(model, datas, sub_steps: int, steps: int) -> float:
    start = time.perf_counter()
    for _ in range(steps):
        for data in datas:
            mujoco.mj_step(model, data, sub_steps)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200, help="vector steps per trial")
    parser.add_argument("--repeats", type=int, default=5, help="trials per measurement")
    parser.add_argument("--sizes", default="1,2,4,8", help="numbers of MjData")
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    env = manipulation.load(_TASK)
    model = env.physics.model.ptr
    sub_steps = round(env.control_timestep() / env.physics.timestep())
    print(
        f"task {_TASK} ({sub_steps} sub-steps), {cores} cores, 1-minute load average "
        f"{os.getloadavg()[0]:.2f}; {args.repeats} trials of {args.steps} vector steps, "
        "medians\n"
    )
    rows = []
    for size in (int(size) for size in args.sizes.split(",")):
        datas = [mujoco.MjData(model) for _ in range(size)]
        k = min(size, cores)
        steppers = {name: way(model, datas, sub_steps, k) for name, way in _WAYS.items()}
        ratios: dict[str, list[float]] = {name: [] for name in _WAYS}
        for _ in range(args.repeats):
            single = _one_thread(model, datas, sub_steps, args.steps)
            for name, stepper in steppers.items():
                ratios[name].append(single / _time(stepper, args.steps))
        for stepper in steppers.values():
            stepper.close()
        rows.append([f"{size}", f"{k}"] + [f"{statistics.median(ratios[n]):.2f}x" for n in _WAYS])
    print("| N | threads | " + " | ".join(_WAYS) + " |")
    print("|" + "---|" * (len(_WAYS) + 2))
    for row in rows:
        print("| " + " | ".join(row) + " |")

    datas = [mujoco.MjData(model) for _ in range(cores)]
    costs = {}
    for name, way in _WAYS.items():
        if way is _Rollout:
            continue
        stepper = way(model, datas, 0, cores)
        calls = args.steps * 20
        costs[name] = statistics.median(
            _time(stepper, calls) / calls * 1e6 for _ in range(args.repeats)
        )
        stepper.close()
    print(
        f"\nempty call, {cores} threads (us): "
        + ", ".join(f"{name} {cost:.1f}" for name, cost in costs.items())
    )
    print(f"1-minute load average at the end: {os.getloadavg()[0]:.2f}")
    env.close()


if __name__ == "__main__":
    main()
