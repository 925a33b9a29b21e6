"""The CPU batch (`mujoco.batch`) against what a CPU user has otherwise, as ratios from one run.

For each task of `--tasks` (default reach_site_features, lift_brick_features) and each N of
`--sizes` (default 64, 256), in env-steps per second (one world's control step each), each
run over the task's own 10 s episodes with its initial-state producer (every world starts
at least one episode inside the timed window):

  loop: a plain loop of `composer.Environment`s (`manipulation.load`), reset at LAST;
  raw: `mujoco.batch.Batch` of the task's model, N worlds on the same threads, stepped as
    the batch steps (controls written through `bind("ctrl")`, `n_sub_steps` physics steps
    ending at the velocity stage): the physics alone, the batch's ceiling;
  batch: `manipulation.batch.load(task, N, device="cpu")`, and batch / loop, batch / raw;
  threaded: `composer.gym.ThreadedVectorEnv` at its best N of 2, 4, 8, and batch / it;
  async: Gymnasium's `AsyncVectorEnv` (one process per sub-environment) at its best N of
    2 and 4, and batch / it (skipped with --no-async).

Then, from a run of the batch with its `StepClock`: the caller's serial CPU per world-step
(everything outside the physics step, `MujocoBatchPhysics.step`, the producers' waits and
uploads included) as a share of one world's physics step on one thread, and the speed-up
over one core that this serial share leaves possible at 16 and 64 cores (Amdahl:
(s + p) / (s + p / cores)); beside it, the initial-state producers' own CPU per world-step
(`InitialStateStats.producer_cpu_seconds`: work on the producer thread, beside the caller's
and the physics threads'), and the share of both together; the bytes per world (resident
memory of a 4,096-world batch, over 4,096), and a few steps of 4,096 lift worlds.

With `--threads 1,2,4,...`, a scaling table follows (alone with `--scaling-only`): for each
task and N, raw and the batch on each number of C threads over `--scaling-steps` control
steps, batch / raw, and each one's speed-up over its own 1-thread figure, with
`--state-workers` initial-state processes (several fill 4,096 worlds' slots faster)
(benchmarks/cores_check.sh runs it on a many-core host).

Throughputs are medians of `--repeats` trials; in each trial every row is measured in
turn, so that load from other processes spreads over all rows; ratios are of the medians.
The number of cores and the 1-minute load average are printed with the table.

Usage: python benchmarks/cpu_batch.py [--tasks T1,T2] [--sizes 64,256] [--repeats 3]
    [--no-async] [--no-large] [--threads 1,2,4,8,16 [--scaling-steps 10] [--scaling-only]
    [--state-workers 1]]
"""

import argparse
import os
import pathlib
import statistics
import sys
import time

# `import manipulation` finds the package rather than benchmarks/manipulation.py.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

import gymnasium  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402

import manipulation  # noqa: E402
from composer.batch.step_clock import StepClock  # noqa: E402
from composer.gym import GymnasiumEnv, ThreadedVectorEnv  # noqa: E402
from manipulation import batch as manipulation_batch  # noqa: E402

_VEL = int(mujoco.mjtStage.mjSTAGE_VEL)
_LOOP_ENVS = 4


def _cores() -> int:
    return len(os.sched_getaffinity(0))


def _episode_steps(task: str) -> int:
    env = manipulation.load(task)
    return int(round(10.0 / env.control_timestep()))


def _actions(spec, count: int, n: int, seed: int) -> np.ndarray:
    rng = np.random.RandomState(seed)
    return rng.uniform(spec.minimum, spec.maximum, (count, n, *spec.shape))


def _loop_rate(task: str, steps: int) -> float:
    envs = [manipulation.load(task, seed=i) for i in range(_LOOP_ENVS)]
    actions = _actions(envs[0].action_spec(), steps, _LOOP_ENVS, 0)
    for env in envs:
        env.reset()
    start = time.perf_counter()
    for t in range(steps):
        for env, action in zip(envs, actions[t]):
            if env.step(action).last():
                env.reset()
    return steps * _LOOP_ENVS / (time.perf_counter() - start)


def _raw_rate(task: str, n: int, steps: int, threads: int | None = None) -> float:
    from mujoco import batch as mujoco_batch

    env = manipulation.load(task)
    env.reset()
    model, n_sub = env.physics.model.ptr, env.task.physics_steps_per_control_step
    worlds = mujoco_batch.Batch(model, n, nthread=threads or _cores(), persistent=True)
    worlds.reset()
    ctrl = worlds.bind("ctrl")
    actions = _actions(env.action_spec(), steps, n, 1)
    start = time.perf_counter()
    for t in range(steps):
        ctrl[...] = actions[t]
        worlds.step(nstep=n_sub, stage=_VEL)
    return steps * n / (time.perf_counter() - start)


