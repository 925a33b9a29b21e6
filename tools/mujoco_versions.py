"""Tests every supported MuJoCo minor release; prints release -> passed/failed/skipped.

Usage: `python -m tools.mujoco_versions [--releases 3.3 4.0] [--strict] [--install-only]
[-- PYTEST_ARGS]`

Builds one venv per release under `.cache/mujoco_versions/<version>` (kept between runs;
`--venvs` puts them elsewhere), installs this project with its `[test]` extra and that
`mujoco` there, proves there which MJCF attributes a reset may patch in place
(`python -m manipulation.patch_proof`: on the release of the checked-in table it checks the table,
on any other it caches its proof, in `xdg_cache/` beside the venvs), and runs `pytest` in
each with `MUJOCO_GL=egl` (the tests start from an empty cache of their own, so each patch is
proven at first use there); each run's full output goes to
`logs/<version>.txt` beside the venvs (`--install-only` builds the venvs and exits). The
releases are the newest patch of every minor release that pip offers from the project's
floor (`mujoco_physics.version.MINIMUM_VERSION`) up, the floor version itself, and the
newest release below the floor, where importing the project must fail with the ImportError
that names both versions. `--releases` picks some: `floor`, `newest`, `below-floor`, a
minor (`3.3`, its newest patch) or an exact version (`3.3.0`). With `--strict` the exit
status is 1 when a release has a failing test or its install or test run breaks.
`--skip-installed` leaves out the release that the running Python already has (CI's main
run proved and tested it), saying so.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import NamedTuple

from tools import ROOT, scratch_venv

CACHE = ROOT / ".cache" / "mujoco_versions"
_COMPAT_MODULE = ROOT / "mujoco_physics" / "version.py"
_TAIL_LINES = 15
_SUMMARY_COUNT = re.compile(r"(\d+) (passed|failed|skipped|errors?|xfailed|xpassed)")
_PROVEN_COUNT = re.compile(r"^(\d+) pairs patch, ", re.M)


class Release(NamedTuple):
    """One MuJoCo release to test; one below the floor is tested for a clean ImportError."""

    version: str
    minor: str
    below_floor: bool = False


class Outcome(NamedTuple):
    """What one release's test run gave."""

    version: str
    passed: int
    failed: int
    skipped: int
    seconds: float
    problem: str  # empty when the run reached pytest's summary
    details: tuple[str, ...]  # pytest's FAILED/ERROR lines, or the log's tail on a problem
    patched: int | None  # pairs `mjcf.patching.patch_proof` proved; None if it did not run

    @property
    def ok(self) -> bool:
        return not self.problem and self.failed == 0


def _version_key(version: str) -> tuple[int, ...]:
    return tuple(int(part) for part in re.findall(r"\d+", version)[:3])


def _minor(version: str) -> str:
    return ".".join(version.split(".")[:2])


def minimum_version() -> str:
    """The project's MuJoCo floor, read from the module that enforces it at import."""
    match = re.search(
        r'^MINIMUM_VERSION = "([\d.]+)"', _COMPAT_MODULE.read_text(encoding="utf-8"), re.M
    )
    if match is None:
        raise RuntimeError(f'no MINIMUM_VERSION = "x.y.z" line in {_COMPAT_MODULE}')
    return match.group(1)


def available_versions() -> list[str]:
    """Every final mujoco release that pip offers, newest first."""
    result = subprocess.run(
        [sys.executable, "-m", "pip", "index", "versions", "mujoco"],
        capture_output=True,
        text=True,
        check=True,
    )
    for line in result.stdout.splitlines():
        if line.startswith("Available versions:"):
            versions = [v.strip() for v in line.split(":", 1)[1].split(",")]
            return [v for v in versions if re.fullmatch(r"\d+\.\d+\.\d+", v)]
    raise RuntimeError(f"pip index versions mujoco listed no versions:\n{result.stdout}")


