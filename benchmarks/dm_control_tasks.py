"""dm_control's own manipulation and Control Suite tasks: this project + mujoco 4 vs
dm_control 1.0.50 + 3.17.

Usage: `python benchmarks/dm_control_tasks.py [--trials 3] [--steps 200] [--resets 5]
[--tasks NAME ...] [--sections manipulation suite]`

Builds two scratch venvs under `.cache/dm_control_tasks` (once): real dm_control 1.0.50 on
mujoco 3.17.0, and dm_control 1.0.50 whose `composer`/`mjcf` are served by this project
(`composer.dm_control_compat`) on the project's mujoco. The same unmodified task code, seeds
and random actions run in both; trials alternate between the two. Prints a table of reset ms
and step ms (medians over trials), their ratio ours / dm_control, the time a reset spends in
MuJoCo's simulation pipeline (settling and placing props: the floor under the reset ratio),
and each one's step time over the raw `mj_step` calls of the same steps (the framework's
own overhead).

The suite section (`suite.load` of `SUITE_TASKS`; its `rl.control.Environment` and task
code are dm_control's in both venvs, its `dm_control.mujoco` engine is ours in one) prints
`env.step` over raw `mj_step` of the same steps, the engine's share (`physics.step`
over the same raw steps: what the engine adds to stepping), and `suite.load` over one raw
`mujoco.MjModel.from_xml_string` of the same XML and assets in the same process.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

# The repository root, for the scratch venvs of `tools` (a script's own folder is on the path).
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from tools import scratch_venv  # noqa: E402

DM_CONTROL = "dm-control==1.0.50"
DM_CONTROL_MUJOCO = "mujoco==3.17.0"
CACHE = scratch_venv.CACHE / "dm_control_tasks"

# A worker loads each task once, then answers "TASK" lines with one trial's timings: the
# mean reset time over RESETS resets and the mean step time over STEPS random actions.
_WORKER = r"""
import json, sys, time
import mujoco
import numpy as np
if sys.argv[1] == "ours":
    from composer import dm_control_compat
    dm_control_compat.install()
from dm_control import manipulation
resets, steps = int(sys.argv[2]), int(sys.argv[3])
environments = {}
print("READY", flush=True)
for line in sys.stdin:
    name = line.strip()
    if name not in environments:
        environments[name] = manipulation.load(name, seed=0)
        environments[name].reset()
    env = environments[name]
    spec = env.action_spec()
    rng = np.random.RandomState(0)
    actions = rng.uniform(spec.minimum, spec.maximum, size=(steps,) + spec.shape)
    env.random_state.seed(1)
    # Time inside MuJoCo's simulation pipeline (mj_step*, mj_forward*, mj_fwd*) during the
    # resets: settling and placing props, which both implementations do alike.
    simulation_seconds = [0.0]
    def timed(function):
        def call(*args):
            begin = time.perf_counter()
            result = function(*args)
            simulation_seconds[0] += time.perf_counter() - begin
            return result
        return call
    pipeline = {name: getattr(mujoco, name) for name in dir(mujoco)
                if name.startswith(("mj_step", "mj_forward", "mj_fwd"))}
    for name, function in pipeline.items():
        setattr(mujoco, name, timed(function))
    start = time.perf_counter()
    for _ in range(resets):
        env.reset()
    reset_seconds = (time.perf_counter() - start) / resets
    for name, function in pipeline.items():
        setattr(mujoco, name, function)
    model, data = env.physics.model.ptr, env.physics.data.ptr
    n_sub_steps = int(round(env.control_timestep() / model.opt.timestep))
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    initial = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, initial, kind)
    controls = []
    step_seconds = 0.0
    for action in actions:
        start = time.perf_counter()
        timestep = env.step(action)
        step_seconds += time.perf_counter() - start
        controls.append(data.ctrl.copy())
        if timestep.last():
            break
    # The raw physics of the same steps: the same start state and controls, mj_step alone.
    mujoco.mj_setState(model, data, initial, kind)
    start = time.perf_counter()
    for control in controls:
        data.ctrl[:] = control
        mujoco.mj_step(model, data, n_sub_steps)
    raw_seconds = time.perf_counter() - start
    env.reset()
    print(json.dumps({"reset": reset_seconds, "step": step_seconds / len(controls),
                      "raw": raw_seconds / len(controls),
                      "simulation": simulation_seconds[0] / resets}), flush=True)
