"""Where a `ThreadedVectorEnv` step's time goes, and what many cores would give.

Task: `--task` (default manipulation's `reach_site_features`). For each N of `--sizes`,
a `ThreadedVectorEnv` of N sub-environments on k = min(N, cores) threads is stepped
`--steps` times with every sub-environment step timed where it runs; per vector step:

  hand-offs: worker wake-ups per vector step, counted by the pool (`hand_offs`): one
    per worker (k - 1; the caller steps share 0 itself), however many sub-environments
    its shard holds;
  wake-up us: from the caller entering the pool to a worker starting its first
    sub-environment (the hand-off), mean over workers and steps (and the least seen:
    the hand-off without load, which the model uses);
  barrier wait us: from a thread finishing its share to the last one finishing (what
    each thread waits at the end-of-step barrier), mean over threads; and per thread
    (caller first, then workers 1..k-1) in a second table, with the share each steps;
  straggler us: the last share's end less the median share's end;
  waiting us: per sub-environment step, its wall time less its thread's CPU time over
    it (waiting for the GIL, or for a core; for a vision task, also the time a software
    GL driver renders on threads of its own), mean over sub-environment steps;
  resets: sub-environment steps that were autoresets (a new episode started instead of
    a step), per 100 vector steps, and their mean wall time in ms: a thread resetting
    holds its share's end back while the others wait at the barrier;
  renders in flight: for a task whose observations render (a vision task), the
    `mujoco.Renderer.render` calls of a vector step in flight at once, on average (their
    summed time over the time any was in flight): k when every thread renders at once,
    1 when the renders serialise (each thread renders with its own GL context);
  step us: the whole vector step; and the threaded / loop speed-up next to the
    barrier-synchronised raw ceiling (k threads of raw `mj_step` on the N datas, in lock
    step through the same pool; no Python of the environment at all).

Then, from one sub-environment stepped alone: its CPU time, the part that is MuJoCo
(`mj_step*`, `mjr_render` and `mjr_readPixels` calls timed on this thread) and the rest
(Python, the GIL held); the GIL
releases per sub-environment step (calls into `mujoco` and ctypes, each releasing the GIL
and taking it back, counted with `sys.setprofile`); and the threaded env's speed over the
loop's at the largest N, at GIL switch intervals of 5 ms (CPython's default), 0.5 ms and
0.05 ms, and with 2, 4, 8, ... threads up to one per core (fewer threads than cores,
each with a larger shard: fewer threads contending for the GIL); for a task that renders,
also with at most 1, 2, 4, ... renders in flight at once (a semaphore around
`mujoco.Renderer.render`): whether the threads' GL contexts contend for one GPU.

Last, a model of c cores (default 16): a vector step takes
  max(ceil(N / c) * (M + P), N * P) + (min(N, c) - 1) * h
(M: MuJoCo time per sub-env step, P: its Python time, which holds the GIL and so runs
one thread at a time, h: one hand-off), against N * (M + P) for a loop.

Usage: python benchmarks/vector_env_profile.py [--task T] [--sizes 4,16,32] [--steps N]
    [--model-cores 16] [--no-switch-intervals] [--no-thread-counts] [--no-render-caps]
"""

import argparse
import collections
import functools
import math
import os
import pathlib
import statistics
import sys
import threading
import time

# `import manipulation` finds the package rather than benchmarks/manipulation.py.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

import manipulation  # noqa: E402
from composer.gym import GymnasiumEnv, ThreadedVectorEnv  # noqa: E402
from composer.gym.thread_pool import PinnedThreadPool  # noqa: E402


def _make_env(task: str) -> GymnasiumEnv:
    return GymnasiumEnv(manipulation.load(task))