def supported_releases(versions: list[str], floor: str) -> list[Release]:
    """The newest patch of each minor release from `floor`'s minor up, oldest first."""
    newest: dict[str, str] = {}
    for version in versions:
        if _version_key(version) < _version_key(floor):
            continue
        minor = _minor(version)
        if minor not in newest or _version_key(version) > _version_key(newest[minor]):
            newest[minor] = version
    return [Release(v, m) for m, v in sorted(newest.items(), key=lambda i: _version_key(i[1]))]


def below_floor_release(versions: list[str], floor: str) -> Release | None:
    """The newest release older than `floor`, or None when pip offers none."""
    older = [v for v in versions if _version_key(v) < _version_key(floor)]
    if not older:
        return None
    version = max(older, key=_version_key)
    return Release(version, _minor(version), below_floor=True)


def pick(
    releases: list[Release], versions: list[str], wanted: list[str], floor: str
) -> list[Release]:
    """The releases named in `wanted`: a minor (`3.3`), an exact version (`3.3.0`),
    `floor` (exactly the project's floor version), `newest` (the newest release) or
    `below-floor` (the newest release older than the floor)."""
    by_minor = {release.minor: release for release in releases}
    aliases = {"floor": floor, "newest": releases[-1].version}
    below = below_floor_release(versions, floor)
    picked = []
    for name in wanted:
        name = aliases.get(name, name)
        if name == "below-floor" and below is not None:
            picked.append(below)
        elif name in by_minor:
            picked.append(by_minor[name])
        elif name in versions:
            picked.append(Release(name, _minor(name)))
        else:
            known = ", ".join(by_minor)
            raise SystemExit(
                f"--releases: {name!r} is not floor, newest, below-floor, a minor ({known}) "
                "or a pip version"
            )
    return picked


def without_installed(releases: list[Release], installed: str) -> list[Release]:
    """`releases` less the one whose version is `installed`; prints that it is left out."""
    kept = [release for release in releases if release.version != installed]
    if len(kept) < len(releases):
        print(
            f"mujoco {installed}: left out, it is the release this Python runs (--skip-installed)"
        )
    return kept


def _run(args: list[str], log, **kwargs) -> int:
    log.write(f"$ {' '.join(args)}\n")
    log.flush()
    return subprocess.run(args, stdout=log, stderr=subprocess.STDOUT, **kwargs).returncode


def _project_requirements() -> list[str]:
    """The project's dependencies and its `[test]` extra, from its pyproject.toml (none on
    Python 3.10, which cannot read it: there the project's install brings them)."""
    try:
        import tomllib
    except ImportError:
        return []
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    return [*project["dependencies"], *project["optional-dependencies"]["test"]]


def _install(venv: Path, release: Release, log) -> str:
    """Builds `venv` for `release` unless it exists; returns a problem or ''.

    The project's requirements are installed first, then the project itself editable under
    `scratch_venv.project_install_lock` (so CI can build the venvs while its own venv
    installs)."""
    marker = venv / ".installed"
    # The project's requirements are part of what a venv was built with: rebuild when the
    # `[test]` extra or the dependencies change.
    built_with = (
        f"{release.version} {hashlib.sha256((ROOT / 'pyproject.toml').read_bytes()).hexdigest()}\n"
    )
    if marker.exists() and marker.read_text(encoding="utf-8") == built_with:
        return ""
    if _run([sys.executable, "-m", "venv", "--clear", str(venv)], log):
        return "venv creation failed"
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "-q"]
    # Below the floor the project's own requirement excludes this mujoco: the project is
    # installed with its dependencies first, then the old mujoco put in its place.
    mujoco = [] if release.below_floor else [f"mujoco=={release.version}"]
    if _run([*pip, *_project_requirements(), *mujoco], log):
        return "install failed"
    with scratch_venv.project_install_lock():
        if _run([*pip, "-e", f"{ROOT}[test]", *mujoco], log):
            return "install failed"
    if release.below_floor:
        # Newer mujoco wheels leave files that pip does not remove (plugins linked to their
        # libmujoco), hence the rmtree.
        if _run(
            [str(venv / "bin" / "python"), "-m", "pip", "uninstall", "-q", "-y", "mujoco"], log
        ):
            return "uninstall failed"
        for leftover in venv.glob("lib/python*/site-packages/mujoco"):
            shutil.rmtree(leftover)
        if _run([*pip, f"mujoco=={release.version}"], log):
            return "install failed"
    marker.write_text(built_with, encoding="utf-8")
    return ""


