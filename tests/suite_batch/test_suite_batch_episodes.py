"""The batched suite tasks: world i is dm_control's `suite.load(..., task_kwargs={"random": seed})`.

Needs dm_control's suite (not a dependency of this project): CI runs these tests in the
dm_control conformance harness's venv (dm_control 1.0.50 on the newest MuJoCo), where
`suite.load` runs through this project's redirect; elsewhere they are skipped.
"""

import importlib.util

import numpy as np
import pytest

import suite_batch
from suite_batch import cartpole, loading


def _has_suite() -> bool:
    try:
        return importlib.util.find_spec("dm_control.suite") is not None
    except ModuleNotFoundError:
        return False


pytestmark = pytest.mark.skipif(
    not _has_suite(),
    reason="needs dm_control's suite (pip install dm-control --no-deps); CI runs these in "
    "the conformance harness's venv",
)

CARTPOLE_TASKS = (
    "balance",
    "balance_sparse",
    "swingup",
    "swingup_sparse",
    "two_poles",
    "three_poles",
)
BATCHED_TASKS = [("cartpole", task) for task in CARTPOLE_TASKS] + [("cheetah", "run")]
SEEDS = (3, 11, 12345)
# 25 control steps an episode (0.01 s each, cartpole's and cheetah's): 60 steps cross two
# resets.
SHORT = {"time_limit": 0.25}
STEPS = 60


@pytest.fixture(scope="module")
def suite():
    return loading.import_suite()


def _differences(suite, domain, task, *, environment_kwargs=None) -> list[str]:
    """Steps the batch and the CPU envs seeded alike with the same actions; returns every
    difference found, named by step, world and quantity."""
    batch = suite_batch.load(
        domain,
        task,
        len(SEEDS),
        task_kwargs=SHORT,
        environment_kwargs=environment_kwargs,
        random_states=SEEDS,
        threads=1,
    )
    cpus = [
        suite.load(
            domain,
            task,
            task_kwargs={"random": seed, **SHORT},
            environment_kwargs=environment_kwargs,
        )
        for seed in SEEDS
    ]
    spec = cpus[0].action_spec()
    actions = np.random.RandomState(0).uniform(
        spec.minimum, spec.maximum, (STEPS, len(SEEDS), *spec.shape)
    )
    found, restarted = [], False
    step, cpu_steps = batch.reset(), [cpu.reset() for cpu in cpus]
    for t in range(STEPS + 1):
        for world, (cpu, cpu_step) in enumerate(zip(cpus, cpu_steps)):
            where = f"step {t}, world {world}"
            expected = {
                "step type": int(cpu_step.step_type),
                "reward": 0.0 if cpu_step.reward is None else cpu_step.reward,
                "discount": 1.0 if cpu_step.discount is None else cpu_step.discount,
            }
            got = {
                "step type": int(step.step_type[world]),
                "reward": step.reward[world],
                "discount": step.discount[world],
            }
            found += [f"{where}: {key}" for key in expected if got[key] != expected[key]]
            for key, value in cpu_step.observation.items():
                if not np.array_equal(step.observation[key][world], value):
                    found.append(f"{where}: observation {key!r}")
            for field in ("qpos", "qvel"):
                cpu_value = getattr(cpu.physics.data, field)
                if not np.array_equal(getattr(batch.physics.data, field)[world], cpu_value):
                    found.append(f"{where}: {field}")
        if t == STEPS:
            break
        step = batch.step(actions[t])
        cpu_steps = [cpu.step(action) for cpu, action in zip(cpus, actions[t])]
        restarted |= bool(step.first().any())
    batch.close()
    return found + ([] if restarted else ["no episode restarted"])


def test_the_batch_has_every_cartpole_task_of_the_suite(suite):
    assert set(CARTPOLE_TASKS) == {task for domain, task in suite.ALL_TASKS if domain == "cartpole"}


@pytest.mark.parametrize("domain, task", BATCHED_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, domain, task):
    assert _differences(suite, domain, task) == []


def test_flat_observations_are_dm_controls(suite):
    assert (
        _differences(suite, "cartpole", "swingup", environment_kwargs={"flat_observation": True})
        == []
    )


def test_a_reward_one_ulp_off_is_found(suite, monkeypatch):
    original = cartpole.BatchBalance.get_reward
    monkeypatch.setattr(
        cartpole.BatchBalance, "get_reward", lambda self: np.nextafter(original(self), np.inf)
    )
    found = _differences(suite, "cartpole", "swingup")
    assert found and all(difference.endswith("reward") for difference in found)


def test_unknown_names_are_told_the_closest_ones(suite):
    with pytest.raises(ValueError, match=r"domain_name: 'cartpol' .* did you mean 'cartpole'"):
        suite_batch.load("cartpol", "swingup", 2)
    with pytest.raises(
        ValueError, match=r"task_name: .* no task 'swingupp'; did you mean 'swingup'"
    ):
        suite_batch.load("cartpole", "swingupp", 2)


def test_a_task_without_array_code_is_named(suite):
    with pytest.raises(NotImplementedError, match=r"walker-walk \(PlanarWalker\): no array code"):
        suite_batch.load("walker", "walk", 2)


def test_a_seed_in_task_kwargs_is_refused_for_seed_or_random_states(suite):
    with pytest.raises(ValueError, match=r"task_kwargs: 'random' seeds one environment"):
        suite_batch.load("cartpole", "swingup", 2, task_kwargs={"random": 1})


def test_a_bad_number_of_worlds_is_named(suite):
    with pytest.raises(ValueError, match=r"num_envs: expected an integer >= 1, got 0"):
        suite_batch.load("cartpole", "swingup", 0)