class _RenderSpans:
    """Records (start, end) of every `mujoco.Renderer.render` call while installed."""

    def __init__(self):
        self.spans: list[tuple[float, float]] = []
        self._original = mujoco.Renderer.render

    def __enter__(self) -> "_RenderSpans":
        original, spans = self._original, self.spans

        def timed(renderer, *args, **kwargs):
            start = time.perf_counter()
            try:
                return original(renderer, *args, **kwargs)
            finally:
                spans.append((start, time.perf_counter()))  # list.append is atomic

        mujoco.Renderer.render = timed
        return self

    def __exit__(self, *exc_info) -> None:
        mujoco.Renderer.render = self._original

    def in_flight(self) -> float | None:
        """Summed render time over the time any render was in flight, for the spans
        recorded since the last call (None for none); clears them."""
        spans, self.spans[:] = sorted(self.spans), []
        if not spans:
            return None
        busy, (start, end) = 0.0, spans[0]
        for next_start, next_end in spans[1:]:
            if next_start > end:
                busy += end - start
                start, end = next_start, next_end
            else:
                end = max(end, next_end)
        busy += end - start
        return sum(b - a for a, b in spans) / busy if busy > 0 else 1.0


class _RenderCap:
    """While installed, at most `limit` `mujoco.Renderer.render` calls run at once (a
    semaphore around each): how the threaded vision env fares when its threads' renders
    queue for the GL driver rather than all going at once."""

    def __init__(self, limit: int):
        self._slots = threading.BoundedSemaphore(limit)
        self._original = mujoco.Renderer.render

    def __enter__(self) -> "_RenderCap":
        original, slots = self._original, self._slots

        def capped(renderer, *args, **kwargs):
            with slots:
                return original(renderer, *args, **kwargs)

        mujoco.Renderer.render = capped
        return self

    def __exit__(self, *exc_info) -> None:
        mujoco.Renderer.render = self._original


class _Timings:
    """Start and end (perf_counter) of each sub-environment's part of one vector step,
    timed around the threaded env's own per-sub-environment step (`_step_one`), on the
    thread that runs it."""

    def __init__(self, envs: ThreadedVectorEnv):
        self.starts = np.zeros(envs.num_envs)
        self.ends = np.zeros(envs.num_envs)
        self.waiting: list[float] = []  # wall less CPU time of each sub-environment step
        self.resets: list[float] = []  # wall time of each autoreset
        self._envs = envs
        self._step_one = envs._step_one
        envs._step_one = self.timed_step  # what the env's step hands the pool

    def timed_step(self, index: int) -> tuple:
        resets = self._envs._episode_over[index]
        cpu = time.thread_time()
        self.starts[index] = time.perf_counter()
        fields = self._step_one(index)
        self.ends[index] = end = time.perf_counter()
        self.waiting.append(end - self.starts[index] - (time.thread_time() - cpu))
        if resets:
            self.resets.append(end - self.starts[index])
        return fields


def profile_steps(task: str, num_envs: int, steps: int) -> dict[str, object]:
    """Per-vector-step hand-offs (counted), wake-up, barrier wait (mean, and per thread),
    straggler and step time (us), for `num_envs` sub-environments."""
    envs = ThreadedVectorEnv([functools.partial(_make_env, task)] * num_envs)
    envs.reset(seed=0)
    k = envs.num_threads
    timings = _Timings(envs)
    rng = np.random.default_rng(0)
    shape = envs.single_action_space.shape
    wake, wait, straggle, total = [], [], [], []
    wait_by_thread = np.zeros(k)
    hand_offs = envs._pool.hand_offs
    renders = _RenderSpans()
    in_flight = []
    for _ in range(steps):
        actions = rng.uniform(-1, 1, (num_envs, *shape)).astype(np.float32)
        with renders:
            begin = time.perf_counter()
            envs.step(actions)
            finish = time.perf_counter()
        step_in_flight = renders.in_flight()
        if step_in_flight is not None:
            in_flight.append(step_in_flight)
        share_ends = [timings.ends[s::k].max() for s in range(k)]
        last = max(share_ends)
        wake.extend(timings.starts[s::k].min() - begin for s in range(1, k))
        wait.extend(last - end for end in share_ends)
        wait_by_thread += last - np.array(share_ends)
        straggle.append(last - statistics.median(share_ends))
        total.append(finish - begin)
    hand_offs = (envs._pool.hand_offs - hand_offs) / steps
    envs.close()
    us = 1e6
    return {
        "threads": k,
        "hand_offs": hand_offs,
        "renders_in_flight": statistics.mean(in_flight) if in_flight else None,
        "wait_by_thread": (wait_by_thread / steps * us).tolist(),
        "wake": statistics.mean(wake) * us if wake else 0.0,
        "wake_min": min(wake) * us if wake else 0.0,
        "wait": statistics.mean(wait) * us,
        "straggler": statistics.median(straggle) * us,
        "waiting": statistics.mean(timings.waiting) * us,
        "resets": len(timings.resets) * 100 / steps,
        "reset_ms": statistics.mean(timings.resets) * 1e3 if timings.resets else 0.0,
        "step": statistics.median(total) * us,
    }


