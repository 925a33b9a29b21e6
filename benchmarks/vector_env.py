"""Gymnasium adapter overhead and threaded vector env throughput, as ratios from one run.

Task: manipulation `lift_brick_features` (20 physics steps per control step).

Rows:
  GIL held: CPU time per adapter step that is Python rather than MuJoCo, and the
    speed-up two threads could reach at most with that much serial work (Amdahl).
  adapter: `GymnasiumEnv.step` / `composer.Environment.step`, from the same states with
    the same actions, steps interleaved (median of per-trial ratios; target <= 1.05).
  ceiling: T threads each calling raw `mujoco.mj_step(model, data, 20)` on its own
    `MjData` / one thread doing the same calls (T = 2, cores, and min(N, cores)): what
    threads can give at best on this machine. "Free": each thread runs all its steps;
    "lock step": the threads are handed one control step at a time and waited for, as
    in any vector env. While other processes keep the cores busy, the operating system
    tends to run briefly sleeping threads one after another on the same core, so the
    lock-step ceiling can fall far below the free one.
  threaded N: `ThreadedVectorEnv` of N sub-environments (one thread per core) in
    environment steps per second / one `GymnasiumEnv` stepped in a loop, both with
    autoreset (target >= 1.6 at N = 2 on 2 cores), also as a share of the lock-step
    ceiling for min(N, cores) threads; the same for
    `gymnasium.vector.AsyncVectorEnv` (one process per sub-environment), and
    threaded / async (target > 1 at every N).
  ray N: `RayVectorEnv` of N sub-environments in actors of N / cores sub-environments
    (one actor per core, on a local Ray started by the benchmark), its
    steps/s next to the loop's and the threaded env's from the same trials, ray /
    threaded (target >= 0.7), and Ray's cost per vector step: 1 / (ray vector steps/s)
    - 1 / (threaded vector steps/s), in ms. Skipped when Ray is not installed or with
    --no-ray.

Throughputs are medians over `--repeats` trials of `--steps` vector steps each, taken
in turn so that load from other processes spreads over all rows; ratios are medians of
the ratios within each trial. On a machine shared
with other work the ratios are noisy.

Usage: python benchmarks/vector_env.py [--steps N] [--repeats N] [--sizes 1,2,4,8] [--no-ray]
"""

import argparse
import importlib.util
import math
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

import gymnasium  # noqa: E402
import mujoco  # noqa: E402

import manipulation  # noqa: E402
from composer.gym import GymnasiumEnv, RayVectorEnv, ThreadedVectorEnv  # noqa: E402

_TASK = "lift_brick_features"
_ADAPTER_TARGET = 1.05
_THREADED_TARGET = 1.6
_RAY_TARGET = 0.7


def _make_env() -> GymnasiumEnv:
    return GymnasiumEnv(manipulation.load(_TASK))


def _actions(space: gymnasium.Space, count: int, seed: int) -> list:
    space.seed(seed)
    return [space.sample() for _ in range(count)]


def adapter_ratio(steps: int, repeats: int) -> float:
    """Median over trials of (adapter step time) / (dm_env step time).

    Two environments seeded alike take the same actions, so they pass through the same
    states; their steps alternate, so load from other processes hits both alike.
    """
    gym_env = _make_env()
    dm = manipulation.load(_TASK)
    actions = _actions(gym_env.action_space, steps, seed=0)
    clock = time.perf_counter
    ratios = []
    for trial in range(repeats):
        gym_env.reset(seed=trial)
        dm.random_state.seed(trial)
        dm.reset()
        adapter = direct = 0.0
        for k, action in enumerate(actions):
            # Alternate which goes first, so neither always runs on a warmer cache.
            first, second = (gym_env.step, dm.step) if k % 2 else (dm.step, gym_env.step)
            start = clock()
            first(action)
            middle = clock()
            second(action)
            end = clock()
            if k % 2:
                adapter += middle - start
                direct += end - middle
            else:
                direct += middle - start
                adapter += end - middle
        ratios.append(adapter / direct)
    gym_env.close()
    dm.close()
    return statistics.median(ratios)


