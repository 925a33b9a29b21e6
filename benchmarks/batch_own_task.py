"""The push-puck task of docs/batch_own_task.md: one CPU environment against its batch on
Warp's CPU device, in environment steps (control steps of one world) per second.

The task is the docs' own: the blocks of docs/own_task.md up to "Run it" and the blocks of
docs/batch_own_task.md that define `make_task` and `BatchPushPuck`, run here as
written. Random actions, a 4 s time limit (episodes restart), one producer thread.

Usage: python benchmarks/batch_own_task.py [--num-envs 16,64] [--steps 40]
[--cpu-steps 400]. Prints a table with the machine's load average; the CPU environment is
the baseline, measured in the same run.
"""

import argparse
import os
import pathlib
import re
import time

import numpy as np

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"
_FENCE = re.compile(r"^```(?P<info>[^\n`]*)\n(?P<code>.*?)^```\s*$", re.M | re.S)
_DEFINES = ("def make_task", "class BatchPushPuck")


def _task_namespace() -> dict:
    """The docs' task classes and `make_task`, defined by running their blocks."""
    own_task = (DOCS / "own_task.md").read_text(encoding="utf-8").split("## Run it")[0]
    page = (DOCS / "batch_own_task.md").read_text(encoding="utf-8")
    blocks = [m["code"] for m in _FENCE.finditer(own_task) if m["info"].strip() == "python"]
    blocks += [
        m["code"]
        for m in _FENCE.finditer(page)
        if m["info"].strip() == "{.python .no-run}" and any(d in m["code"] for d in _DEFINES)
    ]
    namespace = {"__name__": "__push_puck__"}
    exec("from composer import batch", namespace)
    for code in blocks:
        exec(code, namespace)
    return namespace


def _cpu_rate(make_task, steps: int) -> float:
    import composer

    env = composer.Environment(make_task(), time_limit=4.0, random_state=0)
    spec = env.action_spec()
    actions = np.random.default_rng(0).uniform(spec.minimum, spec.maximum, (steps, 2))
    env.reset()
    start = time.perf_counter()
    for action in actions:
        env.step(action)
    return steps / (time.perf_counter() - start)


def _batch_rate(make_task, num_envs: int, steps: int) -> float:
    from composer import batch

    env = batch.BatchEnvironment(
        make_task(), num_envs, device="cpu", time_limit=4.0, random_state=0
    )
    actions = np.random.default_rng(0).uniform(-1, 1, (steps + 5, num_envs, 2))
    env.reset()
    for action in actions[:5]:  # kernels loaded, slots refilled once
        env.step(action)
    start = time.perf_counter()
    for action in actions[5:]:
        env.step(action)
    rate = steps * num_envs / (time.perf_counter() - start)
    env.close()
    return rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--num-envs", default="16,64")
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--cpu-steps", type=int, default=400)
    args = parser.parse_args()
    make_task = _task_namespace()["make_task"]
    cpu = _cpu_rate(make_task, args.cpu_steps)
    rows = [("composer.Environment (baseline)", cpu)]
    for n in (int(v) for v in args.num_envs.split(",")):
        rows.append(
            (f"BatchEnvironment, {n} worlds, Warp CPU", _batch_rate(make_task, n, args.steps))
        )
    print(f"load average {os.getloadavg()[0]:.1f}, {os.cpu_count()} cores")
    print("| environment | env-steps/s | / baseline |")
    print("|---|---:|---:|")
    for name, rate in rows:
        print(f"| {name} | {rate:,.0f} | {rate / cpu:.3f} |")


if __name__ == "__main__":
    main()