def loop_step_us(task: str, steps: int, repeats: int = 3) -> float:
    """us per step of one environment in a loop: the median of `repeats` passes of
    `steps` steps (one pass read 663 and 787 us in two runs on a 2-core machine)."""
    env = _make_env(task)
    env.reset(seed=0)
    # The actions `profile_steps` gives sub-environment 0 of a vector env of one (the same
    # generator, drawn the same way): actions change what a lift step costs.
    rng = np.random.default_rng(0)
    shape = env.action_space.shape
    actions = [rng.uniform(-1, 1, (1, *shape)).astype(np.float32)[0] for _ in range(steps)]
    passes = []
    for _ in range(repeats):
        start = time.perf_counter()
        for action in actions:
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset()
        passes.append(time.perf_counter() - start)
    env.close()
    return statistics.median(passes) / steps * 1e6


def raw_ceiling(task: str, num_envs: int, steps: int) -> float:
    """Raw `mj_step` on `num_envs` datas through the threaded env's pool, in lock step
    / the same calls on one thread."""
    env = manipulation.load(task)
    model = env.physics.model.ptr
    sub_steps = round(env.control_timestep() / env.physics.timestep())
    env.close()
    datas = [mujoco.MjData(model) for _ in range(num_envs)]
    start = time.perf_counter()
    for _ in range(steps):
        for data in datas:
            mujoco.mj_step(model, data, sub_steps)
    single = time.perf_counter() - start
    # The threaded env's pool class, with its share of threads, and nothing else.
    pool = PinnedThreadPool(num_envs)

    def step(i: int) -> None:
        mujoco.mj_step(model, datas[i], sub_steps)

    indices = range(num_envs)
    start = time.perf_counter()
    for _ in range(steps):
        pool.run(step, indices)
    pooled = time.perf_counter() - start
    pool.close()
    return single / pooled


def split_step(task: str, steps: int) -> tuple[float, float, float]:
    """CPU us per sub-environment step: total, MuJoCo's (timed mj_step* calls), and the
    GIL releases per step (calls into mujoco or ctypes)."""
    env = _make_env(task)
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape, env.action_space.dtype)
    mujoco_time = [0.0]
    released = ("mj_step", "mj_step1", "mj_step2", "mjr_render", "mjr_readPixels")
    originals = {name: getattr(mujoco, name) for name in released}

    def timed(function, *args):
        start = time.thread_time()
        function(*args)
        mujoco_time[0] += time.thread_time() - start

    calls = collections.Counter()

    def count(frame, event, arg):
        if event == "c_call":
            module = (
                getattr(arg, "__module__", None) or type(getattr(arg, "__self__", None)).__module__
            )
            calls[str(module).split(".")[0]] += 1

    sys.setprofile(count)
    for _ in range(10):
        env.step(action)
    sys.setprofile(None)
    gil_releases = (calls["mujoco"] + calls["_ctypes"]) / 10
    for name, function in originals.items():
        setattr(mujoco, name, functools.partial(timed, function))
    try:
        start = time.thread_time()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset()
        total = time.thread_time() - start
    finally:
        for name, function in originals.items():
            setattr(mujoco, name, function)
    env.close()
    return total / steps * 1e6, mujoco_time[0] / steps * 1e6, gil_releases


