"""tools/dm_control_conformance.py: a stuck or silent environment runner fails the run,
naming the runner, instead of hanging CI."""

import subprocess
import sys

import pytest

from tools import dm_control_conformance as conformance


@pytest.fixture
def runner_files(monkeypatch, tmp_path):
    """Points the runner's output and error files at `tmp_path`."""
    monkeypatch.setattr(conformance, "TASK_OUTPUT", tmp_path / "tasks.out")
    monkeypatch.setattr(conformance, "TASK_ERRORS", tmp_path / "tasks.err")
    return tmp_path


def _runner(code: str, files) -> subprocess.Popen:
    with open(files / "tasks.out", "w") as out, open(files / "tasks.err", "w") as err:
        return subprocess.Popen([sys.executable, "-c", code], stdout=out, stderr=err)


def test_a_runner_past_its_time_is_killed_and_named(runner_files, monkeypatch):
    monkeypatch.setattr(conformance, "TASKS_TIMEOUT", 1)
    runner = _runner(
        "import sys, time; print('loading lift_brick', file=sys.stderr, flush=True); "
        "time.sleep(60)",
        runner_files,
    )
    with pytest.raises(RuntimeError) as error:
        conformance.finish_tasks(sys.executable, runner)
    assert runner.returncode is not None  # killed, not left running
    message = str(error.value)
    assert "environment runner did not finish within 1 s and was killed" in message
    assert message.endswith("loading lift_brick\n")


def test_a_runner_that_prints_no_results_fails_with_its_stderr(runner_files):
    runner = _runner("import sys; sys.exit('no tasks found')", runner_files)
    with pytest.raises(RuntimeError, match="printed no results(.|\n)*no tasks found"):
        conformance.finish_tasks(sys.executable, runner)
