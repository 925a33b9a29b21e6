"""Batched environments on MuJoCo Warp: throughput against raw batched stepping, the
framework's time on the caller's thread, device-to-host copies and initial-state producers.

Tasks: manipulation `reach_site_features` and `lift_brick_features` (`--tasks`), 20 physics
steps per control step, zero actions. Throughputs are environment steps (control steps of
one world) per second.

Table 1, for each task and num_envs:
  batch/s: `BatchEnvironment.step`, resets included (worlds reset at the rate the time limit
    `--time-limit` gives them: every 25 control steps by default, 10x the tasks' own 10 s).
  raw/s: the same model on the same device, `mujoco_warp.step` n_sub_steps times per control
    step, nothing else: the ceiling. overhead = raw / batch (goal on a GPU: <= 1.3 at 4096).
  frame ms: the time `step` spends on the caller's thread outside MuJoCo Warp's physics
    calls (`step`, `step1`, `step2`, `forward`, `set_state`, `get_state`, `reset_data`):
    the framework's own cost per control step, resets at the benchmark's rate included;
    steady ms: the same over the steps where no world started an episode; reset ms: what a
    step where every world started one costs beyond that (on Warp's CPU device only).
  d2h/step: calls per step that copy a device array to the host (Warp `.numpy()`/`.list()`,
    torch `.cpu()`/`.item()`/...), counted over the run (on Warp's CPU device they cost no
    copy, but would on CUDA): the refill's read of the episode counters, every 8 steps.
  reused: episodes that started from a reused initial state / episodes started.
Fit, least squares over the sizes: steady ms = fixed + µs per world-step * num_envs, the
  same for a reset of all worlds, and both together at the tasks' natural reset rate (every
  250 control steps; goal: <= 2 ms fixed, <= 0.25 µs per world-step).
Table 2, the framework alone: `step` with MuJoCo Warp's physics calls replaced by no-ops,
  `--framework-steps` steps at the tasks' own 10 s time limit (so every world resets once,
  at its natural rate), for `--framework-envs`; fitted as fixed ms + µs per world-step
  (goal: <= 2 ms fixed, <= 0.25 µs per world-step). The wall-clock difference of table 1
  is the same quantity with the physics running, noisier by the physics' own variation.
Table 3: initial states per second of the producers (the CPU task's initializers), threads
  and processes, 1 and 2 workers.
Baselines (`--baselines`), on this machine's cores: the threaded CPU vector env (one
  sub-environment per core) and the mj_step ceiling (one thread per core, raw
  `mujoco.mj_step` on its own MjData); batch / ceiling is the speed-up over the CPU (goal on a
  GPU: >= 2 at the best num_envs).

Usage: python benchmarks/batch_env.py [--device cpu|cuda:0] [--num-envs 64,256]
  [--steps 50] [--tasks reach_site_features,lift_brick_features] [--namespace numpy|torch]
  [--baselines] [--producer-states 64] [--state-workers 1] [--state-processes]
  [--framework-envs 64,256,1024,4096] [--framework-steps 300]. On Warp's CPU device the
  default num_envs are 64 and 256 (a control step of 256 lift worlds takes about half a
  second there).
"""

import argparse
import functools
import os
import pathlib
import sys
import threading
import time

import mujoco
import numpy as np

_HERE = pathlib.Path(__file__).resolve().parent
_REPOSITORY = _HERE.parent
# This folder holds manipulation.py (a benchmark), which would shadow the package.
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]
os.environ.setdefault("COMPOSER_WARP_KERNEL_CACHE", str(_REPOSITORY / ".cache" / "warp"))

import gymnasium  # noqa: E402
import mujoco_warp as mjw  # noqa: E402
import warp as wp  # noqa: E402

import manipulation  # noqa: E402
from composer import batch as composer_batch  # noqa: E402
from composer.batch import initial_states  # noqa: E402
from manipulation import batch  # noqa: E402
from manipulation.tasks import registry  # noqa: E402

# A manipulation episode: 10 s of 0.04 s control steps.
_NATURAL_EPISODE_STEPS = 250

_PHYSICS_CALLS = (
    "step",
    "step1",
    "step2",
    "forward",
    "kinematics",
    "set_state",
    "get_state",
    "reset_data",
)


class _PhysicsClock:
    """Accumulates the wall time spent inside MuJoCo Warp's physics calls (patched)."""

    def __init__(self):
        self.seconds = 0.0
        self._originals = {name: getattr(mjw, name) for name in _PHYSICS_CALLS}
        for name, original in self._originals.items():
            setattr(mjw, name, self._timed(original))

    def _timed(self, original):
        @functools.wraps(original)
        def timed(*args, **kwargs):
            begin = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                self.seconds += time.perf_counter() - begin

        return timed

    def restore(self) -> None:
        for name, original in self._originals.items():
            setattr(mjw, name, original)