def install_only(releases: list[Release], venvs: Path) -> int:
    """Builds each release's venv in `venvs` (logs in `venvs/logs/`); returns 1 when one
    failed, naming it and its log."""
    status = 0
    for release in releases:
        log_path = venvs / "logs" / f"{release.version}-install.txt"
        log_path.parent.mkdir(parents=True, exist_ok=True)
        with open(log_path, "w") as log:
            problem = _install(venvs / release.version, release, log)
        print(f"mujoco {release.version}: {problem or 'installed'} (log: {log_path})")
        status |= bool(problem)
    return status


def _summary_counts(output: str) -> dict[str, int] | None:
    """Counts from pytest's closing summary line, or None where there is none."""
    for line in reversed(output.splitlines()):
        if " in " in line and _SUMMARY_COUNT.search(line):
            counts: dict[str, int] = {}
            for number, word in _SUMMARY_COUNT.findall(line):
                key = "failed" if word.startswith("error") else word
                counts[key] = counts.get(key, 0) + int(number)
            return counts
    return None


def run_release(release: Release, venvs: Path, pytest_args: list[str]) -> Outcome:
    """Installs (once) and tests one release in `venvs/<version>`; its full log goes to
    `venvs/logs/<version>.txt`."""
    start = time.monotonic()
    venv = venvs / release.version
    log_path = venvs / "logs" / f"{release.version}.txt"
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "w") as log:
        problem = _install(venv, release, log)
    if problem:
        tail = tuple(log_path.read_text(encoding="utf-8").splitlines()[-_TAIL_LINES:])
        return Outcome(release.version, 0, 0, 0, time.monotonic() - start, problem, tail, None)
    if release.below_floor:
        return _check_import_refused(release, venv, log_path, start)
    env = dict(os.environ, MUJOCO_GL="egl", XDG_CACHE_HOME=str(venvs / "xdg_cache"))
    env.pop("VIRTUAL_ENV", None)
    patched, problem = _prove_patch_table(venv, env, log_path)
    if problem:
        tail = tuple(log_path.read_text(encoding="utf-8").splitlines()[-_TAIL_LINES:])
        return Outcome(release.version, 0, 0, 0, time.monotonic() - start, problem, tail, patched)
    with open(log_path, "a") as log:
        args = [str(venv / "bin" / "python"), "-m", "pytest", "-q", "-p", "no:cacheprovider"]
        log.write(f"$ {' '.join(args + pytest_args)}\n")
        log.flush()
        result = subprocess.run(
            args + pytest_args, cwd=ROOT, env=env, capture_output=True, text=True
        )
        log.write(result.stdout + result.stderr)
    counts = _summary_counts(result.stdout)
    seconds = time.monotonic() - start
    if counts is None:
        tail = tuple((result.stdout + result.stderr).splitlines()[-_TAIL_LINES:])
        return Outcome(
            release.version, 0, 0, 0, seconds, f"no pytest summary, see {log_path}", tail, patched
        )
    failures = tuple(
        line for line in result.stdout.splitlines() if line.startswith(("FAILED ", "ERROR "))
    )
    return Outcome(
        release.version,
        counts.get("passed", 0),
        counts.get("failed", 0),
        counts.get("skipped", 0),
        seconds,
        "",
        failures,
        patched,
    )


def _prove_patch_table(venv: Path, env: dict[str, str], log_path: Path) -> tuple[int | None, str]:
    """Runs `python -m manipulation.patch_proof` in `venv`; returns the number of pairs it proved
    (None when it printed none) and a problem, or '' when it exited 0."""
    with open(log_path, "a") as log:
        args = [str(venv / "bin" / "python"), "-m", "manipulation.patch_proof"]
        log.write(f"$ {' '.join(args)}\n")
        log.flush()
        result = subprocess.run(args, cwd=ROOT, env=env, capture_output=True, text=True)
        log.write(result.stdout + result.stderr)
    match = _PROVEN_COUNT.search(result.stdout)
    patched = int(match.group(1)) if match else None
    if result.returncode:
        return patched, f"patch proof failed (exit {result.returncode}), see {log_path}"
    return patched, ""


