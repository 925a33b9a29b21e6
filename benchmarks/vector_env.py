"""Gymnasium adapter overhead and vector env throughput, as ratios from one run.

Tasks: manipulation tasks named by `--tasks` (default `lift_brick_features`, 20 physics
steps per control step); the adapter, GIL and free-ceiling rows use the first one, the
throughput table is printed for each (a vision task's steps render its cameras; its
lock-step ceiling is still raw `mj_step` only).

Rows:
  GIL held: CPU time per adapter step that is Python rather than MuJoCo, and the
    speed-up two threads could reach at most with that much serial work (Amdahl).
  adapter: `GymnasiumEnv.step` / `composer.Environment.step`, from the same states with
    the same actions, steps interleaved (median of per-trial ratios; target <= 1.05).
  threaded N: `ThreadedVectorEnv` of N sub-environments (one thread per core, the
    calling one included) in environment steps per second / one `GymnasiumEnv` stepped
    in a loop, both with autoreset (targets: >= 0.97x at N = 1); the same for
    `gymnasium.vector.AsyncVectorEnv` (one process per sub-environment, spawned rather
    than forked for a task with image observations: a forked worker cannot make an EGL
    context once the benchmark has rendered) and
    `gymnasium.vector.SyncVectorEnv` (the sub-environments in turn, in the calling
    thread) over the same sub-environments, and threaded / async.
  free ceiling: one thread per core, each calling raw `mj_step(model, data, 20)` on its
    own `MjData` with no hand-off at all / one thread doing the same calls.
  lock-step ceiling N: a plain script, no environment: k = min(N, cores) threads (the
    main one included) each calling `mujoco.mj_step(model, data, 20)` on a fixed share of
    N `MjData`, between two `threading.Barrier` waits per vector step / the same calls
    on one thread. What a vector env that steps in lock step can reach at best on this
    machine; "of ceiling" is threaded/loop over it (target >= 95% at N = 4 and 8).
  ray N: `RayVectorEnv` of N sub-environments in actors of ceil(N / cores)
    sub-environments (one actor per core, on a local Ray started by the benchmark), its
    steps/s next to the loop's and the threaded env's from the same trials; Ray's cost
    per vector step, 1 / (ray vector steps/s) - 1 / (threaded vector steps/s), next to
    an empty round trip to as many actors (a call that returns its argument, to each
    actor at once), measured in the same trials (target: cost <= 1.5x the round trip).
  ray envs per actor: the largest N in actors of 1, 2, 4, ... sub-environments (an
    actor with c cores' worth of the machine steps its share on c threads).
    Skipped, like the ray rows, when Ray is not installed or with --no-ray.

Throughputs are medians over `--repeats` trials of `--steps` vector steps each; in each
trial every row of every N is measured in turn, so that load from other processes
spreads over all rows; ratios are medians of the ratios within each trial. The number
of cores and the 1-minute load average are printed with the tables: on a machine
shared with other work the ratios are noisy.

Usage: python benchmarks/vector_env.py [--steps N] [--repeats K] [--sizes 1,2,4,8]
    [--tasks lift_brick_features,reach_site_vision] [--no-ray] [--envs-per-actor 1,2,4,8]
"""

import argparse
import functools
import importlib.util
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

import gymnasium  # noqa: E402
import mujoco  # noqa: E402

import manipulation  # noqa: E402
from composer.gym import GymnasiumEnv, RayVectorEnv, ThreadedVectorEnv  # noqa: E402

_TASK = "lift_brick_features"
_ADAPTER_TARGET = 1.05
_SINGLE_TARGET = 0.97  # threaded / loop at N = 1
_CEILING_TARGET = 0.95  # threaded / loop over the lock-step ceiling, at N = 4 and 8
_RAY_TARGET = 1.5  # Ray's cost per vector step over an empty actor round trip


def _make_env(task: str = _TASK) -> GymnasiumEnv:
    return GymnasiumEnv(manipulation.load(task))


