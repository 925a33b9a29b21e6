"""The scripted controllers of examples/ solve reach_site_features and lift_brick_features,
and examples/quickstart.py runs and reports an episode: the tasks are solvable, not just
runnable."""

import importlib.util
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import manipulation

_EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
_SEEDS = (0, 1, 2, 3, 4)
_STEPS_PER_SECOND = 25


def _load_scripted_control():
    spec = importlib.util.spec_from_file_location(
        "scripted_control", _EXAMPLES / "scripted_control.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


scripted_control = _load_scripted_control()


@pytest.mark.parametrize("seed", _SEEDS)
def test_reach_controller_holds_the_pinch_site_on_the_target_for_the_last_second(seed):
    env = manipulation.load("reach_site_features", seed=seed)
    timestep = env.reset()
    policy = scripted_control.ReachPolicy(env)
    rewards = []
    while not timestep.last():
        timestep = env.step(policy(timestep))
        rewards.append(timestep.reward)
    assert len(rewards) == 250
    assert np.mean(rewards[-_STEPS_PER_SECOND:]) >= 0.9


def _lifts_brick(seed: int) -> bool:
    """Runs the scripted lift until the reward reaches 0.9 (True) or the episode ends."""
    env = manipulation.load("lift_brick_features", seed=seed)
    timestep = env.reset()
    policy = scripted_control.LiftPolicy(env)
    while not timestep.last():
        timestep = env.step(policy(timestep))
        if timestep.reward >= 0.9:
            return True
    return False


def test_lift_controller_lifts_the_brick_on_at_least_3_of_5_seeds():
    lifted = [seed for seed in _SEEDS if _lifts_brick(seed)]
    assert len(lifted) >= 3, f"lifted on seeds {lifted} only"


def test_quickstart_runs_a_reach_episode_and_prints_steps_return_and_timing():
    result = subprocess.run(
        [sys.executable, str(_EXAMPLES / "quickstart.py"), "--seed", "1"],
        capture_output=True,
        text=True,
        check=True,
        env=dict(os.environ, PYTHONPATH=str(_EXAMPLES.parent)),
        timeout=120,
    )
    assert "reach_site_features (seed 1), scripted controller" in result.stdout
    assert "steps: 250, return:" in result.stdout
    assert "mean reward over the last second: 1.000" in result.stdout
    assert "step:" in result.stdout and "ms (mean)" in result.stdout