def python_share(steps: int, repeats: int) -> tuple[float, float]:
    """CPU microseconds per `GymnasiumEnv.step`, and how many of them are Python.

    The Python part (the GIL is held) is the step's CPU time less that of the same
    `mj_step2`, `mj_step(19)`, `mj_step1` calls from the same states. CPU time of this
    thread is used, so that waiting for a core does not count.
    """
    gym_env = _make_env()
    physics = gym_env.dm_env.physics
    model, data = physics.model.ptr, physics.data.ptr
    twin = mujoco.MjData(model)
    actions = _actions(gym_env.action_space, steps, seed=0)
    clock = time.thread_time
    totals, pythons = [], []
    for trial in range(repeats):
        gym_env.reset(seed=trial)
        mujoco.mj_copyData(twin, model, data)
        start = clock()
        for action in actions:
            gym_env.step(action)
        total = clock() - start
        start = clock()
        for action in actions:
            twin.ctrl[:] = action
            mujoco.mj_step2(model, twin)
            mujoco.mj_step(model, twin, 19)
            mujoco.mj_step1(model, twin)
        raw = clock() - start
        totals.append(total / steps * 1e6)
        pythons.append((total - raw) / steps * 1e6)
    gym_env.close()
    return statistics.median(totals), statistics.median(pythons)


def _raw_steps(model, data, steps: int) -> None:
    for _ in range(steps):
        mujoco.mj_step(model, data, 20)


def _run_free(model, datas, steps: int) -> None:
    workers = [threading.Thread(target=_raw_steps, args=(model, d, steps)) for d in datas]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()


def _run_lock_step(model, datas, steps: int) -> None:
    jobs = [queue.SimpleQueue() for _ in datas]
    done = queue.SimpleQueue()

    def work(data, inbox):
        while inbox.get():
            mujoco.mj_step(model, data, 20)
            done.put(None)

    workers = [threading.Thread(target=work, args=pair) for pair in zip(datas, jobs)]
    for worker in workers:
        worker.start()
    for _ in range(steps):
        for inbox in jobs:
            inbox.put(True)
        for _ in jobs:
            done.get()
    for inbox, worker in zip(jobs, workers):
        inbox.put(False)
        worker.join()


def ceiling_ratios(threads: int, steps: int, repeats: int) -> tuple[float, float]:
    """Steps/s of `threads` threads of raw mj_step / steps/s of one thread, with the
    threads running free and in lock step (handed one control step at a time through
    queues, and waited for, as a vector env does)."""
    env = manipulation.load(_TASK)
    model = env.physics.model.ptr
    datas = [mujoco.MjData(model) for _ in range(threads)]
    free, lock_step = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        _raw_steps(model, datas[0], steps)
        single = time.perf_counter() - start
        for runner, ratios in ((_run_free, free), (_run_lock_step, lock_step)):
            start = time.perf_counter()
            runner(model, datas, steps)
            ratios.append(threads * single / (time.perf_counter() - start))
    env.close()
    return statistics.median(free), statistics.median(lock_step)


def _loop_rate(env: GymnasiumEnv, actions: list) -> float:
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    return len(actions) / (time.perf_counter() - start)


def _vector_rate(envs: gymnasium.vector.VectorEnv, actions: list) -> float:
    start = time.perf_counter()
    for action in actions:
        envs.step(action)
    return envs.num_envs * len(actions) / (time.perf_counter() - start)