def _renders_images(env: GymnasiumEnv) -> bool:
    """Whether any of the env's observations is an image: uint8, (..., height, width, channels)."""
    spaces = env.observation_space.values()
    return any(space.dtype == "uint8" and len(space.shape) >= 3 for space in spaces)


def _actions(space: gymnasium.Space, count: int, seed: int) -> list:
    space.seed(seed)
    return [space.sample() for _ in range(count)]


def _episode_steps(task: str) -> int:
    """The steps of one episode of the task before its time limit ends it."""
    env = manipulation.load(task)
    steps = math.ceil(env.time_limit / env.control_timestep()) - 1
    env.close()
    return steps


def adapter_ratio(task: str, steps: int, repeats: int) -> float:
    """Median over trials of (adapter step time) / (dm_env step time).

    Two environments seeded alike take the same actions, so they pass through the same
    states; their steps alternate, so load from other processes hits both alike.
    """
    gym_env = _make_env(task)
    dm = manipulation.load(task)
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


def python_share(task: str, steps: int, repeats: int) -> tuple[float, float]:
    """CPU microseconds per `GymnasiumEnv.step`, and how many of them are Python.

    The Python part (the GIL is held) is the step's CPU time less that of the same
    `mj_step2`, `mj_step(n - 1)`, `mj_step1` calls from the same states (n physics
    steps per control step). CPU time of this thread is used, so that waiting for a
    core does not count.
    """
    gym_env = _make_env(task)
    _, sub_steps = _load_model(task)
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
            mujoco.mj_step(model, twin, sub_steps - 1)
            mujoco.mj_step1(model, twin)
        raw = clock() - start
        totals.append(total / steps * 1e6)
        pythons.append((total - raw) / steps * 1e6)
    gym_env.close()
    return statistics.median(totals), statistics.median(pythons)


def _load_model(task: str) -> tuple[mujoco.MjModel, int]:
    """The task's model and its physics steps per control step."""
    env = manipulation.load(task)
    model = env.physics.model.ptr
    sub_steps = round(env.control_timestep() / env.physics.timestep())
    env.close()
    return model, sub_steps


class LockStepCeiling:
    """Raw `mj_step` on N `MjData`: one thread, and k threads in lock step (Barrier)."""

    def __init__(self, task: str, num_envs: int, threads: int, steps: int):
        self.model, self.sub_steps = _load_model(task)
        self.datas = [mujoco.MjData(self.model) for _ in range(num_envs)]
        self.threads = threads
        self.steps = steps
        self.ratios: list[float] = []

    def _step_share(self, share: list) -> None:
        for data in share:
            mujoco.mj_step(self.model, data, self.sub_steps)

    def _one_thread(self) -> float:
        start = time.perf_counter()
        for _ in range(self.steps):
            self._step_share(self.datas)
        return time.perf_counter() - start

    def _lock_step(self) -> float:
        k = self.threads
        shares = [self.datas[s::k] for s in range(k)]
        begin, end = threading.Barrier(k), threading.Barrier(k)

        def work(share):
            for _ in range(self.steps):
                begin.wait()
                self._step_share(share)
                end.wait()

        workers = [threading.Thread(target=work, args=(share,)) for share in shares[1:]]
        for worker in workers:
            worker.start()
        start = time.perf_counter()
        work(shares[0])
        elapsed = time.perf_counter() - start
        for worker in workers:
            worker.join()
        return elapsed

    def trial(self) -> None:
        single = self._one_thread()
        self.ratios.append(single / self._lock_step() if self.threads > 1 else 1.0)

    def median(self) -> float:
        return statistics.median(self.ratios)


def free_ceiling(task: str, threads: int, steps: int, repeats: int) -> float:
    """Steps/s of `threads` threads each running raw mj_step on its own `MjData`, free of
    any hand-off, / steps/s of one thread."""
    model, sub_steps = _load_model(task)
    datas = [mujoco.MjData(model) for _ in range(threads)]

    def run(data):
        for _ in range(steps):
            mujoco.mj_step(model, data, sub_steps)

    ratios = []
    for _ in range(repeats):
        start = time.perf_counter()
        run(datas[0])
        single = time.perf_counter() - start
        workers = [threading.Thread(target=run, args=(data,)) for data in datas]
        start = time.perf_counter()
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join()
        ratios.append(threads * single / (time.perf_counter() - start))
    return statistics.median(ratios)


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