class _HostCopies:
    """Counts calls that copy a device array to the host (patched while counting)."""

    def __init__(self):
        self.count = 0
        self._originals = {(wp.array, "numpy"): wp.array.numpy, (wp.array, "list"): wp.array.list}
        try:
            import torch
        except ImportError:
            torch = None
        if torch is not None:
            for name in ("cpu", "numpy", "item", "tolist", "__bool__"):
                self._originals[(torch.Tensor, name)] = getattr(torch.Tensor, name)
        for (owner, name), original in self._originals.items():
            setattr(owner, name, self._counted(original))

    def _counted(self, original):
        def counted(*args, **kwargs):
            self.count += 1
            return original(*args, **kwargs)

        return counted

    def restore(self) -> None:
        for (owner, name), original in self._originals.items():
            setattr(owner, name, original)


def _batch_row(task: str, num_envs: int, args) -> dict:
    on_cpu = args.device == "cpu"
    env = batch.load(
        task,
        num_envs,
        device=args.device,
        seed=0,
        time_limit=args.time_limit,
        namespace=args.namespace,
        # Results stay on the device on CUDA; on the CPU NumPy's are the device's memory.
        array_type="numpy" if on_cpu else "torch",
        check_action_values=False,
        state_workers=args.state_workers,
        state_processes=args.state_processes,
    )
    env.reset()
    action = env.hand_out(np.zeros((num_envs, *env.action_spec().shape), np.float32))
    physics = env.physics
    # Compiles, captures graphs and warms caches, through one reset of every world.
    n_sub_steps = env.task.task.physics_steps_per_control_step
    limit = int(round(args.time_limit / (n_sub_steps * env.task.task.physics_timestep)))
    for _ in range(limit + 2):
        env.step(action)
    wp.synchronize_device(physics.device)
    clock, copies = _PhysicsClock(), _HostCopies()
    framework = {True: [], False: []}  # by whether some world started an episode
    try:
        begin = time.perf_counter()
        for _ in range(args.steps):
            inside, start = clock.seconds, time.perf_counter()
            time_step = env.step(action)
            spent = time.perf_counter() - start - (clock.seconds - inside)
            # On the CPU the step types are host memory; on CUDA looking would synchronise.
            framework[bool(on_cpu and time_step.first().any())].append(spent)
        wp.synchronize_device(physics.device)
        elapsed = time.perf_counter() - begin
    finally:
        clock.restore(), copies.restore()
    stats = env.initial_state_stats()
    env.close()
    raw = _raw_rate(physics, env.task.task.physics_steps_per_control_step, args.steps)
    steady = 1e3 * float(np.mean(framework[False]))
    resets = framework[True]
    return {
        "batch": args.steps * num_envs / elapsed,
        "raw": raw,
        "framework_ms": 1e3 * (elapsed - clock.seconds) / args.steps,
        "steady_ms": steady,
        # The framework's time of a step where every world started an episode, beyond a
        # step where none did.
        "reset_ms": 1e3 * float(np.mean(resets)) - steady if resets else None,
        "d2h": copies.count / args.steps,
        "reused": stats.reused,
        "started": stats.started,
    }


def _raw_rate(physics, n_sub_steps: int, steps: int) -> float:
    model, data = physics.warp_model, physics.warp_data
    if physics.is_cuda:
        with wp.ScopedDevice(physics.device):
            mjw.step(model, data)
            with wp.ScopedCapture() as capture:
                for _ in range(n_sub_steps):
                    mjw.step(model, data)

        def raw():
            wp.capture_launch(capture.graph)

    else:

        def raw():
            for _ in range(n_sub_steps):
                mjw.step(model, data)

    raw()
    wp.synchronize_device(physics.device)
    begin = time.perf_counter()
    for _ in range(steps):
        raw()
    wp.synchronize_device(physics.device)
    return steps * physics.num_envs / (time.perf_counter() - begin)


