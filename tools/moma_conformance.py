"""DeepMind's MoMa (`dm-robotics-moma` 0.10.0) tests, run on this project through the
dm_control redirect; part of `python -m tools.dm_control_conformance` (alone:
`--moma-only`).

MoMa and its dm_robotics siblings are installed into the conformance harness's scratch venv
with `pip --no-deps` (they pin dm_control 1.0.31 and mujoco 3.3.3; the venv keeps dm_control
1.0.50 and this project's MuJoCo), their test files are copied out of the install (nothing
of MoMa is kept in the repository), and each file runs in a pytest process of its own, as
MoMa's own `run_tests.py` does (its spec validation switches itself off after a while,
process-wide). Prints per-file counts, the failures and the totals; fails when a test that
passes on dm_control 1.0.50 + mujoco 3.17 fails here.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ElementTree
from concurrent import futures
from pathlib import Path
from typing import NamedTuple

MOMA_VERSION = "0.10.0"
#: MoMa and the dm_robotics packages it imports, installed with `pip --no-deps`.
MOMA_WHEELS = [
    f"dm-robotics-{name}=={MOMA_VERSION}"
    for name in ("moma", "transformations", "geometry", "agentflow", "controllers")
]
#: What those packages import beyond dm_control's own requirements (cv2, attr, pydot).
MOMA_DEPENDENCIES = ["opencv-python-headless", "attrs", "pydot", "typing-extensions"]
#: The Pythons `dm-robotics-controllers` 0.10.0 (a compiled extension) has wheels for.
MOMA_PYTHONS = ((3, 10), (3, 11), (3, 12))

_CRASHES_IN_CONTROLLERS = (
    "segfaults on real dm_control 1.0.50 + mujoco 3.17 too: MoMa's Cartesian velocity mapper "
    "(behind its IK solver and 6-D Cartesian effector) is dm_robotics.controllers, a compiled "
    "extension with its own MuJoCo 3.3.3, which reads another release's MjModel with 3.3.3's "
    "layout"
)

#: MoMa test files not run, with why: every test in them crashes the interpreter. Measured
#: with dm-control==1.0.50 mujoco==3.17.0 and the MoMa wheels in a venv of their own, each
#: of the 24 + 6 + 1 + 1 = 32 tests run alone: all SIGSEGV when the controllers' mapper is
#: made (`ik_solver._create_qp_mapper`, `Cartesian6dVelocityEffector.after_compile`); they
#: crash the same way here.
EXCLUDED_FILES = {
    "effectors/cartesian_6d_velocity_effector_test.py": _CRASHES_IN_CONTROLLERS,
    "utils/ik_solver_test.py": _CRASHES_IN_CONTROLLERS,
    "sensors/robotiq_gripper_sensor_integration_test.py": _CRASHES_IN_CONTROLLERS,
    "tasks/example_task/example_task_test.py": _CRASHES_IN_CONTROLLERS,
}

#: How many of the other files' tests pass on real dm_control 1.0.50 + mujoco 3.17.
REFERENCE_PASSED = 101
#: Tests of the other files that fail on real dm_control 1.0.50 + mujoco 3.17, keyed
#: "file::class::test", with why. None do: all 101 pass there.
REFERENCE_FAILURES: dict[str, str] = {}

_CONFTEST = '''
"""Written by tools.moma_conformance: dm_control's composer/mjcf/mujoco are this project."""
from composer import dm_control_compat

dm_control_compat.install()

from absl import flags  # noqa: E402