class _Echo:
    """A Ray actor's body that does nothing: `echo` returns its argument."""

    def echo(self, data: bytes) -> bytes:
        return data


def _round_trip_rate(actors: list, steps: int) -> float:
    """Round trips per second of one call to each actor at once, waited for together."""
    import ray

    start = time.perf_counter()
    for _ in range(steps):
        ray.get([actor.echo.remote(b"") for actor in actors])
    return steps / (time.perf_counter() - start)


def _ray_vector_env(
    task: str, num_envs: int, envs_per_actor: int, cpus_per_actor: int
) -> RayVectorEnv:
    # An actor steps its sub-environments on as many threads as it has CPUs (at least 1).
    envs = RayVectorEnv(
        [functools.partial(_make_env, task)] * num_envs,
        envs_per_actor=envs_per_actor,
        num_cpus_per_actor=cpus_per_actor,
    )
    envs.reset(seed=0)
    return envs


class Throughput:
    """Environment steps per second of one loop, a threaded, an async and a sync vector
    env, the lock-step ceiling for N sub-environments of `task`, and with `use_ray` a Ray
    vector env of one actor per core and as many empty actors."""

    def __init__(self, task: str, num_envs: int, steps: int, use_ray: bool, cores: int):
        self.num_envs = num_envs
        self.steps = steps
        make = functools.partial(_make_env, task)
        self.ceiling = LockStepCeiling(task, num_envs, min(num_envs, cores), steps)
        self.single = make()
        self.single.reset(seed=0)
        self.threaded = ThreadedVectorEnv([make] * num_envs)
        self.threaded.reset(seed=0)
        # Forked workers cannot make an EGL context once this process has rendered
        # ("Offscreen framebuffer is not complete"), so a task that renders gets
        # freshly spawned ones; the rest get Gymnasium's default start method.
        context = "spawn" if _renders_images(self.single) else None
        self.asynchronous = gymnasium.vector.AsyncVectorEnv([make] * num_envs, context=context)
        self.asynchronous.reset(seed=0)
        self.synchronous = gymnasium.vector.SyncVectorEnv([make] * num_envs)
        self.synchronous.reset(seed=0)
        self.vector_actions = _actions(self.threaded.action_space, steps, seed=2)
        # The loop takes the first sub-environment's actions, so that at N = 1 it steps the
        # same episode as the vector envs: actions change what a step costs (a lift arm
        # touching the brick or not), and different ones put 5% between loop and threaded.
        self.single_actions = [action[0] for action in self.vector_actions]
        self.rates = {"loop": [], "threaded": [], "async": [], "sync": []}
        self.ray = None
        if use_ray:
            import ray

            self.envs_per_actor = math.ceil(num_envs / cores)
            # No CPU reservation: the actors of every N live at once, on `cores` cores.
            self.ray = _ray_vector_env(task, num_envs, self.envs_per_actor, cpus_per_actor=0)
            echo = ray.remote(_Echo).options(num_cpus=0)
            self.echoes = [echo.remote() for _ in self.ray.actors]
            _round_trip_rate(self.echoes, 1)  # the actors have started
            self.rates["ray"] = []
            self.rates["round trip"] = []

    def trial(self) -> None:
        self.ceiling.trial()
        self.rates["loop"].append(_loop_rate(self.single, self.single_actions))
        self.rates["threaded"].append(_vector_rate(self.threaded, self.vector_actions))
        self.rates["async"].append(_vector_rate(self.asynchronous, self.vector_actions))
        self.rates["sync"].append(_vector_rate(self.synchronous, self.vector_actions))
        if self.ray is not None:
            self.rates["ray"].append(_vector_rate(self.ray, self.vector_actions))
            self.rates["round trip"].append(_round_trip_rate(self.echoes, self.steps))

    def median(self, name: str) -> float:
        return statistics.median(self.rates[name])

    def ratio(self, numerator: str, denominator: str) -> float:
        """The median over trials of the ratio of two rates measured in the same trial."""
        pairs = zip(self.rates[numerator], self.rates[denominator])
        return statistics.median(a / b for a, b in pairs)

    def of_ceiling(self) -> float:
        """The median over trials of (threaded / loop) / lock-step ceiling."""
        speedups = (t / loop for t, loop in zip(self.rates["threaded"], self.rates["loop"]))
        return statistics.median(s / c for s, c in zip(speedups, self.ceiling.ratios))

    def ray_cost_ms(self) -> list[float]:
        """Per trial: ms per vector step that Ray adds to the threaded env's."""
        n = self.num_envs
        pairs = zip(self.rates["ray"], self.rates["threaded"])
        return [(n / ray_rate - n / threaded) * 1e3 for ray_rate, threaded in pairs]

    def close(self) -> None:
        self.single.close()
        self.threaded.close()
        self.asynchronous.close()
        self.synchronous.close()
        if self.ray is not None:
            import ray

            self.ray.close()
            for echo in self.echoes:
                ray.kill(echo)


