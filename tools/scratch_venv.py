"""Scratch virtual environments for the harnesses and benchmarks (not library code).

`ensure_venv(path, requirements, project=True, no_deps=())` creates `path` once with the
given pip requirements (and this project installed editable, and `no_deps` installed without
their dependencies), and reuses it while the requirements and the project's
`pyproject.toml` are unchanged.

`project_install_lock()` is held while pip installs this project editable: setuptools writes
the project's metadata into the working tree (`*.egg-info`), so installs of it into several
venvs at once (CI builds the harnesses' venvs while the project's own venv installs, taking
`PROJECT_INSTALL_LOCK` with `flock`) take turns there and only there.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from tools import ROOT

CACHE = ROOT / ".cache"
PROJECT_INSTALL_LOCK = CACHE / "project-install.lock"
#: Seconds `project_install_lock` waits: longer than CI's install of the project's own venv.
PROJECT_INSTALL_LOCK_TIMEOUT = 1200


@contextlib.contextmanager
def project_install_lock() -> Iterator[None]:
    """Holds `PROJECT_INSTALL_LOCK` (see the module docstring).

    Raises:
      TimeoutError: naming the lock file, when another install held it for
        `PROJECT_INSTALL_LOCK_TIMEOUT` seconds.
    """
    PROJECT_INSTALL_LOCK.parent.mkdir(parents=True, exist_ok=True)
    with open(PROJECT_INSTALL_LOCK, "a") as lock:
        deadline = time.monotonic() + PROJECT_INSTALL_LOCK_TIMEOUT
        while True:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise TimeoutError(
                        f"{PROJECT_INSTALL_LOCK}: another install of the project held it for "
                        f"{PROJECT_INSTALL_LOCK_TIMEOUT} s"
                    ) from None
                time.sleep(0.5)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _pip(python: Path, *args: str) -> None:
    subprocess.run([str(python), "-m", "pip", "install", "-q", *args], check=True)


def ensure_venv(
    path: Path, requirements: list[str], *, project: bool = True, no_deps: list[str] = ()
) -> Path:
    """Returns the python of a venv at `path` holding `requirements`.

    With `project` the working tree is installed editable, after the requirements and
    under `project_install_lock`, so the venv runs the current code without a reinstall.
    The venv is rebuilt when the requirements differ from the ones it was built with, or,
    with `project`, when the project's `pyproject.toml` (its dependencies, version and
    packages) or its folder does. `no_deps` are installed last, with `pip --no-deps`
    (packages whose pinned dependencies would replace the ones installed before them).
    """
    python = path / "bin" / "python"
    stamp = path / "scratch-venv-requirements"
    wanted = "\n".join(
        [*requirements, *(f"--no-deps {requirement}" for requirement in no_deps)]
        + [f"project={_project_stamp() if project else False}"]
    )
    if not (stamp.exists() and stamp.read_text(encoding="utf-8") == wanted):
        shutil.rmtree(path, ignore_errors=True)
        subprocess.run([sys.executable, "-m", "venv", str(path)], check=True)
        _pip(python, "--upgrade", "pip")
        if requirements:
            _pip(python, *requirements)
        if project:
            with project_install_lock():
                _pip(python, "-e", str(ROOT))
        if no_deps:
            _pip(python, "--no-deps", *no_deps)
        stamp.write_text(wanted)
    return python


def _project_stamp() -> str:
    """The project's folder and its pyproject.toml's digest: what an editable install of it
    was made from."""
    digest = hashlib.sha256((ROOT / "pyproject.toml").read_bytes()).hexdigest()
    return f"{ROOT} {digest}"