def _check_import_refused(release: Release, venv: Path, log_path: Path, start: float) -> Outcome:
    """Imports the project under a mujoco below the floor: passes when the import fails with
    the ImportError that names both versions, fails on anything else."""
    result = subprocess.run(
        [str(venv / "bin" / "python"), "-c", "import mjcf, composer, manipulation"],
        cwd=venv,
        capture_output=True,
        text=True,
    )
    with open(log_path, "a") as log:
        log.write(result.stdout + result.stderr)
    lines = result.stderr.strip().splitlines()
    last = lines[-1] if lines else "(the import succeeded)"
    expected = f"ImportError: this project needs mujoco>={minimum_version()}, but mujoco "
    refused = last.startswith(expected + f"{release.version} is installed")
    seconds = time.monotonic() - start
    return Outcome(release.version, int(refused), int(not refused), 0, seconds, "", (last,), None)


def print_table(outcomes: list[Outcome], below_floor: set[str]) -> None:
    """Prints one row per release: its test counts, the MJCF attribute pairs its patch
    proof proved ('-' where none ran) and the result."""
    print(
        f"{'mujoco':<10}{'passed':>8}{'failed':>8}{'skipped':>9}{'patched':>9}{'seconds':>9}"
        "  result"
    )
    for o in outcomes:
        result = o.problem or ("ok" if o.ok else "FAILED")
        if o.version in below_floor and not o.problem:
            result += ": below the floor, import " + ("refused" if o.ok else "NOT refused")
        patched = "-" if o.patched is None else str(o.patched)
        print(
            f"{o.version:<10}{o.passed:>8}{o.failed:>8}{o.skipped:>9}{patched:>9}"
            f"{o.seconds:>9.0f}  {result}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--releases",
        nargs="+",
        metavar="RELEASE",
        help="floor, newest, below-floor, minors (3.3: its newest patch) or exact versions "
        "(3.3.0); default: below-floor, floor and every minor",
    )
    parser.add_argument(
        "--venvs", type=Path, default=CACHE, help=f"where the venvs are kept (default {CACHE})"
    )
    parser.add_argument(
        "--strict", action="store_true", help="exit 1 when any release has a failure"
    )
    parser.add_argument(
        "--skip-installed",
        action="store_true",
        help="leave out the release installed where this command runs (tested there already)",
    )
    parser.add_argument(
        "--install-only",
        action="store_true",
        help="build the releases' venvs and exit (CI builds them while other checks run)",
    )
    parser.add_argument("pytest_args", nargs="*", help="extra arguments for pytest (after --)")
    args = parser.parse_args(argv)
    versions = available_versions()
    floor = minimum_version()
    releases = supported_releases(versions, floor)
    if args.releases:
        releases = pick(releases, versions, args.releases, floor)
    else:
        extra = ["below-floor"] + ([] if floor in {r.version for r in releases} else ["floor"])
        releases = pick(releases, versions, extra, floor) + releases
    if args.skip_installed:
        import mujoco

        releases = without_installed(releases, mujoco.__version__)
    if args.install_only:
        return install_only(releases, args.venvs.resolve())
    outcomes = []
    for release in releases:
        print(f"mujoco {release.version}: installing and testing ...", flush=True)
        outcome = run_release(release, args.venvs.resolve(), args.pytest_args)
        for line in outcome.details:
            print(f"  {line}")
        outcomes.append(outcome)
    print_table(outcomes, {r.version for r in releases if r.below_floor})
    broken = [o.version for o in outcomes if o.problem]
    if broken:
        print(f"releases whose run broke: {', '.join(broken)}")
    failed = sum(o.failed for o in outcomes) + len(broken)
    passed = sum(o.passed for o in outcomes)
    skipped = sum(o.skipped for o in outcomes)
    print(f"mujoco_versions: {passed} passed, {failed} failed, {skipped} skipped")
    if args.strict and (failed or broken):
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