def _table(header: tuple[str, ...], rows: list[tuple]) -> None:
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for row in rows:
        print("| " + " | ".join(row) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100, help="vector steps per trial")
    parser.add_argument("--repeats", type=int, default=5, help="trials per measurement")
    parser.add_argument("--sizes", default="1,2,4,8", help="numbers of sub-environments")
    parser.add_argument(
        "--tasks", default=_TASK, help="manipulation tasks, one throughput table each"
    )
    parser.add_argument("--no-ray", action="store_true", help="leave out the Ray rows")
    parser.add_argument(
        "--no-overhead", action="store_true", help="leave out the adapter, GIL and free rows"
    )
    parser.add_argument(
        "--envs-per-actor",
        default="1,2,4,8",
        help="sub-environments per Ray actor to compare, for the largest size",
    )
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    sizes = [int(size) for size in args.sizes.split(",")]
    use_ray = not args.no_ray and importlib.util.find_spec("ray") is not None
    if use_ray:
        import ray

        # "local": a new Ray of this machine, whatever an earlier run left behind.
        ray.init(address="local", num_cpus=cores, include_dashboard=False, log_to_driver=False)

    tasks = args.tasks.split(",")
    print(
        f"tasks {tasks}, {cores} cores, 1-minute load average {os.getloadavg()[0]:.2f} "
        f"at the start; {args.repeats} trials of {args.steps} vector steps, medians"
    )
    if not args.no_overhead:
        _print_overheads(tasks[0], args, cores)
    for task in tasks:
        benches = [Throughput(task, size, args.steps, use_ray, cores) for size in sizes]
        for _ in range(args.repeats):
            for bench in benches:
                bench.trial()
        print(f"\n{task}: 1-minute load average after the trials {os.getloadavg()[0]:.2f}\n")
        _print_throughput_table(benches)
        if use_ray:
            _print_ray_table(benches)
            _print_envs_per_actor(task, max(sizes), args, cores)
        for bench in benches:
            bench.close()


def _print_overheads(task: str, args: argparse.Namespace, cores: int) -> None:
    """The adapter, GIL and free-ceiling rows, for `task`."""
    # The adapter and GIL rows run one episode per trial: no more steps than it has.
    episode_steps = _episode_steps(task)
    adapter = adapter_ratio(task, min(args.steps * 2, episode_steps), args.repeats)
    verdict = "ok" if adapter <= _ADAPTER_TARGET else "MISSED"
    print(
        f"{task} adapter: GymnasiumEnv.step / Environment.step = {adapter:.3f} "
        f"(target <= {_ADAPTER_TARGET}: {verdict})"
    )
    total, python = python_share(task, min(args.steps * 2, episode_steps), args.repeats)
    print(
        f"GIL held: {python:.1f} of {total:.0f} CPU us per step are Python "
        f"({python / total:.0%}); Amdahl bound for {cores} threads "
        f"{1 / (python / total + (1 - python / total) / cores):.2f}x"
    )
    free = free_ceiling(task, cores, args.steps * 2, args.repeats)
    print(f"free ceiling: {cores} threads of raw mj_step, no hand-off / 1 thread = {free:.2f}x")


