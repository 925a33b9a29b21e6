"""The batched suite through Gymnasium: `make_vec` of a Shimmy-style id gives the batch,
world i being `suite.load(..., task_kwargs={"random": seed + i})`."""

import numpy as np
import pytest
from episodes import needs_suite

pytestmark = needs_suite
gymnasium = pytest.importorskip(
    "gymnasium", reason="needs Gymnasium (CI's conformance venv has it; pip install gymnasium)"
)

ID = "dm_control/cartpole-swingup-v0"
SEED = 7
NUM_ENVS = 3
STEPS = 6


@pytest.fixture(scope="module")
def registered(suite):
    import suite_batch.gym  # noqa: F401  (registers the ids)


def _cpu_envs(suite, **task_kwargs):
    return [
        suite.load("cartpole", "swingup", task_kwargs={"random": SEED + i, **task_kwargs})
        for i in range(NUM_ENVS)
    ]


def test_make_vec_picks_the_batch_and_world_i_is_seed_plus_i(suite, registered):
    from composer.batch.gym import BatchVectorEnv

    envs = gymnasium.make_vec(ID, num_envs=NUM_ENVS)
    assert isinstance(envs, BatchVectorEnv)
    assert envs.single_action_space.shape == (1,)
    cpus = _cpu_envs(suite)
    observations, _ = envs.reset(seed=SEED)
    expected = [cpu.reset().observation for cpu in cpus]
    actions = np.random.RandomState(0).uniform(-1, 1, (STEPS, NUM_ENVS, 1))
    for t in range(STEPS + 1):
        for world, cpu_observation in enumerate(expected):
            for key, value in cpu_observation.items():
                np.testing.assert_array_equal(observations[key][world], value, f"{t} {key}")
        if t == STEPS:
            break
        observations, rewards, terminations, truncations, _ = envs.step(actions[t])
        cpu_steps = [cpu.step(action) for cpu, action in zip(cpus, actions[t])]
        assert rewards.tolist() == [step.reward for step in cpu_steps]
        assert not terminations.any() and not truncations.any()
        expected = [step.observation for step in cpu_steps]
    envs.close()


def test_the_suites_time_limit_truncates_and_same_step_resets(suite, registered):
    from gymnasium.vector import AutoresetMode

    limit = {"time_limit": 0.055}  # 5 control steps of 0.01 s, a little over
    envs = gymnasium.make_vec(
        ID, num_envs=NUM_ENVS, task_kwargs=limit, autoreset_mode=AutoresetMode.SAME_STEP
    )
    assert envs.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
    cpus = _cpu_envs(suite, **limit)
    envs.reset(seed=SEED)
    for cpu in cpus:
        cpu.reset()
    zeros = np.zeros((NUM_ENVS, 1))
    for t in range(6):
        observations, _, terminations, truncations, infos = envs.step(zeros)
        cpu_steps = [cpu.step(action) for cpu, action in zip(cpus, zeros)]
        assert truncations.tolist() == [step.last() for step in cpu_steps], t
        assert not terminations.any()
    assert truncations.all() and infos["_final_obs"].all()
    for world, (cpu, step) in enumerate(zip(cpus, cpu_steps)):
        np.testing.assert_array_equal(
            infos["final_obs"]["position"][world], step.observation["position"]
        )
        np.testing.assert_array_equal(
            observations["position"][world], cpu.reset().observation["position"]
        )
    envs.close()


def test_make_gives_one_suite_env_seeded_as_dm_controls(suite, registered):
    env = gymnasium.make(ID)
    observation, _ = env.reset(seed=SEED)
    expected = _cpu_envs(suite)[0].reset().observation
    for key, value in expected.items():
        np.testing.assert_array_equal(observation[key], value)
    env.close()
