"""Batched environments on MuJoCo Warp: throughput against raw batched stepping, where each
control step's time goes, device-to-host copies, and the initial-state producers.

Tasks: manipulation `reach_site_features` and `lift_brick_features` (`--tasks`), 20 physics
steps per control step, zero actions. Throughputs are environment steps (control steps of
one world) per second. Episodes (`--episodes`): at the tasks' own length ("own", 10 s, 250
control steps) and/or at 1 s ("1"); `--stagger` spreads the episodes' starts (each world's
step count drawn in [0, limit) after the first reset, as a training run has them after its
first episodes); without it every world starts at once and the time limit ends them together.

Table 1, throughput, for each task, episode length and num_envs (a run without timers):
  batch/s: `BatchEnvironment.step`, resets included. raw/s: the same model on the same
  device, `mujoco_warp.step` n_sub_steps times per control step, nothing else: the ceiling.
  overhead = raw / batch (goal on a GPU: <= 1.3 at 4096).
Table 2, the split: the same steps again with a `composer.batch.step_clock.StepClock`, which
  synchronises the device after each part of `step` and reads the wall clock (no function is
  patched; on CUDA the parts are the graphs and launches the step makes): ms per step of
  each part (physics, start_episodes, task hooks, counters, observations, refill, action,
  hand_out), `sum` of the parts and `wall` (the steps timed from outside; the parts cover
  the step, so they add up to it), `wait` (the producer wait, from `initial_state_stats()`,
  part of refill), d2h/step (device-to-host copies, `step_clock.HostCopies`: each would
  synchronise on CUDA; the refill reads the episode counters every 8 steps), and
  `frame` = wall - physics - the physics of start_episodes (its forward and state copies,
  timed around MuJoCo Warp's calls on Warp's CPU device, where nothing is captured; on CUDA
  they stay in start_episodes and in frame) - wait (the producers' pace, not the step's
  work): the framework's own cost per control step.
Fit, least squares over the sizes: frame ms = fixed + µs per world-step * num_envs (goal on
  Warp's CPU device, episodes at the tasks' own length: <= 1 ms fixed, <= 0.25 µs per
  world-step).
Table 3: initial states per second of the producers (the CPU task's initializers), threads
  and processes, 1 and 2 workers.
Baselines (`--baselines`), on this machine's cores: the threaded CPU vector env (one
  sub-environment per core) and the mj_step ceiling (one thread per core, raw
  `mujoco.mj_step` on its own MjData); batch / ceiling is the speed-up over the CPU (goal on a
  GPU: >= 2 at the best num_envs).

`--skip-physics` (Warp's CPU device only, where no graph is captured) replaces the physics
sub-steps by nothing, so that a run long enough for episodes at their own length (300 steps:
every world resets once) takes seconds; table 1 is then left out.

`--producers-ahead`: the split's steps run while the producers are idle: every state the
window's episodes start from is made before it (no refill during the window, whose
`refill_interval` is set longer), episodes keep their natural length. The producers' pace
is table 3's; on a host with few cores, producers at work during the window slow the
step's own work as any other load does (on the development machine's 2 vCPUs an unrelated
busy process slows NumPy's work on the other by 35-60%), which is the machine's, not the
framework's, cost.

Usage: python benchmarks/batch_env.py [--device cpu|cuda:0] [--num-envs 64,256]
  [--steps 50] [--tasks reach_site_features,lift_brick_features] [--namespace numpy|torch]
  [--episodes own,1] [--stagger] [--skip-physics] [--state-workers 1] [--state-processes]
  [--baselines] [--producer-states 64] [--producers-ahead]. On Warp's CPU device the
  default num_envs are 64 and 256 (a control step of 256 lift worlds takes about half a
  second there); the framework fit there:
  `--skip-physics --producers-ahead --episodes own --steps 300`.
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
from composer.batch import initial_states, step_clock  # noqa: E402
from manipulation import batch  # noqa: E402
from manipulation.tasks import registry  # noqa: E402
from manipulation.tasks import task_constants as tc  # noqa: E402

# MuJoCo Warp's calls that start an episode (state copies, forward); the physics sub-steps
# call others (step, step1, step2).
_START_CALLS = ("forward", "kinematics", "set_state", "get_state", "reset_data")


class _StartPhysicsClock:
    """Accumulates the wall time of MuJoCo Warp's calls that start episodes, by wrapping
    them: on Warp's CPU device only, where `step` calls them (a CUDA graph would not)."""

    def __init__(self):
        self.seconds = 0.0
        self._originals = {name: getattr(mjw, name) for name in _START_CALLS}
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