"""


SUITE_TASKS = (
    "cartpole-swingup",
    "walker-walk",
    "cheetah-run",
    "humanoid-run",
    "quadruped-run",
)

# The suite's worker: answers "DOMAIN-TASK" lines with one trial's timings (seconds): a
# suite.load, a raw compile of the same XML, and per step: env.step, the physics.step inside
# it, and the raw mj_step calls of the same steps.
_SUITE_WORKER = r"""
import json, sys, time
import mujoco
import numpy as np
if sys.argv[1] == "ours":
    from composer import dm_control_compat
    dm_control_compat.install()
from dm_control import mujoco as dm_mujoco, suite
steps = int(sys.argv[2])
# What each domain compiles: suite.load reaches Physics.from_xml_string with it.
compiled = {}
_from_xml_string = dm_mujoco.Physics.from_xml_string.__func__
def _capturing(cls, xml_string, assets=None):
    compiled["xml"], compiled["assets"] = xml_string, assets
    return _from_xml_string(cls, xml_string, assets)
dm_mujoco.Physics.from_xml_string = classmethod(_capturing)
print("READY", flush=True)
for line in sys.stdin:
    domain, task = line.strip().split("-", 1)
    start = time.perf_counter()
    env = suite.load(domain, task, task_kwargs={"random": 0})
    load_seconds = time.perf_counter() - start
    start = time.perf_counter()
    mujoco.MjModel.from_xml_string(compiled["xml"], compiled["assets"])
    compile_seconds = time.perf_counter() - start
    env.reset()
    physics = env.physics
    spec = env.action_spec()
    rng = np.random.RandomState(0)
    low = np.where(np.abs(spec.minimum) < 1e9, spec.minimum, -1.0)
    high = np.where(np.abs(spec.maximum) < 1e9, spec.maximum, 1.0)
    actions = rng.uniform(low, high, size=(steps,) + spec.shape)
    model, data = physics.model.ptr, physics.data.ptr
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    initial = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, initial, kind)
    physics_seconds = [0.0]
    inner_step = physics.step
    def timed_step(*args, **kwargs):
        begin = time.perf_counter()
        inner_step(*args, **kwargs)
        physics_seconds[0] += time.perf_counter() - begin
    physics.step = timed_step
    controls, substeps = [], []
    step_seconds = 0.0
    for action in actions:
        before = data.time
        start = time.perf_counter()
        timestep = env.step(action)
        step_seconds += time.perf_counter() - start
        controls.append(data.ctrl.copy())
        substeps.append(int(round((data.time - before) / model.opt.timestep)))
        if timestep.last():
            break
    del physics.step
    mujoco.mj_setState(model, data, initial, kind)
    start = time.perf_counter()
    for control, n in zip(controls, substeps):
        data.ctrl[:] = control
        mujoco.mj_step(model, data, n)
    raw_seconds = time.perf_counter() - start
    n = len(controls)
    print(json.dumps({"load": load_seconds, "compile": compile_seconds,
                      "step": step_seconds / n, "physics": physics_seconds[0] / n,
                      "raw": raw_seconds / n}), flush=True)
"""


class Timing(NamedTuple):
    """Median times of one implementation on one task, in milliseconds: a reset, an
    `env.step`, the raw `mj_step` calls of the same step on the same state, and the time a
    reset spends in MuJoCo's simulation pipeline."""

    reset_ms: float
    step_ms: float
    raw_ms: float
    simulation_ms: float


