"""dm_control's Control Suite batched (`suite_batch`) against a plain loop, the raw physics
and EnvPool, as ratios from one run.

For each task of `--tasks` (default: the seven of the issue), at `--num-envs` worlds (256)
on `--threads` C threads (2), in env-steps per second (one world's control step each), over
`--steps` control steps (1,000) with the suite's own episodes (1,000 control steps for
these seven; `--episode-steps` shortens them), after 10 untimed steps, so that every world
starts one new episode inside the timed window, as often as training meets them:

  loop: a plain loop of `--loop-envs` `suite.load` envs (through the redirect), reset
    after LAST, as a dm_control user steps them;
  raw: `mujoco.batch.Batch` of the task's own model, the same worlds and threads, from
    the batch's first states (the suite's random starts: a default pose can be far cheaper
    to step), stepped as the batch steps (controls through `bind("ctrl")`, `n_sub_steps`
    physics steps ending at the velocity stage), no task code and no episode starts: the
    physics alone, the ceiling;
  batch: `suite_batch.load(domain, task, N, threads=...)`, and batch / loop, batch / raw;
  envpool: EnvPool 1.2.5's `make_dm` at the same N (batch size N) and threads, with the
    same episode length, run in a scratch venv (`.cache/suite_batch_bench/envpool-venv`,
    built on first use from PyPI, never a dependency of this project); batch / envpool and
    their geometric mean. Without it (`--no-envpool`, or when the venv cannot be built)
    the column says absent.

Throughputs are medians of `--repeats` trials; in each trial every row of every task is
measured in turn, so that load from other processes spreads over all rows. Actions are
uniform in the action spec, the same for every row. The number of cores and the 1-minute
load average are printed with the table, which ends with one JSON line of the medians,
env-steps/s keyed by task: {"cheetah-run": {"loop": ..., "raw": ..., "batch": ...,
"envpool": ... or null}, ...}.

Needs dm_control's suite: run from the project's venv, the script re-runs itself in the
dm_control conformance harness's venv (dm_control 1.0.50 on the newest MuJoCo, built on
first use), as the batched suite's tests do.

With `--pixels`, it measures instead frames per second with dm_control's pixel observations
(84x84, camera 0), for cartpole-swingup and walker-walk (or `--tasks`): a loop of
`--loop-envs` envs in dm_control's `pixels.Wrapper` beside `suite_batch.pixels.Wrapper` over
the batch (run it with `--num-envs 64`), and ends with a JSON line of those.

Usage: python benchmarks/suite_batch.py [--tasks cheetah-run,walker-walk] [--num-envs 256]
    [--threads 2] [--steps 1000] [--episode-steps N] [--repeats 3] [--no-envpool] [--pixels]
"""

import argparse
import importlib.util
import json
import math
import os
import pathlib
import statistics
import subprocess
import sys
import time

# `import suite_batch` finds the package rather than this script.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

import numpy as np  # noqa: E402

_ROOT = _HERE.parent
_ENVPOOL_VENV = _ROOT / ".cache" / "suite_batch_bench" / "envpool-venv"
_ENVPOOL_VERSION = "1.2.5"
TASKS = (
    "cheetah-run",
    "walker-walk",
    "humanoid-run",
    "cartpole-swingup",
    "finger-spin",
    "quadruped-run",
    "hopper-hop",
)

# EnvPool's own benchmark, run in its venv: argv is a JSON list of jobs, it prints one JSON
# list of env-steps/s.
_ENVPOOL_SCRIPT = """
import json, sys, time
import envpool, numpy as np
rates = []
for job in json.loads(sys.argv[1]):
    env = envpool.make_dm(job["id"], num_envs=job["n"], batch_size=job["n"],
                          num_threads=job["threads"], max_episode_steps=job["episode_steps"])
    spec = env.action_spec()
    rng = np.random.RandomState(2)
    actions = rng.uniform(spec.minimum, spec.maximum, (job["steps"], job["n"], *spec.shape))
    env.reset()
    for t in range(10):
        env.step(actions[t])
    start = time.perf_counter()
    for t in range(job["steps"]):
        env.step(actions[t])
    rates.append(job["steps"] * job["n"] / (time.perf_counter() - start))
    env.close()
print(json.dumps(rates))
"""


def _in_suite_venv() -> None:
    """Re-runs this script in the conformance venv when dm_control's suite is missing."""
    try:
        found = importlib.util.find_spec("dm_control.suite") is not None
    except ModuleNotFoundError:
        found = False
    if found:
        return
    sys.path.insert(0, str(_ROOT))
    from tools import dm_control_conformance

    python = dm_control_conformance.ensure_conformance_venv()
    env = {**os.environ, "PYTHONPATH": str(_ROOT)}
    sys.exit(subprocess.call([str(python), __file__, *sys.argv[1:]], env=env))


def _split(task: str) -> tuple[str, str]:
    domain, _, name = task.partition("-")
    return domain, name