def _threaded_speedup(envs: ThreadedVectorEnv, loop_us: float, steps: int) -> float:
    """Threaded / loop: `envs` (reset) stepped `steps` times against `loop_us` a step."""
    actions = np.zeros((envs.num_envs, *envs.single_action_space.shape), np.float32)
    start = time.perf_counter()
    for _ in range(steps):
        envs.step(actions)
    return loop_us / ((time.perf_counter() - start) / steps / envs.num_envs * 1e6)


def _doublings(first: int, last: int) -> list[int]:
    """first, 2 first, 4 first, ... below `last`, then `last`."""
    out = []
    while first < last:
        out.append(first)
        first *= 2
    return out + [last]


def switch_interval_speedups(
    task: str, num_envs: int, steps: int, loop_us: float
) -> dict[float, float]:
    """Threaded / loop (`loop_us` a step) at several GIL switch intervals (CPython's
    `sys.setswitchinterval`)."""
    default = sys.getswitchinterval()
    out = {}
    envs = ThreadedVectorEnv([functools.partial(_make_env, task)] * num_envs)
    envs.reset(seed=0)
    try:
        for interval in (0.005, 0.0005, 0.00005):
            sys.setswitchinterval(interval)
            out[interval] = _threaded_speedup(envs, loop_us, steps)
    finally:
        sys.setswitchinterval(default)
        envs.close()
    return out


def thread_count_speedups(
    task: str, num_envs: int, steps: int, loop_us: float, cores: int
) -> dict[int, float]:
    """Threaded / loop (`loop_us` a step) with 2, 4, 8, ... threads up to min(N, cores):
    whether fewer threads than cores, each stepping a larger shard, convoy less on the GIL."""
    out = {}
    for count in _doublings(2, min(num_envs, cores)):
        envs = ThreadedVectorEnv([functools.partial(_make_env, task)] * num_envs, count)
        envs.reset(seed=0)
        try:
            out[count] = _threaded_speedup(envs, loop_us, steps)
        finally:
            envs.close()
    return out


def render_cap_speedups(task: str, num_envs: int, steps: int, loop_us: float) -> dict[int, float]:
    """Threaded / loop (`loop_us` a step) with at most 1, 2, 4, ... renders in flight, up
    to one per thread (no cap), for a task whose observations render."""
    envs = ThreadedVectorEnv([functools.partial(_make_env, task)] * num_envs)
    envs.reset(seed=0)
    out = {}
    try:
        for limit in _doublings(1, envs.num_threads):
            with _RenderCap(limit):
                out[limit] = _threaded_speedup(envs, loop_us, steps)
    finally:
        envs.close()
    return out