class Worker:
    """A long-lived process in one venv that runs trials on request."""

    def __init__(self, python: Path, flavour: str, script: str, *script_args: int):
        self._process = subprocess.Popen(
            [str(python), "-c", script, flavour, *map(str, script_args)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=CACHE,
            env=dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl")),
        )
        if self._process.stdout.readline().strip() != "READY":
            raise RuntimeError(f"the {flavour} worker did not start (see its stderr above)")

    def trial(self, task: str) -> dict:
        self._process.stdin.write(task + "\n")
        self._process.stdin.flush()
        line = self._process.stdout.readline()
        if not line:
            raise RuntimeError(f"the worker died on {task} (see its stderr above)")
        return json.loads(line)

    def close(self) -> None:
        self._process.stdin.close()
        self._process.wait(timeout=60)


def _default_tasks(python: Path) -> list[str]:
    listing = subprocess.run(
        [str(python), "-c", "from dm_control import manipulation; print(*manipulation.ALL)"],
        capture_output=True,
        text=True,
        check=True,
        cwd=CACHE,
    )
    return sorted(name for name in listing.stdout.split() if name.endswith("_features"))


def _run_trials(workers: dict, tasks: list[str], trials: int) -> dict:
    """(flavour, task) -> the trials' results, the two implementations alternating."""
    samples = {(flavour, task): [] for flavour in workers for task in tasks}
    for trial in range(trials):
        for task in tasks:
            # Alternate which implementation goes first, so drift hits both alike.
            order = list(workers) if trial % 2 == 0 else list(reversed(workers))
            for flavour in order:
                samples[flavour, task].append(workers[flavour].trial(task))
    for worker in workers.values():
        worker.close()
    return samples


def _suite_section(pythons: dict, trials: int, steps: int) -> None:
    workers = {
        flavour: Worker(python, flavour, _SUITE_WORKER, steps)
        for flavour, python in pythons.items()
    }
    samples = _run_trials(workers, list(SUITE_TASKS), trials)

    def median(flavour: str, task: str, key: str) -> float:
        return statistics.median(r[key] for r in samples[flavour, task])

    print(
        f"\ndm_control 1.0.50 Control Suite (suite.load): ours = dm_control.mujoco served by "
        f"this project + mujoco (project venv), dm_control = dm_control + {DM_CONTROL_MUJOCO}; "
        f"medians of {trials} trials, {steps} steps each"
    )
    print(
        f"{'task':<18} {'step/raw':>8} {'dm':>6}  {'engine/raw':>10} {'dm':>6}  "
        f"{'step us':>7} {'dm':>6}  {'load/compile':>12} {'dm':>6}  {'load ms':>7} {'dm':>6}"
    )
    for task in SUITE_TASKS:
        row = {}
        for flavour in ("ours", "dm_control"):
            raw = median(flavour, task, "raw")
            row[flavour] = (
                median(flavour, task, "step") / raw,
                median(flavour, task, "physics") / raw,
                1e6 * median(flavour, task, "step"),
                median(flavour, task, "load") / median(flavour, task, "compile"),
                1e3 * median(flavour, task, "load"),
            )
        ours, theirs = row["ours"], row["dm_control"]
        print(
            f"{task:<18} {ours[0]:7.2f}x {theirs[0]:5.2f}x  {ours[1]:9.2f}x {theirs[1]:5.2f}x  "
            f"{ours[2]:7.1f} {theirs[2]:6.1f}  {ours[3]:11.2f}x {theirs[3]:5.2f}x  "
            f"{ours[4]:7.1f} {theirs[4]:6.1f}"
        )
    print(
        "step/raw: env.step over raw mj_step of the same steps in the same venv; engine/raw: "
        "the physics.step calls inside those env.steps over the same raw steps; load/compile: "
        "suite.load over one MjModel.from_xml_string of the same XML and assets "
        "(targets: step/raw <= dm_control's, load/compile <= 1.10)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=3)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--resets", type=int, default=5)
    parser.add_argument("--tasks", nargs="*")
    parser.add_argument(
        "--sections",
        nargs="+",
        choices=("manipulation", "suite"),
        default=["manipulation", "suite"],
    )
    args = parser.parse_args()
    CACHE.mkdir(parents=True, exist_ok=True)
    dm_python = scratch_venv.ensure_venv(
        CACHE / "dm_control-venv", [DM_CONTROL, DM_CONTROL_MUJOCO], project=False
    )
    our_python = scratch_venv.ensure_venv(CACHE / "ours-venv", [DM_CONTROL])
    if "manipulation" in args.sections:
        _manipulation_section(our_python, dm_python, args)
    if "suite" in args.sections:
        _suite_section({"ours": our_python, "dm_control": dm_python}, args.trials, args.steps)


def _manipulation_section(our_python: Path, dm_python: Path, args: argparse.Namespace) -> None:
    tasks = args.tasks or _default_tasks(dm_python)
    workers = {
        "ours": Worker(our_python, "ours", _WORKER, args.resets, args.steps),
        "dm_control": Worker(dm_python, "dm_control", _WORKER, args.resets, args.steps),
    }
    samples = _run_trials(workers, tasks, args.trials)

    def median(flavour: str, task: str) -> Timing:
        runs = samples[flavour, task]
        keys = ("reset", "step", "raw", "simulation")
        return Timing(*(1e3 * statistics.median(r[key] for r in runs) for key in keys))

    print(
        f"dm_control 1.0.50 manipulation tasks; ours = this project + mujoco (project venv), "
        f"dm_control = dm_control + {DM_CONTROL_MUJOCO}; medians of {args.trials} trials, "
        f"{args.resets} resets and {args.steps} steps each"
    )
    header = (
        f"{'task':<42} {'reset ms':>8} {'dm':>7} {'ratio':>6} {'sim ms':>7} {'dm':>6} "
        f"{'floor':>6}  {'step ms':>7} {'dm':>7} {'ratio':>6}  {'step/raw':>8} "
        f"{'dm step/raw':>11}"
    )
    print(header)
    reset_ratios, step_ratios = [], []
    for task in tasks:
        ours, theirs = median("ours", task), median("dm_control", task)
        reset_ratios.append(ours.reset_ms / theirs.reset_ms)
        step_ratios.append(ours.step_ms / theirs.step_ms)
        floor = ours.simulation_ms / theirs.reset_ms
        print(
            f"{task:<42} {ours.reset_ms:8.2f} {theirs.reset_ms:7.2f} {reset_ratios[-1]:5.2f}x "
            f"{ours.simulation_ms:7.2f} {theirs.simulation_ms:6.2f} {floor:5.2f}x  "
            f"{ours.step_ms:7.3f} {theirs.step_ms:7.3f} {step_ratios[-1]:5.2f}x  "
            f"{ours.step_ms / ours.raw_ms:7.2f}x {theirs.step_ms / theirs.raw_ms:10.2f}x"
        )
    print(
        f"{'max (target: reset <= 0.20x)':<60} {max(reset_ratios):5.2f}x  "
        f"{'':36} {max(step_ratios):5.2f}x"
    )
    print(
        "sim ms: of a reset, the time inside MuJoCo's simulation pipeline (mj_step*, "
        "mj_forward*, mj_fwd*: settling and placing props, the reset's forward); floor: ours "
        "over dm_control's whole reset, the ratio a reset would have if nothing but that "
        "simulation cost anything. step/raw: env.step over the raw mj_step calls of the same "
        "steps from the same state in the same venv (mujoco 4 for ours, 3.17 for dm_control)"
    )


if __name__ == "__main__":
    main()