def _batch_row(task: str, num_envs: int, time_limit: float | None, args) -> dict:
    """One env of `task`: its throughput (unless physics is skipped), then the split."""
    on_cpu = args.device == "cpu"
    options = {} if time_limit is None else {"time_limit": time_limit}
    env = batch.load(
        task,
        num_envs,
        device=args.device,
        seed=0,
        namespace=args.namespace,
        # Results stay on the device on CUDA; on the CPU NumPy's are the device's memory.
        array_type="numpy" if on_cpu else "torch",
        check_action_values=False,
        state_workers=args.state_workers,
        state_processes=args.state_processes,
        **(_states_ahead(task, time_limit, args.steps) if args.producers_ahead else {}),
        **options,
    )
    physics = env.physics
    if args.skip_physics:
        physics.step = lambda n_sub_steps=1: None
    env.reset()
    action = env.hand_out(np.zeros((num_envs, *env.action_spec().shape), np.float32))
    # Compiles kernels and captures graphs: a step, and a start of every world.
    env.step(action)
    env.episode_steps = np.full(num_envs, env.max_episode_steps - 1, np.int32)
    env.step(action)
    env.step(action)
    limit = env.max_episode_steps
    if args.stagger:
        env.episode_steps = np.random.RandomState(0).randint(0, limit, num_envs).astype(np.int32)
    else:
        env.episode_steps = np.zeros(num_envs, np.int32)
    row = {"steps": args.steps}
    if not args.skip_physics:
        env.synchronize()
        begin = time.perf_counter()
        for _ in range(args.steps):
            env.step(action)
        env.synchronize()
        row["batch"] = args.steps * num_envs / (time.perf_counter() - begin)
        row["raw"] = _raw_rate(physics, env.task.task.physics_steps_per_control_step, args.steps)
    if not args.stagger:
        env.episode_steps = np.zeros(num_envs, np.int32)
    clock = step_clock.StepClock(env.synchronize)
    before = env.initial_state_stats()
    start_physics = _StartPhysicsClock() if on_cpu else None
    try:
        with step_clock.HostCopies() as copies:
            env.step_clock = clock
            env.synchronize()
            begin = time.perf_counter()
            for _ in range(args.steps):
                env.step(action)
            env.synchronize()
            wall = time.perf_counter() - begin
            env.step_clock = None
    finally:
        if start_physics is not None:
            start_physics.restore()
    after = env.initial_state_stats()
    env.close()
    parts = clock.milliseconds_per_step()
    wall_ms = 1e3 * wall / args.steps
    start_ms = 0.0 if start_physics is None else 1e3 * start_physics.seconds / args.steps
    wait_ms = 1e3 * (after.wait_seconds - before.wait_seconds) / args.steps
    row.update(
        parts=parts,
        wall_ms=wall_ms,
        wait_ms=wait_ms,
        d2h=copies.count / args.steps,
        frame_ms=wall_ms - parts["physics"] - start_ms - wait_ms,
        started=after.started - before.started,
        reused=after.reused - before.reused,
    )
    return row