def modelled_speedup(
    num_envs: int, cores: int, mujoco_us: float, python_us: float, hand_off_us: float
) -> float:
    serial = num_envs * python_us
    parallel = math.ceil(num_envs / cores) * (mujoco_us + python_us)
    step = max(parallel, serial) + (min(num_envs, cores) - 1) * hand_off_us
    return num_envs * (mujoco_us + python_us) / step


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="reach_site_features")
    parser.add_argument("--sizes", default="4,8")
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--model-cores", type=int, default=16)
    parser.add_argument(
        "--no-switch-intervals",
        action="store_true",
        help="leave out the GIL switch interval sweep (which builds the largest N again)",
    )
    parser.add_argument(
        "--no-thread-counts",
        action="store_true",
        help="leave out the sweep over thread counts (which builds the largest N once per count)",
    )
    parser.add_argument(
        "--no-render-caps",
        action="store_true",
        help="leave out the sweep over renders allowed in flight at once (a rendering task)",
    )
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    sizes = [int(size) for size in args.sizes.split(",")]
    print(
        f"task {args.task}, {cores} cores, 1-minute load average {os.getloadavg()[0]:.2f}; "
        f"{args.steps} vector steps"
    )
    loop_us = loop_step_us(args.task, args.steps)
    print(
        "\n| N | threads | hand-offs per step | wake-up us (min) | barrier wait us "
        "| straggler us | waiting us | resets (ms) | renders in flight | vector step us "
        "| threaded/loop | raw lock-step ceiling |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    hand_offs = []
    rows = {}
    for size in sizes:
        row = rows[size] = profile_steps(args.task, size, args.steps)
        ceiling = raw_ceiling(args.task, size, args.steps)
        speedup = size * loop_us / row["step"]
        flight = row["renders_in_flight"]
        if row["threads"] > 1:  # one thread hands nothing off
            hand_offs.append(row["wake_min"])
        print(
            f"| {size} | {row['threads']} | {row['hand_offs']:g} | {row['wake']:.0f} "
            f"({row['wake_min']:.0f}) | {row['wait']:.0f} | {row['straggler']:.0f} | "
            f"{row['waiting']:.0f} | {row['resets']:.1f} ({row['reset_ms']:.1f}) | "
            + ("-" if flight is None else f"{flight:.2f} of {row['threads']}")
            + f" | {row['step']:.0f} | {speedup:.2f}x | {ceiling:.2f}x |"
        )
    print(
        "\nbarrier wait per thread, us per vector step (thread: sub-environments it steps; "
        "thread 0 is the caller):"
    )
    widest = max(row["threads"] for row in rows.values())
    print("| N | " + " | ".join(f"thread {s}" for s in range(widest)) + " |")
    print("|---|" + "---|" * widest)
    for size, row in rows.items():
        k = row["threads"]
        cells = [
            f"{len(range(s, size, k))}: {wait:.0f}" for s, wait in enumerate(row["wait_by_thread"])
        ]
        print(f"| {size} | " + " | ".join(cells) + " |")
    total, mujoco_us, releases = split_step(args.task, args.steps)
    python_us = total - mujoco_us
    print(
        f"\nloop: {loop_us:.0f} us per step; CPU per sub-env step {total:.0f} us: MuJoCo "
        f"(steps and renders, GIL released) {mujoco_us:.0f}, Python (GIL held) "
        f"{python_us:.0f} ({python_us / total:.0%}); "
        f"GIL releases (calls into mujoco or ctypes) per sub-env step: {releases:.0f}"
    )
    if not args.no_switch_intervals:
        speedups = switch_interval_speedups(args.task, max(sizes), args.steps, loop_us)
        print(
            f"threaded/loop at N = {max(sizes)} by GIL switch interval: "
            + ", ".join(f"{interval * 1e3:g} ms {s:.2f}x" for interval, s in speedups.items())
        )
    if not args.no_thread_counts and min(max(sizes), cores) > 1:
        speedups = thread_count_speedups(args.task, max(sizes), args.steps, loop_us, cores)
        print(
            f"threaded/loop at N = {max(sizes)} by threads: "
            + ", ".join(f"{count} {s:.2f}x" for count, s in speedups.items())
        )
    renders = any(row["renders_in_flight"] is not None for row in rows.values())
    if renders and not args.no_render_caps:
        speedups = render_cap_speedups(args.task, max(sizes), args.steps, loop_us)
        print(
            f"threaded/loop at N = {max(sizes)} by renders allowed in flight at once: "
            + ", ".join(f"{limit} {s:.2f}x" for limit, s in speedups.items())
        )
    hand_off = min(hand_offs) if hand_offs else 0.0
    c = args.model_cores
    print(
        f"\nmodel of {c} cores (M {mujoco_us:.0f} us, P {python_us:.0f} us, "
        f"hand-off {hand_off:.0f} us, the least wake-up seen):"
    )
    print("| N | modelled threaded/loop | bound by |")
    print("|---|---|---|")
    for size in (1, 4, 8, 16, 32, 64):
        s = modelled_speedup(size, c, mujoco_us, python_us, hand_off)
        serial = size * python_us >= math.ceil(size / c) * (mujoco_us + python_us)
        print(f"| {size} | {s:.2f}x | {'Python (GIL)' if serial else 'cores'} |")
    print(f"\n1-minute load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
