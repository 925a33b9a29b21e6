"""tools/scratch_venv.py: a harness's venv is built once and reused, the project in it
installed editable, and rebuilt only when what it was built from changes."""

import subprocess
import sys
import time
import types

import pytest

from tools import scratch_venv


@pytest.fixture
def installs(monkeypatch, tmp_path):
    """Fakes venv creation and pip, for a project folder of its own; returns the commands
    run (`installs.commands`) and that folder (`installs.project`)."""
    project = tmp_path / "project"
    project.mkdir()
    (project / "pyproject.toml").write_text('[project]\nname = "p"\nversion = "1"\n')
    monkeypatch.setattr(scratch_venv, "ROOT", project)
    commands = []

    def make_venv(args, check):
        commands.append(["venv", args[-1]])
        (tmp_path / "venv" / "bin").mkdir(parents=True, exist_ok=True)

    monkeypatch.setattr(scratch_venv.subprocess, "run", make_venv)
    monkeypatch.setattr(scratch_venv, "_pip", lambda python, *args: commands.append(list(args)))
    return types.SimpleNamespace(commands=commands, project=project)


def test_the_first_call_builds_the_venv_with_the_project_editable(installs, tmp_path):
    python = scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"])
    assert python == tmp_path / "venv" / "bin" / "python"
    assert installs.commands == [
        ["venv", str(tmp_path / "venv")],
        ["--upgrade", "pip"],
        ["dm-control==1.0.50"],
        ["-e", str(installs.project)],
    ]


def test_a_second_call_with_nothing_changed_installs_nothing(installs, tmp_path):
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"])
    installs.commands.clear()
    (installs.project / "module.py").write_text("# a code change: the editable install has it")
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"])
    assert installs.commands == []


def test_a_changed_pyproject_rebuilds_the_venv(installs, tmp_path):
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"])
    installs.commands.clear()
    pyproject = installs.project / "pyproject.toml"
    pyproject.write_text(pyproject.read_text() + 'dependencies = ["numpy"]\n')
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"])
    assert ["-e", str(installs.project)] in installs.commands


def test_a_venv_without_the_project_ignores_its_pyproject(installs, tmp_path):
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"], project=False)
    installs.commands.clear()
    (installs.project / "pyproject.toml").write_text('[project]\nname = "p"\nversion = "2"\n')
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"], project=False)
    assert installs.commands == []


def test_changed_requirements_rebuild_the_venv(installs, tmp_path):
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.50"])
    installs.commands.clear()
    scratch_venv.ensure_venv(tmp_path / "venv", ["dm-control==1.0.49"])
    assert ["dm-control==1.0.49"] in installs.commands


def _hold_lock(path, seconds: float) -> subprocess.Popen:
    """Another process (as CI's `flock` around the project's own install) holding `path`."""
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import fcntl, sys, time\n"
            f"lock = open({str(path)!r}, 'a')\n"
            "fcntl.flock(lock, fcntl.LOCK_EX)\n"
            "print('held', flush=True)\n"
            f"time.sleep({seconds})\n",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert holder.stdout.readline() == "held\n"
    return holder


def test_the_project_install_waits_while_another_install_holds_the_lock(monkeypatch, tmp_path):
    monkeypatch.setattr(scratch_venv, "PROJECT_INSTALL_LOCK", tmp_path / "project-install.lock")
    holder = _hold_lock(tmp_path / "project-install.lock", 2)
    start = time.monotonic()
    with scratch_venv.project_install_lock():
        waited = time.monotonic() - start
    assert waited > 1.5  # until the other install let go, 2 s after taking it
    holder.wait()


def test_a_lock_held_too_long_fails_naming_the_lock_file(monkeypatch, tmp_path):
    lock = tmp_path / "project-install.lock"
    monkeypatch.setattr(scratch_venv, "PROJECT_INSTALL_LOCK", lock)
    monkeypatch.setattr(scratch_venv, "PROJECT_INSTALL_LOCK_TIMEOUT", 1)
    holder = _hold_lock(lock, 30)
    try:
        with pytest.raises(TimeoutError, match=f"{lock}: another install of the project held it"):
            with scratch_venv.project_install_lock():
                pass
    finally:
        holder.kill()
        holder.wait()