def _states_ahead(task: str, time_limit: float | None, steps: int) -> dict:
    """The slots and refill interval with which every episode of a window of `steps` (after
    the three warm-up steps) starts from a state made before the window: no refill."""
    seconds = tc.TIME_LIMIT if time_limit is None else time_limit
    control_steps = round(seconds / registry.build_task(task).control_timestep)
    episodes = -(-steps // max(control_steps, 1)) + 3  # and the warm-up's restarts
    return {"slots_per_world": episodes, "refill_interval": steps + 8}


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


_SHORT = {
    "physics": "phys",
    "start_episodes": "start",
    "task": "task",
    "counters": "count",
    "observations": "obs",
    "refill": "refill",
    "action": "action",
    "hand_out": "out",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cpu", help="Warp device: cpu or cuda:0")
    parser.add_argument("--num-envs", default=None, help="comma-separated numbers of worlds")
    parser.add_argument("--steps", type=int, default=50, help="control steps per measurement")
    parser.add_argument("--tasks", default="reach_site_features,lift_brick_features")
    parser.add_argument(
        "--episodes", default="own,1", help="episode lengths: 'own' (the task's) and/or seconds"
    )
    parser.add_argument("--stagger", action="store_true", help="spread the episodes' starts")
    parser.add_argument(
        "--skip-physics", action="store_true", help="no physics sub-steps (CPU device only)"
    )
    parser.add_argument("--namespace", default=None, help="task code on numpy or torch")
    parser.add_argument("--baselines", action="store_true", help="threaded CPU and mj_step")
    parser.add_argument("--state-workers", type=int, default=1, help="initial-state producers")
    parser.add_argument(
        "--state-processes", action="store_true", help="producers in processes, not threads"
    )
    parser.add_argument("--producer-states", type=int, default=64, help="states per timing")
    parser.add_argument(
        "--producers-ahead", action="store_true", help="the split's states made before it"
    )
    args = parser.parse_args()
    if args.skip_physics and args.device != "cpu":
        parser.error("--skip-physics: Warp's CPU device only (a CUDA step replays graphs)")
    if args.producers_ahead and not args.skip_physics:
        parser.error("--producers-ahead: with --skip-physics only (one window of steps)")
    default_sizes = "64,256" if args.device == "cpu" else "1024,4096,8192"
    sizes = [int(n) for n in (args.num_envs or default_sizes).split(",")]
    tasks = args.tasks.split(",")
    episodes = [None if e == "own" else float(e) for e in args.episodes.split(",")]
    producers = f"{args.state_workers} {'processes' if args.state_processes else 'threads'}"
    print(
        f"producers {producers}, device {args.device}, namespace {args.namespace or 'default'}, "
        f"{args.steps} steps per row, starts {'staggered' if args.stagger else 'together'}, "
        f"physics {'skipped' if args.skip_physics else 'on'}, "
        f"producers {'idle (states made ahead)' if args.producers_ahead else 'at work'} in the "
        f"split, {os.cpu_count()} cores, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    parts = " ".join(f"{short:>6}" for short in _SHORT.values())
    print(
        f"{'task':<20} {'episode':>7} {'n':>5} {'batch/s':>8} {'raw/s':>8} {'ovh':>5} | {parts} "
        f"{'sum':>6} {'wall':>6} {'wait':>6} {'frame':>6} {'d2h':>5} {'reused':>9}"
    )
    for task in tasks:
        for seconds in episodes:
            rows = [_batch_row(task, n, seconds, args) for n in sizes]
            label = "own" if seconds is None else f"{seconds:g} s"
            for n, row in zip(sizes, rows):
                rates = (
                    f"{row['batch']:>8.0f} {row['raw']:>8.0f} {row['raw'] / row['batch']:>5.2f}"
                    if "batch" in row
                    else f"{'-':>8} {'-':>8} {'-':>5}"
                )
                split = " ".join(f"{row['parts'][part]:>6.2f}" for part in _SHORT)
                print(
                    f"{task:<20} {label:>7} {n:>5} {rates} | {split} "
                    f"{sum(row['parts'].values()):>6.2f} {row['wall_ms']:>6.2f} "
                    f"{row['wait_ms']:>6.2f} {row['frame_ms']:>6.3f} {row['d2h']:>5.3f} "
                    f"{row['reused']:>4}/{row['started']:<4}"
                )
            if len(sizes) > 1:
                fixed, per_world = _fit(sizes, [row["frame_ms"] for row in rows])
                print(
                    f"{task:<20} {label:>7} frame fit: {fixed:.3f} ms fixed + "
                    f"{per_world:.3f} µs/world-step"
                )
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
