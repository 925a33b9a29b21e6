"""Speed of the manipulation suite per task: reset, env.step and the raw physics it wraps.

Columns, per task (medians; each trial starts from a fresh `env.reset()`):
  reset ms: one `env.reset()`.
  step ms: one `env.step` with uniform random actions (observations included).
  raw ms: the physics of that step alone, `mujoco.mj_step(model, data, 20)` on the same
    model, from the same state with the same controls, timed in the same trial.
  overhead: step / raw (target <= 1.10). For vision tasks, measured with the camera
    observable disabled, so that it shows what the framework adds around the physics.
  render: for vision tasks, the share of the step spent rendering the 84x84 `front_close`
    image: 1 - (step without the camera) / (step with it).

With `--dm-control`, also runs reach_site, lift_brick and stack_3_bricks (features) under
dm_control 1.0.50 + mujoco 3.17.0 in a separate virtual environment (built with pip when
missing) with the same number of steps of the same kind of random actions, and prints
our step time against dm_control's (target: ratio <= 0.5).

Usage: python benchmarks/manipulation.py [NAME ...] [--trials N] [--steps N]
           [--dm-control] [--dm-control-venv PATH]
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

# Headless rendering for the vision tasks, chosen before mujoco is imported.
os.environ.setdefault("MUJOCO_GL", "egl")
# This file is named like the package it measures: without its own folder on the path,
# `import manipulation` finds the package rather than this script.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

import manipulation  # noqa: E402

_OVERHEAD_TARGET = 1.10
_DM_CONTROL_TARGET = 0.5
_DM_CONTROL_TASKS = ("reach_site_features", "lift_brick_features", "stack_3_bricks_features")
_DM_CONTROL_REQUIREMENTS = ("dm-control==1.0.50", "mujoco==3.17.0")
_CAMERA = "front_close"
# Vision steps render in software on machines without a GPU (tens of ms per frame).
_VISION_STEPS, _VISION_TRIALS = 5, 3

# Runs inside the dm_control venv as a server, so that its trials can alternate with ours:
# argv[1] is a JSON list [names, steps, seed]; it prints "ready", then for each task name
# read from stdin runs one trial (a reset, then `steps` random actions) and prints a JSON
# list [reset s, mean step s].
_DM_CONTROL_SCRIPT = """
import json, sys, time
import numpy as np
from dm_control import manipulation
names, steps, seed = json.loads(sys.argv[1])
envs, actions = {}, {}
for name in names:
    envs[name] = env = manipulation.load(name, seed=seed)
    spec = env.action_spec()
    actions[name] = np.random.RandomState(seed).uniform(spec.minimum, spec.maximum, (steps, 9))
print("ready", flush=True)
for line in sys.stdin:
    name = line.strip()
    env = envs[name]
    start = time.perf_counter()
    env.reset()
    middle = time.perf_counter()
    for action in actions[name]:
        env.step(action)
    end = time.perf_counter()
    print(json.dumps([middle - start, (end - middle) / steps]), flush=True)
