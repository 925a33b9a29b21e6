"""Checks that a seed gives dm_control's episode: the project against dm_control 1.0.50.

Usage: `python -m tools.dm_control_seeds [--seeds 5] [--steps 10] [--only ENV,...]
[--mujoco4] [--install-only]`

Runs `tools/seed_episode_runner.py` twice in one scratch venv under `.cache/dm_control_seeds`,
with dm_control 1.0.50 on mujoco 3.17 and this project installed beside it:
`reference` runs dm_control as it is (the project is installed there but not imported), and
`project` runs the same environments through this project's redirect (dm_control's
manipulation suite and locomotion examples on this project's composer, mjcf and engine).
`--install-only` builds that venv (and, with `--mujoco4`, the conformance harness's) and
exits: CI builds it in the background while other checks run.
For every environment and seed it compares:

- the draws from the environment's random state, in order (method and generator state
  after each draw), during construction and `reset()` and during the steps;
- the physics state after `reset()`: qpos within 1e-8, qvel and act within 1e-8;
- the first observation and `--steps` steps of observations and rewards under fixed
  actions, within 1e-6.

Both sides render with the same harness setting, applied right after each environment is
made: a 512-pixel shadow map without multisampling (`seed_episode_runner.RENDER_QUALITY`,
through the MJCF model, so dm_control's reset recompiles with it and the project's updates
its model and render contexts in place); the images are compared at the same tolerance.

It prints one row per environment, with its first differing quantity, and exits 1 when
any differs. With `--mujoco4`, it also runs the project side on mujoco 4 (the venv of
`tools.dm_control_conformance`, whose dm_control is the same release) and reports the
largest differences from the reference on 3.17, without failing: there only MuJoCo's
numerics may differ, so the draws must still be the same (CI leaves this report out: it
cannot fail). The sides run at the same time, each in `SHARDS` processes that share its
environments.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

from tools import ROOT, dm_control_conformance, scratch_venv

if TYPE_CHECKING:  # NumPy is imported where it is used: `--install-only` runs without it.
    import numpy as np

CACHE = scratch_venv.CACHE / "dm_control_seeds"
DM_CONTROL_VERSION = dm_control_conformance.DM_CONTROL_VERSION
DM_CONTROL = f"dm-control=={DM_CONTROL_VERSION}"
#: dm_control 1.0.50's own MuJoCo release: the one both sides are compared on.
MUJOCO = "mujoco==3.17.0"
RUNNER = ROOT / "tools" / "seed_episode_runner.py"
#: Runners per side, each on a share of the environments (4 processes in all on CI's 2 cores).
SHARDS = 2

QPOS_TOLERANCE = 1e-8
OBSERVATION_TOLERANCE = 1e-6


class Episodes(NamedTuple):
    """What one side recorded: arrays by `ENV/SEED/QUANTITY`, draws, errors, MuJoCo."""

    arrays: dict[str, np.ndarray]
    draws: dict[str, list]
    errors: dict[str, str]
    mujoco: str


class Comparison(NamedTuple):
    """One environment's result: its first difference (None when identical), whether every
    seed drew the same numbers in the same order, and the largest differences over all
    seeds (`qpos`: of the state after reset, qpos, qvel and act)."""

    name: str
    first_difference: str | None
    same_draws: bool
    qpos: float
    observation: float
    reward: float


class Side(NamedTuple):
    """One side's runners: a process and its output file per shard."""

    runners: list[tuple[subprocess.Popen, Path]]