def _batch_env(task: str, n: int, threads: int | None = None, state_workers: int = 1):
    return manipulation_batch.load(
        task,
        n,
        seed=0,
        device="cpu",
        threads=threads,
        state_workers=state_workers,
        state_processes=state_workers > 1,
    )


def _batch_rate(env, steps: int, clock: StepClock | None = None, reset: bool = True) -> float:
    actions = _actions(env.action_spec(), steps, env.num_envs, 2)
    if reset:
        env.reset()
    env.step_clock = clock
    start = time.perf_counter()
    for t in range(steps):
        env.step(actions[t])
    rate = steps * env.num_envs / (time.perf_counter() - start)
    env.step_clock = None
    return rate


def _vector_rate(envs, steps: int) -> float:
    envs.reset(seed=0)
    actions = [envs.action_space.sample() for _ in range(8)]
    start = time.perf_counter()
    for t in range(steps):
        envs.step(actions[t % 8])
    return steps * envs.num_envs / (time.perf_counter() - start)


def _make(task: str):
    return GymnasiumEnv(manipulation.load(task))


def _best_vector_rate(task: str, kind: str, sizes, steps: int, repeats: int) -> tuple[int, float]:
    import functools

    best = (0, 0.0)
    make = functools.partial(_make, task)
    for n in sizes:
        if kind == "threaded":
            envs = ThreadedVectorEnv([make] * n)
        else:
            envs = gymnasium.vector.AsyncVectorEnv([make] * n, context="forkserver")
        rate = statistics.median(_vector_rate(envs, steps) for _ in range(repeats))
        envs.close()
        best = max(best, (n, rate), key=lambda pair: pair[1])
    return best


def _single_thread_physics_us(task: str, steps: int = 200) -> float:
    """One world's physics per control step on one thread, in microseconds."""
    from mujoco import batch as mujoco_batch

    env = manipulation.load(task)
    model, n_sub = env.physics.model.ptr, env.task.physics_steps_per_control_step
    worlds = mujoco_batch.Batch(model, 16, nthread=1, persistent=True)
    worlds.reset()
    start = time.perf_counter()
    for _ in range(steps):
        worlds.step(nstep=n_sub, stage=_VEL)
    return (time.perf_counter() - start) / (steps * 16) * 1e6


def _scaling(tasks, sizes, threads, steps: int, repeats: int, state_workers: int) -> None:
    """Prints raw and the batch on each thread count of `threads` (see the docstring), a
    row as soon as it is measured."""
    print(f"\nC threads: env-steps/s over {steps} control steps, medians of {repeats}")
    row = "{:>20} {:>5} {:>7} {:>10} {:>10} {:>6} {:>14} {:>16}"
    print(
        row.format(
            "task", "N", "threads", "raw", "batch", "/raw", "raw / 1 thread", "batch / 1 thread"
        )
    )
    for task in tasks:
        for n in sizes:
            first = None
            for count in threads:
                raw = statistics.median(_raw_rate(task, n, steps, count) for _ in range(repeats))
                env = _batch_env(task, n, count, state_workers)
                rate = statistics.median(_batch_rate(env, steps) for _ in range(repeats))
                env.close()
                first = first or (raw, rate)
                ratios = (rate / raw, raw / first[0], rate / first[1])
                print(
                    row.format(
                        task,
                        n,
                        count,
                        f"{raw:,.0f}",
                        f"{rate:,.0f}",
                        *(f"{r:.2f}x" for r in ratios),
                    ),
                    flush=True,
                )


