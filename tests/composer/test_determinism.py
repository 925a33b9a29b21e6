"""Two processes given the same seed see bit-identical trajectories."""

import os
import subprocess
import sys

import pytest

import composer

_SCRIPT = os.path.join(os.path.dirname(__file__), "trajectory_run.py")
# The subprocesses import the same packages as this process, installed or not.
_ENV = {**os.environ, "PYTHONPATH": os.path.dirname(os.path.dirname(composer.__file__))}


def _digests(runs):
    """SHA-256 digests of `trajectory_run.py TASK SEED` for each (task, seed), run at once."""
    processes = [
        subprocess.Popen(
            [sys.executable, _SCRIPT, task, str(seed)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=_ENV,
        )
        for task, seed in runs
    ]
    digests = []
    for process in processes:
        out, err = process.communicate(timeout=300)
        assert process.returncode == 0, err[-2000:]
        digests.append(out.strip().splitlines()[-1])
    return digests


@pytest.mark.parametrize("task", ["varied_reach", "lift_brick"])
def test_same_seed_in_two_processes_gives_identical_trajectories(task):
    first, second, other_seed = _digests([(task, 3), (task, 3), (task, 4)])
    assert first == second
    assert first != other_seed
