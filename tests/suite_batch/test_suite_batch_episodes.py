"""The batched suite tasks: world i is dm_control's `suite.load(..., task_kwargs={"random": seed})`.

Needs dm_control's suite (not a dependency of this project): CI runs these tests in the
dm_control conformance harness's venv (dm_control 1.0.50 on the newest MuJoCo), where
`suite.load` runs through this project's redirect; elsewhere they are skipped.
"""

import math

import numpy as np
import pytest
from episodes import differences, needs_suite

import suite_batch
from suite_batch.domains import cartpole

pytestmark = needs_suite

CARTPOLE_TASKS = (
    "balance",
    "balance_sparse",
    "swingup",
    "swingup_sparse",
    "two_poles",
    "three_poles",
)
BATCHED_TASKS = [("cartpole", task) for task in CARTPOLE_TASKS] + [
    ("cheetah", "run"),
    ("reacher", "easy"),
    ("reacher", "hard"),
]

#: The tasks of `suite.ALL_TASKS` without array code yet: each must still be refused.
NOT_YET_BATCHED = {
    # Its terrain is drawn into hfield_data per episode, which mujoco.batch cannot give
    # each world its own copy of (tests/suite_batch/test_quadruped.py).
    ("quadruped", "escape"),
}


def _all_tasks() -> list[tuple[str, str]]:
    try:
        from suite_batch import loading

        return list(loading.import_suite().ALL_TASKS)
    except ImportError:
        return [("(no dm_control)", "(no task)")]  # skipped by needs_suite


def test_the_batch_has_every_cartpole_task_of_the_suite(suite):
    assert set(CARTPOLE_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "cartpole"}


@pytest.mark.parametrize("domain, task", BATCHED_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, domain, task):
    assert differences(suite, domain, task) == []


@pytest.mark.parametrize("domain, task", BATCHED_TASKS)
def test_same_step_autoreset_is_dm_controls_reset_after_last(suite, domain, task):
    assert differences(suite, domain, task, autoreset_mode="same_step") == []


@pytest.mark.suite_batch_episodes
@pytest.mark.parametrize("autoreset_mode", ["next_step", "same_step"])
@pytest.mark.parametrize("domain, task", _all_tasks())
def test_whole_episodes_of_every_suite_task_are_dm_controls(suite, domain, task, autoreset_mode):
    if (domain, task) in NOT_YET_BATCHED:
        with pytest.raises(NotImplementedError, match="no array code yet"):
            suite_batch.load(domain, task, 1)
        return
    env = suite.load(domain, task)
    step_limit = env._step_limit  # dm_control's own, in control steps
    env.close()
    if math.isinf(step_limit):
        # lqr has no time limit (its episodes end at the goal only): 1,003 steps of short
        # episodes instead, which cross resets.
        found = differences(suite, domain, task, steps=1003, autoreset_mode=autoreset_mode)
    else:
        # A whole episode at the task's own time limit, its reset and a few steps of the next.
        found = differences(
            suite,
            domain,
            task,
            steps=int(round(step_limit)) + 3,
            short=False,
            autoreset_mode=autoreset_mode,
        )
    assert found[:10] == []


def test_flat_observations_are_dm_controls(suite):
    assert (
        differences(suite, "cartpole", "swingup", environment_kwargs={"flat_observation": True})
        == []
    )


def test_a_reward_one_ulp_off_is_found(suite, monkeypatch):
    original = cartpole.BatchBalance.get_reward
    monkeypatch.setattr(
        cartpole.BatchBalance, "get_reward", lambda self: np.nextafter(original(self), np.inf)
    )
    found = differences(suite, "cartpole", "swingup")
    assert found and all(difference.endswith("reward") for difference in found)


def test_unknown_names_are_told_the_closest_ones(suite):
    with pytest.raises(ValueError, match=r"domain_name: 'cartpol' .* did you mean 'cartpole'"):
        suite_batch.load("cartpol", "swingup", 2)
    with pytest.raises(
        ValueError, match=r"task_name: .* no task 'swingupp'; did you mean 'swingup'"
    ):
        suite_batch.load("cartpole", "swingupp", 2)


def test_a_task_without_array_code_is_named(suite):
    with pytest.raises(NotImplementedError, match=r"quadruped-escape \(Escape\): no array code"):
        suite_batch.load("quadruped", "escape", 2)


def test_a_seed_in_task_kwargs_is_refused_for_seed_or_random_states(suite):
    with pytest.raises(ValueError, match=r"task_kwargs: 'random' seeds one environment"):
        suite_batch.load("cartpole", "swingup", 2, task_kwargs={"random": 1})


def test_a_bad_number_of_worlds_is_named(suite):
    with pytest.raises(ValueError, match=r"num_envs: expected an integer >= 1, got 0"):
        suite_batch.load("cartpole", "swingup", 0)
