"""What the batched suite's tests share: dm_control's suite (or a skip saying why) and the
world-for-world comparison of a batched task with `suite.load` envs seeded alike."""

import importlib.util

import numpy as np
import pytest

import suite_batch

#: World i of a batch is compared with `suite.load(..., task_kwargs={"random": SEEDS[i]})`.
SEEDS = (3, 11, 12345)
#: Control steps of a short episode: `differences`' default crosses two resets.
SHORT_EPISODE_STEPS = 25


def _has_suite() -> bool:
    try:
        return importlib.util.find_spec("dm_control.suite") is not None
    except ModuleNotFoundError:
        return False


#: Put on a module (`pytestmark = episodes.needs_suite`) whose tests need the suite.
needs_suite = pytest.mark.skipif(
    not _has_suite(),
    reason="needs dm_control's suite (pip install dm-control --no-deps scipy); CI runs these in "
    "the conformance harness's venv",
)


def short_time_limit(suite, domain: str, task: str) -> float:
    """A time limit of `SHORT_EPISODE_STEPS` control steps of the task (its default
    `n_sub_steps`), a little over so that rounding cannot end it a step early."""
    env = suite.load(domain, task)
    try:
        return (SHORT_EPISODE_STEPS + 0.5) * env.control_timestep()
    finally:
        env.close()


def _observation_differences(where: str, got: dict, world: int, expected: dict) -> list[str]:
    found = []
    if got.keys() != expected.keys():
        found.append(f"{where}: observation keys {list(got)}")
    for key, value in expected.items():
        if key not in got or not np.array_equal(got[key][world], value):
            found.append(f"{where}: observation {key!r}")
    return found


def differences(
    suite,
    domain: str,
    task: str,
    *,
    steps: int = 2 * SHORT_EPISODE_STEPS + 10,
    short: bool = True,
    environment_kwargs: dict | None = None,
    seeds: tuple[int, ...] = SEEDS,
    autoreset_mode: str = "next_step",
) -> list[str]:
    """Steps a batch of `domain`-`task` and the CPU envs seeded alike with the same random
    actions for `steps` control steps; returns every difference found, named by step, world
    and quantity (step type, reward, discount, each observation, `qpos`, `qvel`), and "no
    episode restarted" when no world started a second episode.

    `short`: episodes of `short_time_limit`; False: the task's own time limit. Under
    `autoreset_mode="same_step"`, a CPU env is reset right after its LAST step, whose
    observation is compared with the batch's `final_observation` and the reset's with the
    batch's observation of that step.
    """
    limit = {"time_limit": short_time_limit(suite, domain, task)} if short else {}
    batch = suite_batch.load(
        domain,
        task,
        len(seeds),
        task_kwargs=limit,
        environment_kwargs=environment_kwargs,
        random_states=seeds,
        threads=1,
        autoreset_mode=autoreset_mode,
    )
    same_step = autoreset_mode == "same_step"
    cpus = [
        suite.load(
            domain,
            task,
            task_kwargs={"random": seed, **limit},
            environment_kwargs=environment_kwargs,
        )
        for seed in seeds
    ]
    spec = cpus[0].action_spec()
    low = np.broadcast_to(np.nan_to_num(spec.minimum, neginf=-1.0), spec.shape)
    high = np.broadcast_to(np.nan_to_num(spec.maximum, posinf=1.0), spec.shape)
    actions = np.random.RandomState(0).uniform(low, high, (steps, len(seeds), *spec.shape))
    found, restarted = [], False
    step, cpu_steps = batch.reset(), [cpu.reset() for cpu in cpus]
    for t in range(steps + 1):
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
            observation = cpu_step.observation
            if same_step and cpu_step.last():
                found += _observation_differences(
                    f"{where} (final)", batch.final_observation, world, observation
                )
                observation = cpu.reset().observation
                restarted = True
            found += _observation_differences(where, step.observation, world, observation)
            for field in ("qpos", "qvel"):
                cpu_value = getattr(cpu.physics.data, field)
                if not np.array_equal(getattr(batch.physics.data, field)[world], cpu_value):
                    found.append(f"{where}: {field}")
        if t == steps:
            break
        step = batch.step(actions[t])
        cpu_steps = [cpu.step(action) for cpu, action in zip(cpus, actions[t])]
        restarted |= bool(step.first().any())
    batch.close()
    for cpu in cpus:
        cpu.close()
    return found + ([] if restarted else ["no episode restarted"])