class Throughput:
    """Environment steps per second of one loop, a threaded and an async vector env, and
    with `use_ray` a Ray vector env of one actor per core."""

    def __init__(self, num_envs: int, steps: int, use_ray: bool):
        self.num_envs = num_envs
        self.single = _make_env()
        self.single.reset(seed=0)
        self.threaded = ThreadedVectorEnv([_make_env] * num_envs)
        self.threaded.reset(seed=0)
        self.asynchronous = gymnasium.vector.AsyncVectorEnv([_make_env] * num_envs)
        self.asynchronous.reset(seed=0)
        self.single_actions = _actions(self.single.action_space, steps, seed=1)
        self.vector_actions = _actions(self.threaded.action_space, steps, seed=2)
        self.rates = {"loop": [], "threaded": [], "async": []}
        self.ray = None
        if use_ray:
            cores = os.cpu_count() or 1
            # No CPU reservation: the actors of every N live at once, on `cores` cores.
            self.ray = RayVectorEnv(
                [_make_env] * num_envs,
                envs_per_actor=math.ceil(num_envs / cores),
                num_cpus_per_actor=0,
            )
            self.ray.reset(seed=0)
            self.rates["ray"] = []

    def trial(self) -> None:
        self.rates["loop"].append(_loop_rate(self.single, self.single_actions))
        self.rates["threaded"].append(_vector_rate(self.threaded, self.vector_actions))
        self.rates["async"].append(_vector_rate(self.asynchronous, self.vector_actions))
        if self.ray is not None:
            self.rates["ray"].append(_vector_rate(self.ray, self.vector_actions))

    def median(self, name: str) -> float:
        return statistics.median(self.rates[name])

    def ratio(self, numerator: str, denominator: str) -> float:
        """The median over trials of the ratio of two rates measured in the same trial."""
        pairs = zip(self.rates[numerator], self.rates[denominator])
        return statistics.median(a / b for a, b in pairs)

    def close(self) -> None:
        self.single.close()
        self.threaded.close()
        self.asynchronous.close()
        if self.ray is not None:
            self.ray.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100, help="vector steps per trial")
    parser.add_argument("--repeats", type=int, default=5, help="trials per measurement")
    parser.add_argument("--sizes", default="1,2,4,8", help="numbers of sub-environments")
    parser.add_argument("--no-ray", action="store_true", help="leave out the Ray rows")
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    sizes = [int(size) for size in args.sizes.split(",")]
    use_ray = not args.no_ray and importlib.util.find_spec("ray") is not None
    if use_ray:
        import ray

        ray.init(num_cpus=cores, include_dashboard=False, log_to_driver=False)

    print(f"task {_TASK}, {cores} cores, ThreadedVectorEnv with one thread per core")
    adapter = adapter_ratio(args.steps * 2, args.repeats)
    verdict = "ok" if adapter <= _ADAPTER_TARGET else "MISSED"
    print(
        f"adapter: GymnasiumEnv.step / Environment.step = {adapter:.3f} "
        f"(target <= {_ADAPTER_TARGET}: {verdict})"
    )
    total, python = python_share(args.steps * 2, args.repeats)
    print(
        f"GIL held: {python:.1f} of {total:.0f} CPU us per step are Python "
        f"({python / total:.0%}); Amdahl bound for 2 threads "
        f"{1 / (python / total + (1 - python / total) / 2):.2f}x"
    )
    ceilings = {1: 1.0}
    for threads in sorted({2, cores, *(min(size, cores) for size in sizes)} - {1}):
        free, lock_step = ceiling_ratios(threads, args.steps * 2, args.repeats)
        ceilings[threads] = lock_step
        print(
            f"ceiling: {threads} threads of raw mj_step(m, d, 20) / 1 thread = {free:.2f}x "
            f"running free, {lock_step:.2f}x in lock step"
        )

    benches = [Throughput(size, args.steps, use_ray) for size in sizes]
    for _ in range(args.repeats):
        for bench in benches:
            bench.trial()
    print()
    header = (
        "N",
        "loop steps/s",
        "threaded steps/s",
        "async steps/s",
        "threaded/loop",
        "of lock-step ceiling",
        "async/loop",
        "threaded/async",
    )
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for bench in benches:
        loop, threaded, asynchronous = (bench.median(n) for n in ("loop", "threaded", "async"))
        speedup = bench.ratio("threaded", "loop")
        ceiling = ceilings[min(bench.num_envs, cores)]
        print(
            f"| {bench.num_envs} | {loop:.0f} | {threaded:.0f} | {asynchronous:.0f} | "
            f"{speedup:.2f}x | {speedup / ceiling:.0%} | "
            f"{bench.ratio('async', 'loop'):.2f}x | {bench.ratio('threaded', 'async'):.2f}x |"
        )
    print(
        f"\ntargets: threaded/loop >= {_THREADED_TARGET} at N = 2 on 2 cores; "
        "threaded/async > 1 at every N"
    )
    if use_ray:
        _print_ray_table(benches, cores)
    for bench in benches:
        bench.close()


def _print_ray_table(benches: list[Throughput], cores: int) -> None:
    print()
    header = (
        "N",
        "envs per actor",
        "loop steps/s",
        "threaded steps/s",
        "ray steps/s",
        "ray/loop",
        "ray/threaded",
        "ray cost ms per vector step",
    )
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for bench in benches:
        loop, threaded, ray_rate = (bench.median(n) for n in ("loop", "threaded", "ray"))
        cost = (bench.num_envs / ray_rate - bench.num_envs / threaded) * 1e3
        print(
            f"| {bench.num_envs} | {math.ceil(bench.num_envs / cores)} | {loop:.0f} | "
            f"{threaded:.0f} | {ray_rate:.0f} | {bench.ratio('ray', 'loop'):.2f}x | "
            f"{bench.ratio('ray', 'threaded'):.2f}x | {cost:.2f} |"
        )
    print(f"\ntarget: ray/threaded >= {_RAY_TARGET} with one actor per core")


if __name__ == "__main__":
    main()