def _producer_rate(task: str, workers: int, processes: bool, states: int) -> float:
    factory = functools.partial(registry.build_task, task)
    batch_task = composer_batch.for_task(registry.build_task(task))
    batch_task_type, fields = type(batch_task), batch_task.batched_model_fields
    maker = initial_states.build_maker(factory, batch_task_type, fields)
    producer = initial_states.StateProducer(
        maker,
        workers=workers,
        processes=processes,
        task_factory=factory,
        batch_task_type=batch_task_type,
        model_fields=fields,
    )
    try:

        def jobs(offset):
            return [
                initial_states.Job(world, (0,), np.random.RandomState(offset + world))
                for world in range(states)
            ]

        producer.submit(jobs(0)).result(timeout=600)  # starts the workers, builds their tasks
        begin = time.perf_counter()
        producer.submit(jobs(states)).result(timeout=600)
        return states / (time.perf_counter() - begin)
    finally:
        producer.close()


def threaded_cpu_steps(task: str, seconds: float) -> float:
    """Environment steps/s of `task`'s threaded CPU vector env, one sub-env per core, zero
    actions, over `seconds` (batch_cameras.py reuses it)."""
    cores = os.cpu_count() or 1
    env = gymnasium.make_vec(
        f"composer/{task}-v0", num_envs=cores, vectorization_mode="vector_entry_point"
    )
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape)
    try:
        env.step(action)
        begin, calls = time.perf_counter(), 0
        while time.perf_counter() - begin < seconds:
            env.step(action)
            calls += 1
        return calls * cores / (time.perf_counter() - begin)
    finally:
        env.close()


def _mj_step_ceiling(task: str, seconds: float) -> float:
    cpu_env = manipulation.load(task, seed=0)
    cpu_env.reset()
    model = cpu_env.physics.model.ptr
    n_sub_steps = cpu_env.task.physics_steps_per_control_step
    cores = os.cpu_count() or 1
    counts = [0] * cores
    stop = threading.Event()

    def run(index: int) -> None:
        data = mujoco.MjData(model)
        mujoco.mj_copyData(data, model, cpu_env.physics.data.ptr)
        while not stop.is_set():
            mujoco.mj_step(model, data, n_sub_steps)
            counts[index] += 1

    threads = [threading.Thread(target=run, args=(i,)) for i in range(cores)]
    begin = time.perf_counter()
    for thread in threads:
        thread.start()
    time.sleep(seconds)
    stop.set()
    for thread in threads:
        thread.join()
    return sum(counts) / (time.perf_counter() - begin)


def _fit(sizes, framework_ms) -> tuple[float, float]:
    """(fixed ms, µs per world-step) of framework_ms = fixed + per_world * num_envs."""
    slope, intercept = np.polyfit(np.asarray(sizes, float), np.asarray(framework_ms), 1)
    return intercept, slope * 1e3


def _framework_alone(task: str, num_envs: int, args) -> float:
    """ms per control step of `BatchEnvironment.step` with MuJoCo Warp's physics calls
    replaced by no-ops: the framework's own work on the caller's thread (observations,
    rewards, counters, resets and their copies, refills), at the task's own time limit."""
    env = batch.load(
        task,
        num_envs,
        device=args.device,
        seed=0,
        array_type="numpy" if args.device == "cpu" else "torch",
        namespace=args.namespace,
        check_action_values=False,
        state_workers=args.state_workers,
        state_processes=args.state_processes,
    )
    env.reset()
    action = env.hand_out(np.zeros((num_envs, *env.action_spec().shape), np.float32))
    env.step(action)
    originals = {name: getattr(mjw, name) for name in _PHYSICS_CALLS}
    for name in _PHYSICS_CALLS:
        setattr(mjw, name, lambda *args, **kwargs: None)
    try:
        wp.synchronize_device(env.physics.device)
        begin = time.perf_counter()
        for _ in range(args.framework_steps):
            env.step(action)
        wp.synchronize_device(env.physics.device)
        return 1e3 * (time.perf_counter() - begin) / args.framework_steps
    finally:
        for name, original in originals.items():
            setattr(mjw, name, original)
        env.close()


