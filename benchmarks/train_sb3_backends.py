"""Wall-clock to the reach's training goal: SAC (SB3) on the threaded env and on the CPU batch.

Runs `examples/train_sb3.py` on reach_site_features once per backend, one after the other
in the same invocation (same seed, budget, number of training envs and evaluation
episodes), each in a process of its own, and reads each run's learning curve. The goal is
the one docs/concepts/training.md reports: a mean evaluation return of at least 200 and a
mean final distance under 6 cm over the 5 seeded evaluation episodes. The table gives, per
backend, the seconds to the first evaluation that meets it (or "not met"), the env steps
and SAC updates per second over the run, and the best evaluation return; then the batch's
figures as ratios of the threaded env's.

SAC's updates, not the simulation, set the pace of this example on a CPU (about 20 ms an
update against 0.25 ms a step), so the two backends are expected to be close; what the
batch changes is the cost of the steps between updates.

Usage: python benchmarks/train_sb3_backends.py [--minutes 6] [--num-envs 4] [--seed 0]
"""

import argparse
import csv
import os
import pathlib
import subprocess
import sys
import tempfile

_ROOT = pathlib.Path(__file__).resolve().parent.parent
GOAL_RETURN, GOAL_DISTANCE_M = 200.0, 0.06
BACKENDS = ("threads", "batch")


def _run(backend: str, args: argparse.Namespace, out: pathlib.Path) -> list[dict[str, float]]:
    command = [
        sys.executable,
        str(_ROOT / "examples" / "train_sb3.py"),
        "--backend",
        backend,
        "--minutes",
        str(args.minutes),
        "--num-envs",
        str(args.num_envs),
        "--seed",
        str(args.seed),
        "--out",
        str(out),
    ]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    with open(out / "learning_curve.csv", newline="") as file:
        return [{key: float(value) for key, value in row.items()} for row in csv.DictReader(file)]


def _goal_seconds(curve: list[dict[str, float]]) -> float | None:
    for point in curve:
        if point["eval_return"] >= GOAL_RETURN and point["eval_distance"] < GOAL_DISTANCE_M:
            return point["seconds"]
    return None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--minutes", type=float, default=6.0)
    parser.add_argument("--num-envs", type=int, default=4)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(
        f"cores: {len(os.sched_getaffinity(0))}, load average (1 min): "
        f"{os.getloadavg()[0]:.2f}; SAC on reach_site_features, {args.num_envs} training "
        f"envs, {args.minutes:g} min each"
    )
    rows = {}
    with tempfile.TemporaryDirectory() as scratch:
        for backend in BACKENDS:
            curve = _run(backend, args, pathlib.Path(scratch) / backend)
            last = curve[-1]
            rows[backend] = (
                _goal_seconds(curve),
                last["env_steps"] / last["seconds"],
                last["updates"] / last["seconds"],
                max(point["eval_return"] for point in curve),
            )
    print(f"\n{'backend':>8} {'s to goal':>10} {'env steps/s':>12} {'updates/s':>10} {'best':>6}")
    for backend, (goal, steps, updates, best) in rows.items():
        shown = "not met" if goal is None else f"{goal:.0f}"
        print(f"{backend:>8} {shown:>10} {steps:>12,.0f} {updates:>10.1f} {best:>6.1f}")
    (goal_t, steps_t, updates_t, _), (goal_b, steps_b, updates_b, _) = rows.values()
    goal_ratio = "n/a" if goal_t is None or goal_b is None else f"{goal_b / goal_t:.2f}x"
    print(
        f"\nbatch / threads: time to goal {goal_ratio}, env steps/s {steps_b / steps_t:.2f}x, "
        f"updates/s {updates_b / updates_t:.2f}x"
    )


if __name__ == "__main__":
    main()