flags.FLAGS.mark_as_parsed()
'''


class FileResult(NamedTuple):
    """One MoMa test file's outcome; `crashed` holds the signal that ended its process."""

    path: str
    passed: int
    failed: list[str]
    skipped: int
    crashed: int | None


def supported() -> bool:
    """Whether MoMa's wheels exist for this Python."""
    return sys.version_info[:2] in MOMA_PYTHONS


def copy_tests(python: Path, destination: Path) -> list[Path]:
    """Copies MoMa's test files, less `EXCLUDED_FILES`, out of the venv; returns them."""
    location = subprocess.run(
        [str(python), "-c", "import dm_robotics.moma as m; print(m.__path__[0])"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    shutil.rmtree(destination, ignore_errors=True)
    copies = []
    for path in sorted(Path(location).rglob("*_test.py")):
        relative = path.relative_to(location).as_posix()
        if relative in EXCLUDED_FILES:
            continue
        target = destination / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(path, target)
        copies.append(target)
    (destination / "conftest.py").write_text(_CONFTEST)
    return copies


def _run_file(python: Path, tests: Path, test_file: Path) -> FileResult:
    relative = test_file.relative_to(tests).as_posix()
    report = tests / (relative.replace("/", "__") + ".xml")
    report.unlink(missing_ok=True)
    completed = subprocess.run(
        [str(python), "-m", "pytest", "-q", "-p", "no:cacheprovider"]
        + ["--import-mode=importlib", f"--junitxml={report}", "-o", "junit_family=xunit1"]
        + [str(test_file)],
        cwd=tests,
        env=dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl")),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    crashed = -completed.returncode if completed.returncode < 0 else None
    passed, skipped, failed = 0, 0, []
    if report.exists():
        for case in ElementTree.parse(report).getroot().iter("testcase"):
            outcome = {child.tag for child in case}
            if outcome & {"failure", "error"}:
                test_class = case.get("classname", "").rpartition(".")[2]
                # A file that fails to import is one case named after the module.
                name = f"{test_class}::{case.get('name')}" if test_class else "(import failed)"
                failed.append(f"{relative}::{name}")
            elif "skipped" in outcome:
                skipped += 1
            else:
                passed += 1
    return FileResult(relative, passed, failed, skipped, crashed)


def run_tests(python: Path, tests: Path, copies: list[Path]) -> list[FileResult]:
    """Runs each copied file in its own pytest process, a few at a time."""
    workers = max(1, min(4, os.cpu_count() or 1))
    with futures.ThreadPoolExecutor(workers) as pool:
        return list(pool.map(lambda copy: _run_file(python, tests, copy), copies))


def print_table(results: list[FileResult]) -> int:
    """Prints per-file counts, the excluded files, the failures and the totals; returns
    how many tests passing on dm_control 1.0.50 + mujoco 3.17 fail here (a crashed file
    counts once)."""
    width = max(len(r.path) for r in results) + 2
    print(f"\n{'MoMa test file':<{width}}  passed  failed  skipped")
    for r in results:
        crash = f"   crashed (signal {r.crashed})" if r.crashed else ""
        print(f"{r.path:<{width}}  {r.passed:6d}  {len(r.failed):6d}  {r.skipped:7d}{crash}")
    passed = sum(r.passed for r in results)
    failed = [test_id for r in results for test_id in r.failed]
    print(
        f"{'total MoMa':<{width}}  {passed:6d}  {len(failed):6d}  "
        f"{sum(r.skipped for r in results):7d}   "
        f"({REFERENCE_PASSED} pass on dm_control 1.0.50 + mujoco 3.17)"
    )
    print("\nMoMa test files not run:")
    for path, reason in EXCLUDED_FILES.items():
        print(f"  {path}: {reason}")
    regressions = sum(test_id not in REFERENCE_FAILURES for test_id in failed)
    regressions += sum(1 for r in results if r.crashed)
    # Tests that ran nowhere (a file that collected nothing) are missing passes too.
    regressions += max(0, REFERENCE_PASSED - passed - regressions)
    if failed:
        print("\nfailing MoMa tests:")
        for test_id in failed:
            reason = REFERENCE_FAILURES.get(test_id)
            print(f"  {test_id}" + (f"\n      fails on dm_control too: {reason}" if reason else ""))
    return regressions


def run(python: Path, cache: Path) -> int:
    """Copies and runs MoMa's tests with the venv's `python`; prints the MoMa section and
    returns 1 when a test that passes on dm_control 1.0.50 + mujoco 3.17 fails here."""
    if not supported():
        print(
            f"\nMoMa: not run, dm-robotics-controllers {MOMA_VERSION} has no wheel for "
            f"Python {sys.version_info.major}.{sys.version_info.minor}"
        )
        return 0
    start = time.perf_counter()
    tests = cache / "moma_tests"
    results = run_tests(python, tests, copy_tests(python, tests))
    regressions = print_table(results)
    print(f"MoMa section: {time.perf_counter() - start:.0f} s")
    if regressions:
        print(
            f"{regressions} MoMa test(s) passing on dm_control 1.0.50 + mujoco 3.17 did not "
            "pass here (failed, crashed or not collected)"
        )
    return 1 if regressions else 0