"""


def _time_trials(env, actions, trials: int) -> tuple[list, list, list]:
    """Returns per-trial reset times and mean env.step and raw physics step times (s).

    Each trial resets the environment, copies its state into a second `MjData`, then
    alternates one raw physics step and one `env.step` with the same action, so that both
    follow the same trajectory and share the machine's load.
    """
    timer = time.perf_counter
    resets, step_times, raw_times = [], [], []
    for _ in range(trials):
        start = timer()
        env.reset()
        resets.append(timer() - start)
        model, data = env.physics.model.ptr, env.physics.data.ptr
        raw_data = mujoco.MjData(model)
        mujoco.mj_copyData(raw_data, model, data)
        n_sub_steps = env.task.physics_steps_per_control_step
        step_time = raw_time = 0.0
        for action in actions:
            start = timer()
            raw_data.ctrl[:] = action
            mujoco.mj_step(model, raw_data, n_sub_steps)
            middle = timer()
            env.step(action)
            raw_time += middle - start
            step_time += timer() - middle
        step_times.append(step_time / len(actions))
        raw_times.append(raw_time / len(actions))
    return resets, step_times, raw_times


def measure(name: str, steps: int, trials: int, seed: int = 0) -> dict:
    """Returns median reset, step and raw physics times (s), the overhead and render share.

    The overhead is the median over trials of step / raw. A vision task is measured twice:
    as it is (reset and step times), then with its camera observable disabled (overhead);
    the difference between the two step times is the rendering.
    """
    env = manipulation.load(name, seed=seed)
    spec = env.action_spec()
    actions = np.random.RandomState(seed).uniform(spec.minimum, spec.maximum, (steps, 9))
    rendered = None
    if name.endswith("_vision"):
        rendered = _time_trials(env, actions[:_VISION_STEPS], min(trials, _VISION_TRIALS))
        env.task.observables[_CAMERA].enabled = False
    resets, step_times, raw_times = _time_trials(env, actions, trials)
    step = statistics.median(step_times)
    result = {
        "reset": statistics.median(resets),
        "step": step,
        "raw": statistics.median(raw_times),
        "overhead": statistics.median(s / r for s, r in zip(step_times, raw_times)),
        "render_share": None,
    }
    if rendered is not None:
        result["reset"] = statistics.median(rendered[0])
        result["step"] = statistics.median(rendered[1])
        result["render_share"] = 1.0 - step / result["step"]
    return result


def _print_task_table(results: dict) -> None:
    print(f"{'task':<44}{'reset ms':>9}{'step ms':>9}{'raw ms':>9}{'overhead':>10}{'render':>8}")
    for name, row in results.items():
        share = "" if row["render_share"] is None else f"{row['render_share']:.0%}"
        flag = "" if row["overhead"] <= _OVERHEAD_TARGET else "  > target"
        print(
            f"{name:<44}{row['reset'] * 1e3:>9.2f}{row['step'] * 1e3:>9.3f}"
            f"{row['raw'] * 1e3:>9.3f}{row['overhead']:>10.3f}{share:>8}{flag}"
        )
    overheads = [row["overhead"] for row in results.values()]
    print(
        f"overhead (target <= {_OVERHEAD_TARGET}): median {statistics.median(overheads):.3f}, "
        f"max {max(overheads):.3f}"
    )


def _dm_control_python(venv: pathlib.Path) -> pathlib.Path:
    """Returns the venv's python, creating the venv with dm_control when it is missing."""
    python = venv / "bin" / "python"
    if not python.exists():
        print(f"building {venv} with {' '.join(_DM_CONTROL_REQUIREMENTS)} ...", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        subprocess.run(
            [str(python), "-m", "pip", "install", "-q", *_DM_CONTROL_REQUIREMENTS], check=True
        )
    return python


def _our_trial(env, actions) -> tuple[float, float]:
    """Returns the time of one reset and the mean time of one env.step over `actions`."""
    start = time.perf_counter()
    env.reset()
    middle = time.perf_counter()
    for action in actions:
        env.step(action)
    return middle - start, (time.perf_counter() - middle) / len(actions)


def _compare_with_dm_control(venv, steps: int, trials: int, seed: int = 0) -> None:
    """Prints our reset and step times against dm_control's, trial by trial alternating."""
    python = _dm_control_python(pathlib.Path(venv))
    # dm_control logs its resets' IK warnings: kept out of the table, shown on a failure.
    errors = tempfile.TemporaryFile("w+")
    server = subprocess.Popen(
        [str(python), "-c", _DM_CONTROL_SCRIPT, json.dumps([_DM_CONTROL_TASKS, steps, seed])],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=errors,
        text=True,
    )

    def reply() -> str:
        line = server.stdout.readline()
        if not line:
            errors.seek(0)
            sys.exit(f"dm_control stopped in {venv}:\n{errors.read()}")
        return line

    if reply().strip() != "ready":
        sys.exit(f"dm_control did not start in {venv}")
    envs = {name: manipulation.load(name, seed=seed) for name in _DM_CONTROL_TASKS}
    actions = {
        name: np.random.RandomState(seed).uniform(
            env.action_spec().minimum, env.action_spec().maximum, (steps, 9)
        )
        for name, env in envs.items()
    }
    ours = {name: [] for name in _DM_CONTROL_TASKS}
    theirs = {name: [] for name in _DM_CONTROL_TASKS}
    for _ in range(trials):
        for name, env in envs.items():
            server.stdin.write(name + "\n")
            server.stdin.flush()
            theirs[name].append(json.loads(reply()))
            ours[name].append(_our_trial(env, actions[name]))
    server.stdin.close()
    server.wait()
    print(f"\nvs dm_control 1.0.50 + mujoco 3.17.0 ({venv}): same random actions, trials alternate")
    print(
        f"{'task':<30}{'reset ms':>10}{'dmc reset':>11}{'step ms':>9}{'dmc step':>10}"
        f"{'ratio':>8}{'target':>9}"
    )
    for name in _DM_CONTROL_TASKS:
        our_reset, our_step = (statistics.median(column) for column in zip(*ours[name]))
        their_reset, their_step = (statistics.median(column) for column in zip(*theirs[name]))
        ratio = statistics.median(o[1] / t[1] for o, t in zip(ours[name], theirs[name]))
        print(
            f"{name:<30}{our_reset * 1e3:>10.2f}{their_reset * 1e3:>11.2f}"
            f"{our_step * 1e3:>9.3f}{their_step * 1e3:>10.3f}"
            f"{ratio:>8.3f}{'<= ' + str(_DM_CONTROL_TARGET):>9}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="tasks to measure (default: all)")
    parser.add_argument("--trials", type=int, default=15, help="resets per task")
    parser.add_argument("--steps", type=int, default=50, help="control steps per trial")
    parser.add_argument("--dm-control", action="store_true", help="compare with dm_control")
    parser.add_argument("--dm-control-venv", default=".bench/dmc-venv", help="its venv")
    args = parser.parse_args()
    unknown = sorted(set(args.names) - set(manipulation.ALL))
    if unknown:
        parser.error(f"unknown task(s) {unknown}; expected names from manipulation.ALL")
    if args.trials < 1 or args.steps < 1:
        parser.error(f"--trials and --steps must be >= 1, got {args.trials}, {args.steps}")

    results = {}
    for name in args.names or manipulation.ALL:
        results[name] = measure(name, args.steps, args.trials)
    _print_task_table(results)
    if args.dm_control:
        _compare_with_dm_control(args.dm_control_venv, args.steps, args.trials)


if __name__ == "__main__":
    main()
