"""Runs the benchmarks and saves their tables for the docs in docs/data/benchmark_results.json.

Usage: python -m tools.docs.benchmark_results [--quick] [--note "how loaded the machine was"]

Each benchmark's printed table is parsed into rows of (measured time, baseline time, ratio),
where the baseline is the raw `mujoco` work it is compared with, measured in the same run.
The file also names the machine (CPU model, cores, OS, Python and MuJoCo versions) and the
commit. The docs build draws its performance charts from this file, so re-run this script
after a change that affects speed and commit the result.
"""

import argparse
import dataclasses
import datetime
import json
import os
import pathlib
import platform
import re
import subprocess
import sys

import mujoco

from tools import ROOT
from tools.docs import RESULTS

_MANIPULATION_TASKS = (
    "reach_site_features",
    "lift_brick_features",
    "stack_3_bricks_features",
    "reassemble_5_bricks_random_order_features",
)


@dataclasses.dataclass(frozen=True)
class Row:
    """One measurement: its time and its baseline's time (both in `unit`) and their ratio."""

    label: str
    time: float
    baseline: float
    unit: str
    ratio: float
    target: str = ""


@dataclasses.dataclass(frozen=True)
class Benchmark:
    """A benchmark script, how to run it, and what its ratio compares with."""

    name: str
    title: str
    baseline: str
    arguments: tuple[str, ...]
    quick_arguments: tuple[str, ...]


BENCHMARKS = (
    Benchmark(
        "step_overhead",
        "Environment step and reset",
        "raw `mujoco.mj_step` calls on the same model and state (step rows) and one "
        "`mujoco.MjModel.from_xml_string` of the scene (reset rows)",
        ("--repeats", "60"),
        ("--repeats", "10"),
    ),
    Benchmark(
        "observation_updater",
        "Observation updater",
        "20 raw `mujoco.mj_step` calls (one control step of the physics being observed)",
        (),
        (),
    ),
    Benchmark(
        "mjcf_compile",
        "MJCF layer: writing XML and compiling",
        "`mujoco.MjModel.from_xml_string` of the same XML and assets (bind row: a direct "
        "`data.geom_xpos[ids]` read)",
        ("--repeats", "40"),
        ("--repeats", "10"),
    ),
    Benchmark(
        "manipulation",
        "Manipulation tasks: env.step",
        "`mujoco.mj_step(model, data, 20)` on the same model, state and controls",
        (*_MANIPULATION_TASKS, "--trials", "10"),
        (*_MANIPULATION_TASKS[:2], "--trials", "3"),
    ),
)

_NUMBER = r"[-+]?\d+(?:\.\d+)?"


def parse_step_overhead(output: str) -> list[Row]:
    """Rows 'label  time(us)  baseline(us)  ratio  [target]'."""
    pattern = re.compile(
        rf"^(?P<label>\S.*?)\s+(?P<time>{_NUMBER})\s+(?P<base>{_NUMBER})\s+(?P<ratio>{_NUMBER})"
        r"\s*(?P<target>.*)$"
    )
    return [
        Row(m["label"], float(m["time"]), float(m["base"]), "us", float(m["ratio"]), m["target"])
        for m in map(pattern.match, output.splitlines())
        if m
    ]


def parse_observation_updater(output: str) -> list[Row]:
    """Rows 'options  mode  us/step  ratio' against the 'baseline: ... = X us' line."""
    baseline = re.search(rf"baseline: .*?= ({_NUMBER}) us", output)
    pattern = re.compile(
        rf"^(?P<label>\S.*?)\s{{2,}}(?P<mode>\S.*?)\s+(?P<time>{_NUMBER})\s+(?P<ratio>{_NUMBER})$"
    )
    return [
        Row(
            f"{m['label']} ({m['mode']})",
            float(m["time"]),
            float(baseline[1]),
            "us",
            float(m["ratio"]),
        )
        for m in map(pattern.match, output.splitlines())
        if m and baseline
    ]


def parse_mjcf_compile(output: str) -> list[Row]:
    """Rows 'label  time unit  ratio x  best x  target x  result' against the baselines line."""
    baselines = re.search(
        rf"compile ({_NUMBER}) ms.*?read ({_NUMBER}) us", output, flags=re.IGNORECASE
    )
    pattern = re.compile(
        rf"^(?P<label>\S.*?)\s+(?P<time>{_NUMBER}) (?P<unit>ms|us)\s+(?P<ratio>{_NUMBER})x\s+"
        rf"{_NUMBER}x\s+(?P<target>{_NUMBER})x\s+\w+$"
    )
    rows = []
    for m in map(pattern.match, output.splitlines()):
        if m and baselines:
            baseline = float(baselines[1]) if m["unit"] == "ms" else float(baselines[2])
            rows.append(
                Row(
                    m["label"],
                    float(m["time"]),
                    baseline,
                    m["unit"],
                    float(m["ratio"]),
                    f"<= {m['target']}",
                )
            )
    return rows


def parse_manipulation(output: str) -> list[Row]:
    """Rows 'task  reset ms  step ms  raw ms  overhead  [render]'."""
    pattern = re.compile(
        rf"^(?P<label>[a-z0-9_]+)\s+{_NUMBER}\s+(?P<time>{_NUMBER})\s+(?P<base>{_NUMBER})\s+"
        rf"(?P<ratio>{_NUMBER})"
    )
    return [
        Row(m["label"], float(m["time"]), float(m["base"]), "ms", float(m["ratio"]), "<= 1.1")
        for m in map(pattern.match, output.splitlines())
        if m
    ]


PARSERS = {
    "step_overhead": parse_step_overhead,
    "observation_updater": parse_observation_updater,
    "mjcf_compile": parse_mjcf_compile,
    "manipulation": parse_manipulation,
}


def machine() -> dict:
    """The machine the benchmarks ran on, in words and versions."""
    cpu = platform.processor() or platform.machine()
    cpuinfo = pathlib.Path("/proc/cpuinfo")
    if cpuinfo.exists():
        found = re.search(r"model name\s*:\s*(.+)", cpuinfo.read_text(encoding="utf-8"))
        cpu = found[1].strip() if found else cpu
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "os": platform.platform(terse=True),
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
    }


def _commit() -> str:
    result = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
    )
    return result.stdout.strip()


def run(benchmark: Benchmark, quick: bool) -> dict:
    """Runs one benchmark script and returns its command, raw output and parsed rows."""
    arguments = benchmark.quick_arguments if quick else benchmark.arguments
    command = ["python", f"benchmarks/{benchmark.name}.py", *arguments]
    result = subprocess.run(
        [sys.executable, *command[1:]],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
    )
    rows = PARSERS[benchmark.name](result.stdout)
    if not rows:
        raise RuntimeError(f"{benchmark.name}: no table rows found in its output:\n{result.stdout}")
    return {
        "name": benchmark.name,
        "title": benchmark.title,
        "baseline": benchmark.baseline,
        "command": " ".join(command),
        "rows": [dataclasses.asdict(row) for row in rows],
        "output": result.stdout,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats (for a smoke test)")
    parser.add_argument("--out", type=pathlib.Path, default=RESULTS)
    parser.add_argument("--note", default="", help="how loaded the machine was, in words")
    args = parser.parse_args()
    results = {
        "measured": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": _commit(),
        "machine": {**machine(), "note": args.note},
        "benchmarks": [],
    }
    for benchmark in BENCHMARKS:
        print(f"running {benchmark.name} ...", flush=True)
        results["benchmarks"].append(run(benchmark, args.quick))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
