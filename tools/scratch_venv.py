"""Scratch virtual environments for the harnesses and benchmarks (not library code).

`ensure_venv(path, requirements, project=True, no_deps=())` creates `path` once with the
given pip requirements (and this project installed editable, and `no_deps` installed without
their dependencies), and reuses it while the requirements are unchanged.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from tools import ROOT

CACHE = ROOT / ".cache"


def _pip(python: Path, *args: str) -> None:
    subprocess.run([str(python), "-m", "pip", "install", "-q", *args], check=True)


def ensure_venv(
    path: Path, requirements: list[str], *, project: bool = True, no_deps: list[str] = ()
) -> Path:
    """Returns the python of a venv at `path` holding `requirements`.

    The venv is rebuilt when the requirements differ from the ones it was built with. With
    `project` the working tree is (re)installed editable on every call, without touching
    its dependencies, so the venv always runs the current code. `no_deps` are installed
    last, with `pip --no-deps` (packages whose pinned dependencies would replace the ones
    installed before them).
    """
    python = path / "bin" / "python"
    stamp = path / "scratch-venv-requirements"
    wanted = "\n".join(
        [*requirements, *(f"--no-deps {requirement}" for requirement in no_deps)]
        + [f"project={project}"]
    )
    if not (stamp.exists() and stamp.read_text(encoding="utf-8") == wanted):
        shutil.rmtree(path, ignore_errors=True)
        subprocess.run([sys.executable, "-m", "venv", str(path)], check=True)
        _pip(python, "--upgrade", "pip")
        if project:
            _pip(python, "-e", str(ROOT))
        if requirements:
            _pip(python, *requirements)
        if no_deps:
            _pip(python, "--no-deps", *no_deps)
        stamp.write_text(wanted)
    elif project:
        _pip(python, "--no-deps", "-e", str(ROOT))
    return python