def _print_fit(task: str, sizes, rows) -> None:
    """The steady framework time and a reset's, each as fixed + per world, and both at the
    tasks' natural reset rate (every world once per `_NATURAL_EPISODE_STEPS` steps)."""
    fixed, per_world = _fit(sizes, [row["steady_ms"] for row in rows])
    line = f"{task:<22} steady: {fixed:.2f} ms fixed + {per_world:.3f} µs/world-step"
    if all(row["reset_ms"] is not None for row in rows):
        reset_fixed, reset_per_world = _fit(sizes, [row["reset_ms"] for row in rows])
        natural_fixed = fixed + reset_fixed / _NATURAL_EPISODE_STEPS
        natural_per_world = per_world + reset_per_world / _NATURAL_EPISODE_STEPS
        line += (
            f"; reset of all: {reset_fixed:.2f} ms + {reset_per_world:.2f} µs/world"
            f"; at the natural rate: {natural_fixed:.2f} ms + {natural_per_world:.3f} "
            "µs/world-step"
        )
    print(line)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", help="Warp device: cpu or cuda:0")
    parser.add_argument("--num-envs", default=None, help="comma-separated numbers of worlds")
    parser.add_argument("--steps", type=int, default=50, help="control steps per measurement")
    parser.add_argument("--tasks", default="reach_site_features,lift_brick_features")
    parser.add_argument("--time-limit", type=float, default=1.0, help="seconds per episode")
    parser.add_argument("--namespace", default=None, help="task code on numpy or torch")
    parser.add_argument("--baselines", action="store_true", help="threaded CPU and mj_step")
    parser.add_argument("--state-workers", type=int, default=1, help="initial-state producers")
    parser.add_argument(
        "--framework-envs", default="64,256,1024,4096", help="num_envs of the framework table"
    )
    parser.add_argument(
        "--framework-steps", type=int, default=300, help="steps per framework measurement"
    )
    parser.add_argument(
        "--state-processes", action="store_true", help="producers in processes, not threads"
    )
    parser.add_argument("--producer-states", type=int, default=64, help="states per timing")
    args = parser.parse_args()
    default_sizes = "64,256" if args.device == "cpu" else "1024,4096,8192"
    sizes = [int(n) for n in (args.num_envs or default_sizes).split(",")]
    tasks = args.tasks.split(",")
    producers = f"{args.state_workers} {'processes' if args.state_processes else 'threads'}"
    print(
        f"producers {producers}, "
        f"device {args.device}, namespace {args.namespace or 'default'}, {args.steps} steps per "
        f"row, time limit {args.time_limit} s, {os.cpu_count()} cores, load average "
        f"{os.getloadavg()[0]:.2f}"
    )
    print(
        f"{'task':<22} {'num_envs':>8} {'batch/s':>9} {'raw/s':>9} {'overhead':>8} "
        f"{'frame ms':>8} {'steady ms':>9} {'reset ms':>8} {'d2h/step':>8} {'reused':>11}"
    )
    for task in tasks:
        rows = [_batch_row(task, num_envs, args) for num_envs in sizes]
        for num_envs, row in zip(sizes, rows):
            reset = "-" if row["reset_ms"] is None else f"{row['reset_ms']:.2f}"
            print(
                f"{task:<22} {num_envs:>8} {row['batch']:>9.0f} {row['raw']:>9.0f} "
                f"{row['raw'] / row['batch']:>8.2f} {row['framework_ms']:>8.2f} "
                f"{row['steady_ms']:>9.2f} {reset:>8} {row['d2h']:>8.3f} "
                f"{row['reused']:>5}/{row['started']:<5}"
            )
        if len(sizes) > 1:
            _print_fit(task, sizes, rows)
    print()
    print(
        f"framework alone (physics calls as no-ops), {args.framework_steps} steps, resets at the "
        f"tasks' 10 s limit ({_NATURAL_EPISODE_STEPS} steps)"
    )
    print(f"{'task':<22} {'num_envs':>8} {'ms/step':>8}")
    framework_sizes = [int(n) for n in args.framework_envs.split(",")]
    for task in tasks:
        times = [_framework_alone(task, n, args) for n in framework_sizes]
        for num_envs, milliseconds in zip(framework_sizes, times):
            print(f"{task:<22} {num_envs:>8} {milliseconds:>8.3f}")
        fixed, per_world = _fit(framework_sizes, times)
        print(f"{task:<22} fit: {fixed:.3f} ms fixed + {per_world:.4f} µs/world-step")
    print()
    print(f"{'task':<22} {'producers':>12} {'workers':>7} {'states/s':>9}")
    for task in tasks:
        for processes in (False, True):
            for workers in (1, 2):
                rate = _producer_rate(task, workers, processes, args.producer_states)
                kind = "processes" if processes else "threads"
                print(f"{task:<22} {kind:>12} {workers:>7} {rate:>9.0f}")
    if args.baselines:
        print()
        for task in tasks:
            threaded = threaded_cpu_steps(task, 3.0)
            ceiling = _mj_step_ceiling(task, 3.0)
            print(f"{task}: threaded CPU vector env ({os.cpu_count()} sub-envs) {threaded:.0f}/s")
            print(f"{task}: mj_step ceiling ({os.cpu_count()} threads, free) {ceiling:.0f}/s")


if __name__ == "__main__":
    main()