def _resident_bytes() -> int:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _table(header, rows) -> None:
    widths = [max(len(str(c)) for c in column) for column in zip(header, *rows)]
    for row in (header, *rows):
        print("  ".join(str(c).rjust(w) for c, w in zip(row, widths)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tasks", default="reach_site_features,lift_brick_features")
    parser.add_argument("--sizes", default="64,256")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-async", action="store_true")
    parser.add_argument("--no-large", action="store_true")
    parser.add_argument("--threads", default="", help="thread counts for the scaling table")
    parser.add_argument("--scaling-steps", type=int, default=10)
    parser.add_argument("--scaling-only", action="store_true")
    parser.add_argument(
        "--state-workers", type=int, default=1, help="initial-state processes (scaling table)"
    )
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    threads = [int(t) for t in args.threads.split(",") if t]
    if args.scaling_only and not threads:
        parser.error("--scaling-only: give the thread counts with --threads")
    cores = _cores()
    print(
        f"cores: {cores}, load average (1 min): {os.getloadavg()[0]:.2f}, "
        f"mujoco {mujoco.__version__}"
    )
    if not args.scaling_only:
        _main_tables(args, sizes)
    if threads:
        tasks = args.tasks.split(",")
        _scaling(tasks, sizes, threads, args.scaling_steps, args.repeats, args.state_workers)


def _main_tables(args, sizes) -> None:
    """The env-steps/s table, the serial share and, unless --no-large, 4,096 lift worlds."""
    rows, serial_rows = [], []
    for task in args.tasks.split(","):
        steps = _episode_steps(task) + 10
        envs = {n: _batch_env(task, n) for n in sizes}
        loop, raw, batched = [], {n: [] for n in sizes}, {n: [] for n in sizes}
        for _ in range(args.repeats):
            loop.append(_loop_rate(task, steps))
            for n in sizes:
                raw[n].append(_raw_rate(task, n, steps))
                batched[n].append(_batch_rate(envs[n], steps))
        vector_steps = max(40, steps // 4)
        threaded = _best_vector_rate(task, "threaded", (2, 4, 8), vector_steps, args.repeats)
        asynchronous = (
            (0, float("nan"))
            if args.no_async
            else _best_vector_rate(task, "async", (2, 4), vector_steps, args.repeats)
        )
        loop_rate = statistics.median(loop)
        physics_us = _single_thread_physics_us(task)
        for n in sizes:
            raw_rate, batch_rate = statistics.median(raw[n]), statistics.median(batched[n])
            rows.append(
                (
                    task,
                    n,
                    f"{loop_rate:,.0f}",
                    f"{raw_rate:,.0f}",
                    f"{batch_rate:,.0f}",
                    f"{batch_rate / loop_rate:.2f}x",
                    f"{batch_rate / raw_rate:.2f}x",
                    f"{threaded[1]:,.0f} (N={threaded[0]})",
                    f"{batch_rate / threaded[1]:.2f}x",
                    f"{asynchronous[1]:,.0f} (N={asynchronous[0]})",
                    f"{batch_rate / asynchronous[1]:.2f}x",
                )
            )
            clock = StepClock(envs[n].synchronize)
            envs[n].reset()  # its states (every slot of every world) are not counted
            before = envs[n].initial_state_stats().producer_cpu_seconds
            _batch_rate(envs[n], steps, clock, reset=False)
            produced = envs[n].initial_state_stats().producer_cpu_seconds - before
            total = sum(clock.seconds.values())
            serial_us = (total - clock.seconds["physics"]) / (clock.steps * n) * 1e6
            producers_us = produced / (clock.steps * n) * 1e6
            share = serial_us / physics_us
            bound = [(1 + share) / (share + 1 / c) for c in (16, 64)]
            serial_rows.append(
                (
                    task,
                    n,
                    f"{serial_us:.2f}",
                    f"{producers_us:.2f}",
                    f"{physics_us:.1f}",
                    f"{100 * share:.2f}%",
                    f"{100 * (serial_us + producers_us) / physics_us:.2f}%",
                    f"{bound[0]:.1f}x",
                    f"{bound[1]:.1f}x",
                )
            )
        for env in envs.values():
            env.close()
    print("\nenv-steps/s, medians of", args.repeats, "trials")
    _table(
        (
            "task",
            "N",
            "loop",
            "raw",
            "batch",
            "/loop",
            "/raw",
            "threaded",
            "/threaded",
            "async",
            "/async",
        ),
        rows,
    )
    print(
        "\nthe caller's serial CPU per world-step (outside the physics step), the producers' "
        "CPU per world-step (beside it), us"
    )
    _table(
        (
            "task",
            "N",
            "serial",
            "producers",
            "1-thread physics",
            "share",
            "with producers",
            "bound 16",
            "bound 64",
        ),
        serial_rows,
    )
    if not args.no_large:
        before = _resident_bytes()
        env = _batch_env("lift_brick_features", 4096)
        env.reset()
        per_world = (_resident_bytes() - before) / 4096
        rate = _batch_rate(env, 5)
        env.close()
        print(
            f"\n4,096 lift_brick_features worlds: {per_world / 1024:.1f} KiB per world "
            f"(resident), {rate:,.0f} env-steps/s over 5 steps"
        )


if __name__ == "__main__":
    main()