def _print_throughput_table(benches: list[Throughput]) -> None:
    rows = []
    for bench in benches:
        rates = (bench.median(n) for n in ("loop", "threaded", "async", "sync"))
        rows.append(
            (
                f"{bench.num_envs}",
                *(f"{rate:.0f}" for rate in rates),
                f"{bench.ratio('threaded', 'loop'):.2f}x",
                f"{bench.ceiling.median():.2f}x",
                f"{bench.of_ceiling():.0%}",
                f"{bench.ratio('async', 'loop'):.2f}x",
                f"{bench.ratio('sync', 'loop'):.2f}x",
                f"{bench.ratio('threaded', 'async'):.2f}x",
            )
        )
    _table(
        (
            "N",
            "loop steps/s",
            "threaded steps/s",
            "async steps/s",
            "sync steps/s",
            "threaded/loop",
            "lock-step ceiling",
            "threaded of ceiling",
            "async/loop",
            "sync/loop",
            "threaded/async",
        ),
        rows,
    )
    print(
        f"\ntargets: threaded/loop >= {_SINGLE_TARGET}x at N = 1; threaded >= "
        f"{_CEILING_TARGET:.0%} of the lock-step ceiling at N = 4 and 8"
    )


def _print_ray_table(benches: list[Throughput]) -> None:
    print()
    rows = []
    for bench in benches:
        loop, threaded, ray_rate = (bench.median(n) for n in ("loop", "threaded", "ray"))
        costs = bench.ray_cost_ms()
        trips = [1e3 / rate for rate in bench.rates["round trip"]]
        rows.append(
            (
                f"{bench.num_envs}",
                f"{bench.envs_per_actor}",
                f"{loop:.0f}",
                f"{threaded:.0f}",
                f"{ray_rate:.0f}",
                f"{bench.ratio('ray', 'threaded'):.2f}x",
                f"{statistics.median(costs):.2f}",
                f"{statistics.median(trips):.2f}",
                f"{statistics.median(c / t for c, t in zip(costs, trips)):.2f}x",
            )
        )
    _table(
        (
            "N",
            "envs per actor",
            "loop steps/s",
            "threaded steps/s",
            "ray steps/s",
            "ray/threaded",
            "ray cost ms per vector step",
            "empty round trip ms",
            "cost / round trip",
        ),
        rows,
    )
    print(f"\ntarget: Ray's cost per vector step <= {_RAY_TARGET}x an empty round trip")


def _print_envs_per_actor(task: str, num_envs: int, args: argparse.Namespace, cores: int) -> None:
    """Throughput of `num_envs` sub-environments for each of `--envs-per-actor`: actors
    reserve the machine's cores among them (at least one each), one thread per core."""
    counts = [int(c) for c in args.envs_per_actor.split(",") if int(c) <= num_envs]
    rows = []
    for count in counts:
        actors = math.ceil(num_envs / count)
        cpus = max(1, cores // actors) if actors <= cores else 0
        envs = _ray_vector_env(task, num_envs, count, cpus_per_actor=cpus)
        actions = _actions(envs.action_space, args.steps, seed=3)
        rates = [_vector_rate(envs, actions) for _ in range(args.repeats)]
        envs.close()
        rows.append((f"{count}", f"{actors}", f"{cpus}", f"{statistics.median(rates):.0f}"))
    print(f"\nray, N = {num_envs}, 1-minute load average {os.getloadavg()[0]:.2f}\n")
    _table(("envs per actor", "actors", "CPUs per actor", "ray steps/s"), rows)


if __name__ == "__main__":
    main()