def start_side(
    python: Path, side: str, seeds: int, steps: int, only: str, shards: int = SHARDS
) -> Side:
    """Starts `shards` runners of `side` in `python`'s venv, each on every `shards`-th
    environment, so that the machine's cores share the work whatever each environment costs."""
    workdir = CACHE / "workdir"
    workdir.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    venv = python.parent.parent.name
    runners = []
    for shard in range(shards):
        out = CACHE / f"{venv}-{side}-{shard}of{shards}.npz"
        process = subprocess.Popen(
            [str(python), str(RUNNER), side, str(out), str(seeds), str(steps), only]
            + [f"{shard}/{shards}"],
            cwd=workdir,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        runners.append((process, out))
    return Side(runners)


def finish_side(side: Side) -> Episodes:
    """Waits for a side's runners and joins what they recorded."""
    import numpy as np

    arrays: dict[str, np.ndarray] = {}
    draws: dict[str, list] = {}
    errors: dict[str, str] = {}
    mujoco = ""
    for process, out in side.runners:
        _, stderr = process.communicate()
        if process.returncode != 0:
            raise RuntimeError(f"the episode runner failed ({out.name}):\n{stderr[-3000:]}")
        with np.load(out) as saved:
            meta = json.loads(str(saved["__meta__"]))
            arrays.update((key, saved[key]) for key in saved.files if key != "__meta__")
        draws.update(meta["draws"])
        errors.update(meta["errors"])
        mujoco = meta["mujoco"]
    return Episodes(arrays, draws, errors, mujoco)


def _first_draw_difference(reference: list, project: list) -> str | None:
    for index, (want, got) in enumerate(zip(reference, project)):
        if want[:2] != got[:2]:
            return (
                f"draw {index}: dm_control {want[0]} from {want[2]}, project {got[0]} from {got[2]}"
            )
    if len(reference) != len(project):
        return f"{len(reference)} draws on dm_control, {len(project)} here"
    return None


def _largest(reference: Episodes, project: Episodes, prefix: str, suffix: str) -> tuple:
    """The largest |difference| over the keys `prefix...suffix`, and the key it is in."""
    import numpy as np

    worst, worst_key = 0.0, None
    for key, want in reference.arrays.items():
        if not (key.startswith(prefix) and suffix in key[len(prefix) :]):
            continue
        got = project.arrays.get(key)
        if got is None or got.shape != want.shape:
            return np.inf, key
        gap = float(np.max(np.abs(got - want), initial=0.0))
        if not np.isfinite(gap) and np.array_equal(got, want, equal_nan=True):
            gap = 0.0
        if gap > worst or worst_key is None:
            worst, worst_key = gap, key
    return worst, worst_key


def compare(name: str, seeds: int, reference: Episodes, project: Episodes) -> Comparison:
    """Compares one environment over all seeds; the first difference is in seed order."""
    first = None
    same_draws = True
    largest = {"qpos": 0.0, "observation": 0.0, "reward": 0.0}
    for seed in range(seeds):
        prefix = f"{name}/{seed}/"
        for side, episodes in (("dm_control", reference), ("project", project)):
            error = episodes.errors.get(f"{name}/{seed}")
            if error and first is None:
                first = f"seed {seed}: {side} failed: {error}"
        if f"{name}/{seed}" in reference.errors or f"{name}/{seed}" in project.errors:
            same_draws = False
            continue
        for phase in ("reset", "steps"):
            difference = _first_draw_difference(
                reference.draws[prefix + phase], project.draws[prefix + phase]
            )
            same_draws = same_draws and difference is None
            if difference and first is None:
                first = f"seed {seed}, {phase}: {difference}"
        checks = (
            ("qpos", "qpos", QPOS_TOLERANCE),
            ("qpos", "qvel", QPOS_TOLERANCE),
            ("qpos", "act", QPOS_TOLERANCE),
            ("observation", "observation/", OBSERVATION_TOLERANCE),
            ("reward", "reward", OBSERVATION_TOLERANCE),
        )
        for column, suffix, tolerance in checks:
            gap, key = _largest(reference, project, prefix, suffix)
            largest[column] = max(largest[column], gap)
            if gap > tolerance and first is None:
                quantity = key[len(prefix) :] if key else suffix
                first = f"seed {seed}: {quantity} differs by {gap:.3g} (tolerance {tolerance:g})"
    return Comparison(
        name, first, same_draws, largest["qpos"], largest["observation"], largest["reward"]
    )


def _names(episodes: Episodes) -> list[str]:
    keys = [*episodes.draws, *episodes.errors]
    return list(dict.fromkeys(key.split("/", 1)[0] for key in keys))


def print_table(title: str, rows: list[Comparison]) -> int:
    """Prints the comparison rows; returns how many environments differ."""
    width = max(len(row.name) for row in rows) + 2
    print(f"\n{title}")
    header = "draws  max |dstate|  max |dobs|  max |drew|"
    print(f"{'environment':<{width}} {header}  first difference")
    for row in rows:
        print(
            f"{row.name:<{width}} {'same' if row.same_draws else 'DIFF':>5}  {row.qpos:12.3g}  "
            f"{row.observation:10.3g}  {row.reward:10.3g}  {row.first_difference or 'identical'}"
        )
    differing = sum(row.first_difference is not None for row in rows)
    same_draws = sum(row.same_draws for row in rows)
    print(
        f"{len(rows) - differing} of {len(rows)} environments identical; "
        f"{same_draws} of {len(rows)} drew the same numbers in the same order"
    )
    return differing


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--only", default="", help="comma-separated environment names")
    parser.add_argument(
        "--mujoco4",
        action="store_true",
        help="also report the project's differences on mujoco 4 (never fails)",
    )
    parser.add_argument(
        "--install-only", action="store_true", help="build the scratch venv(s) and exit"
    )
    args = parser.parse_args()
    CACHE.mkdir(parents=True, exist_ok=True)
    python = scratch_venv.ensure_venv(CACHE / "venv", [DM_CONTROL, MUJOCO])
    newest_python = dm_control_conformance.ensure_conformance_venv() if args.mujoco4 else None
    if args.install_only:
        return 0
    # The sides run at the same time, each in processes of its own.
    sides = [
        start_side(python, "reference", args.seeds, args.steps, args.only),
        start_side(python, "project", args.seeds, args.steps, args.only),
    ]
    if newest_python is not None:
        sides.append(start_side(newest_python, "project", args.seeds, args.steps, args.only))
    reference, project, *newest = [finish_side(side) for side in sides]
    rows = [compare(name, args.seeds, reference, project) for name in _names(reference)]
    title = (
        f"dm_control {DM_CONTROL_VERSION} on mujoco {reference.mujoco} against the project "
        f"on mujoco {project.mujoco} (seeds 0-{args.seeds - 1}, {args.steps} steps)"
    )
    status = int(print_table(title, rows) > 0)
    for episodes in newest:
        print_table(
            f"dm_control on mujoco {reference.mujoco} against the project on mujoco "
            f"{episodes.mujoco} (reported, not checked: MuJoCo differs)",
            [compare(name, args.seeds, reference, episodes) for name in _names(reference)],
        )
    return status


if __name__ == "__main__":
    sys.exit(main())