def _envpool_id(task: str) -> str:
    """EnvPool's id of a suite task ("CheetahRun-v1", "BallInCupCatch-v1")."""
    domain, name = _split(task)
    words = [*domain.split("_"), *name.split("_")]
    return "".join(word[:1].upper() + word[1:] for word in words) + "-v1"


def _actions(spec, steps: int, n: int) -> np.ndarray:
    return np.random.RandomState(2).uniform(spec.minimum, spec.maximum, (steps, n, *spec.shape))


class _Rows:
    """The rows of one task, each a callable returning env-steps/s."""

    def __init__(self, suite, task: str, args):
        import suite_batch

        domain, name = _split(task)
        self.task = task
        self.args = args
        probe = suite.load(domain, name)
        if args.episode_steps is None:
            self.episode_steps = int(round(probe._step_limit))  # dm_control's own
            self._task_kwargs = {}
        else:
            self.episode_steps = args.episode_steps
            time_limit = (args.episode_steps + 0.5) * probe.control_timestep()
            self._task_kwargs = {"time_limit": time_limit}
        probe.close()
        self._loop_envs = [
            suite.load(domain, name, task_kwargs={"random": i, **self._task_kwargs})
            for i in range(args.loop_envs)
        ]
        self._batch = suite_batch.load(
            domain,
            name,
            args.num_envs,
            task_kwargs=self._task_kwargs,
            seed=0,
            threads=args.threads,
        )
        spec = self._batch.action_spec()
        self._actions = _actions(spec, args.steps + 10, args.num_envs)

    def loop(self) -> float:
        steps = self.args.steps
        actions = self._actions[:, : len(self._loop_envs)]
        for env in self._loop_envs:
            env.reset()
        start = time.perf_counter()
        for t in range(steps):
            for env, action in zip(self._loop_envs, actions[t]):
                if env.step(action).last():
                    env.reset()
        return steps * len(self._loop_envs) / (time.perf_counter() - start)

    def raw(self) -> float:
        import mujoco
        from mujoco import batch as mujoco_batch

        host = self._loop_envs[0].physics
        n_sub = int(self._loop_envs[0]._n_sub_steps)
        worlds = mujoco_batch.Batch(
            host.model.ptr, self.args.num_envs, nthread=self.args.threads, persistent=True
        )
        # From the batch's own first states (the suite's random starts), so that the
        # physics does the same work as the batch's: a model's default pose can be far
        # cheaper to step (no contacts) than the states its episodes start from.
        self._batch.reset()
        worlds.reset()
        worlds.state[...] = self._batch.physics.batch.state
        worlds.forward()
        ctrl = worlds.bind("ctrl")
        stage = int(mujoco.mjtStage.mjSTAGE_VEL)
        start = time.perf_counter()
        for t in range(self.args.steps):
            ctrl[...] = self._actions[t]
            worlds.step(nstep=n_sub, stage=stage)
        return self.args.steps * self.args.num_envs / (time.perf_counter() - start)

    def batch(self) -> float:
        env, steps = self._batch, self.args.steps
        env.reset()
        for t in range(10):
            env.step(self._actions[t])
        start = time.perf_counter()
        for t in range(steps):
            env.step(self._actions[10 + t])
        return steps * env.num_envs / (time.perf_counter() - start)

    def envpool_job(self) -> dict:
        return {
            "id": _envpool_id(self.task),
            "n": self.args.num_envs,
            "threads": self.args.threads,
            "steps": self.args.steps,
            "episode_steps": self.episode_steps,
        }


def _envpool_python(args) -> pathlib.Path | None:
    """The scratch venv's Python with EnvPool, built on first use; None if unavailable."""
    if args.no_envpool:
        return None
    python = _ENVPOOL_VENV / "bin" / "python"
    if not python.exists():
        try:
            subprocess.run([sys.executable, "-m", "venv", str(_ENVPOOL_VENV)], check=True)
            subprocess.run(
                [str(python), "-m", "pip", "install", "-q", f"envpool=={_ENVPOOL_VERSION}"],
                check=True,
            )
        except subprocess.CalledProcessError as error:
            print(f"EnvPool {_ENVPOOL_VERSION}: could not build its venv ({error}); absent")
            return None
    return python


