"""examples/custom_task.py builds its task from scratch and runs an episode."""

import os
import pathlib
import subprocess
import sys

_ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_custom_task_example_runs_an_episode_and_reports_it():
    environment = dict(os.environ, PYTHONPATH=str(_ROOT))
    result = subprocess.run(
        [sys.executable, str(_ROOT / "examples" / "custom_task.py"), "--time_limit", "0.4"],
        capture_output=True,
        text=True,
        check=True,
        cwd=_ROOT,
        env=environment,
        timeout=120,
    )
    assert "observation box/position: shape (1, 3)" in result.stdout
    assert "episode: 10 steps, return" in result.stdout