def _envpool_rates(python: pathlib.Path, jobs: list[dict]) -> list[float]:
    done = subprocess.run(
        [str(python), "-c", _ENVPOOL_SCRIPT, json.dumps(jobs)],
        check=True,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def _number(value: float | None) -> str:
    return "absent" if value is None else f"{value:,.0f}"


def _ratio(a: float | None, b: float | None) -> str:
    return "-" if a is None or b is None else f"{a / b:.2f}x"


#: The pixels table's tasks and rendering (what pixel-based agents render).
PIXEL_TASKS = ("cartpole-swingup", "walker-walk")
PIXEL_RENDER = {"height": 84, "width": 84, "camera_id": 0}


def _pixel_rates(suite, task: str, args) -> dict[str, float]:
    """Frames per second (one world's control step and frame each) of a loop of
    dm_control's pixel-wrapped envs and of the batch's `suite_batch.pixels.Wrapper`."""
    from dm_control.suite.wrappers import pixels as dm_pixels

    import suite_batch
    from suite_batch import pixels

    domain, name = _split(task)
    loop_envs = [
        dm_pixels.Wrapper(suite.load(domain, name, task_kwargs={"random": i}), True, PIXEL_RENDER)
        for i in range(args.loop_envs)
    ]
    batch = pixels.Wrapper(
        suite_batch.load(domain, name, args.num_envs, seed=0, threads=args.threads),
        render_kwargs=PIXEL_RENDER,
    )
    actions = _actions(batch.action_spec(), args.steps + 10, args.num_envs)
    for env in loop_envs:
        env.reset()
    start = time.perf_counter()
    for t in range(args.steps):
        for env, action in zip(loop_envs, actions[t]):
            if env.step(action).last():
                env.reset()
    loop = args.steps * len(loop_envs) / (time.perf_counter() - start)
    batch.reset()
    for t in range(10):
        batch.step(actions[t])
    start = time.perf_counter()
    for t in range(args.steps):
        batch.step(actions[10 + t])
    rate = args.steps * args.num_envs / (time.perf_counter() - start)
    batch.close()
    return {"loop": loop, "batch": rate}


def _pixels_main(args) -> None:
    from suite_batch import loading

    suite = loading.import_suite()
    tasks = [task for task in args.tasks.split(",") if task] if args.tasks else PIXEL_TASKS
    samples = {task: {"loop": [], "batch": []} for task in tasks}
    for _ in range(args.repeats):
        for task in tasks:
            for name, rate in _pixel_rates(suite, task, args).items():
                samples[task][name].append(rate)
    medians = {
        task: {name: statistics.median(values) for name, values in columns.items()}
        for task, columns in samples.items()
    }
    print(
        f"\ncores: {len(os.sched_getaffinity(0))}, load average (1 min): "
        f"{os.getloadavg()[0]:.2f}, N={args.num_envs}, threads={args.threads}, "
        f"{args.steps} control steps timed, frames {PIXEL_RENDER}, medians of "
        f"{args.repeats}; frames/s\n"
    )
    print("| task | loop of pixels.Wrapper envs | batch pixels.Wrapper | batch / loop |")
    print("|---|---|---|---|")
    for task, m in medians.items():
        print(
            f"| {task} | {_number(m['loop'])} | {_number(m['batch'])} | "
            f"{_ratio(m['batch'], m['loop'])} |"
        )
    print(json.dumps(medians))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", default=None)
    parser.add_argument("--num-envs", type=int, default=256)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--episode-steps", type=int, default=None)
    parser.add_argument("--loop-envs", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-envpool", action="store_true")
    parser.add_argument("--pixels", action="store_true")
    args = parser.parse_args()
    _in_suite_venv()
    if args.pixels:
        _pixels_main(args)
        return
    from suite_batch import loading

    suite = loading.import_suite()
    tasks = [task for task in args.tasks.split(",") if task] if args.tasks else list(TASKS)
    rows = {task: _Rows(suite, task, args) for task in tasks}
    envpool_python = _envpool_python(args)
    samples = {task: {"loop": [], "raw": [], "batch": [], "envpool": []} for task in tasks}
    for trial in range(args.repeats):
        for task, row in rows.items():
            for name in ("loop", "raw", "batch"):
                samples[task][name].append(getattr(row, name)())
        if envpool_python is not None:
            rates = _envpool_rates(envpool_python, [rows[task].envpool_job() for task in tasks])
            for task, rate in zip(tasks, rates):
                samples[task]["envpool"].append(rate)
        print(f"trial {trial + 1} of {args.repeats} done", flush=True)
    medians = {
        task: {
            name: (statistics.median(values) if values else None)
            for name, values in columns.items()
        }
        for task, columns in samples.items()
    }
    print(
        f"\ncores: {len(os.sched_getaffinity(0))}, load average (1 min): "
        f"{os.getloadavg()[0]:.2f}, N={args.num_envs}, threads={args.threads}, "
        f"{args.steps} control steps timed, episodes of "
        f"{args.episode_steps or 'the suite task own'} control steps, "
        f"medians of {args.repeats}; env-steps/s\n"
    )
    print("| task | loop | raw | batch | envpool | batch/loop | batch/raw | batch/envpool |")
    print("|---|---|---|---|---|---|---|---|")
    logs = []
    for task, m in medians.items():
        print(
            f"| {task} | {_number(m['loop'])} | {_number(m['raw'])} | {_number(m['batch'])} | "
            f"{_number(m['envpool'])} | {_ratio(m['batch'], m['loop'])} | "
            f"{_ratio(m['batch'], m['raw'])} | {_ratio(m['batch'], m['envpool'])} |"
        )
        if m["envpool"]:
            logs.append(math.log(m["batch"] / m["envpool"]))
    if logs:
        print(f"\ngeometric mean of batch/envpool: {math.exp(statistics.mean(logs)):.2f}x")
    print(json.dumps(medians))


if __name__ == "__main__":
    main()
