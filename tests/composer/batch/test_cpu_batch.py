"""The CPU batch (`device="cpu"`, `mujoco.batch`): each world is its CPU environment, exactly.

World i of a batch built with `random_states=SEEDS` must equal `manipulation.load(name,
seed=SEEDS[i])` in every observation, reward, discount, step type, qpos and qvel, bit for
bit, across resets. The default run compares a short sample of every features task (the
vision tasks' are in test_cpu_batch_cameras.py); the `cpu_batch_episodes` marker runs two
and a half whole episodes of every task, in both autoreset modes.
"""

import builtins
import time

import numpy as np
import pytest

import composer
import manipulation
from composer import batch
from composer.batch import equivalence
from manipulation import batch as manipulation_batch
from manipulation.tasks import observation_settings, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.reach import Reach

pytest.importorskip("mujoco.batch", reason="the CPU batch needs MuJoCo >= 4 (mujoco.batch)")

SEEDS = (11, 12)
FEATURES = manipulation_batch.BATCHED_FEATURES
CONTROL_TIMESTEP = tc.CONTROL_TIMESTEP


def _first_difference(name, steps, time_limit, autoreset_mode="next_step"):
    """The first value in which a batch of `name` differs from its CPU environments, or
    None: every world equal at the reset and each of `steps` random steps."""
    batch_env = manipulation_batch.load(
        name,
        len(SEEDS),
        random_states=SEEDS,
        device="cpu",
        time_limit=time_limit,
        autoreset_mode=autoreset_mode,
    )
    cpu_envs = [
        composer.Environment(registry.build_task(name), time_limit=time_limit, random_state=s)
        for s in SEEDS
    ]
    spec = cpu_envs[0].action_spec()
    rng = np.random.RandomState(0)
    batch_step, cpu_steps = batch_env.reset(), [env.reset() for env in cpu_envs]
    firsts = 0
    for step in range(steps + 1):
        if step:
            action = rng.uniform(spec.minimum, spec.maximum, (len(SEEDS), *spec.shape))
            batch_step = batch_env.step(action)
            cpu_steps = []
            for env, world_action in zip(cpu_envs, action):
                time_step = env.step(world_action)
                if autoreset_mode == "same_step" and time_step.last():
                    time_step = time_step._replace(observation=env.reset().observation)
                cpu_steps.append(time_step)
            firsts += int(np.sum(batch_step.first() | batch_step.last()))
        for world, (env, cpu) in enumerate(zip(cpu_envs, cpu_steps)):
            where = f"world {world} at step {step}"
            for key, value in cpu.observation.items():
                if not np.array_equal(batch_step.observation[key][world], value):
                    return f"observation {key!r} of {where}"
            if int(batch_step.step_type[world]) != int(cpu.step_type):
                return f"step type of {where}"
            if (cpu.reward or 0.0) != batch_step.reward[world]:
                return f"reward of {where}: {batch_step.reward[world]!r} != {cpu.reward!r}"
            if (1.0 if cpu.discount is None else cpu.discount) != batch_step.discount[world]:
                return f"discount of {where}"
            for field in ("qpos", "qvel"):
                got = getattr(batch_env.physics.data, field)[world]
                if not np.array_equal(got, getattr(env.physics.data, field)):
                    return f"{field} of {where}"
    batch_env.close()
    assert firsts, "no episode ended or started in the compared steps"
    return None


@pytest.mark.parametrize("name", FEATURES)
def test_a_short_sample_of_every_features_task_equals_the_cpu_envs_bit_for_bit(name):
    # 0.3 s episodes: three control steps, then a reset, within the seven compared.
    assert _first_difference(name, steps=7, time_limit=3 * CONTROL_TIMESTEP) is None


@pytest.mark.parametrize("name", ["reach_site_features", "lift_brick_features"])
def test_same_step_autoreset_equals_the_cpu_envs_reset_at_once(name):
    difference = _first_difference(
        name, steps=7, time_limit=3 * CONTROL_TIMESTEP, autoreset_mode="same_step"
    )
    assert difference is None


@pytest.mark.cpu_batch_episodes
@pytest.mark.parametrize("autoreset_mode", ["next_step", "same_step"])
@pytest.mark.parametrize("name", manipulation_batch.BATCHED)
def test_whole_episodes_of_every_task_equal_the_cpu_envs(name, autoreset_mode):
    # Two and a half episodes: of 4 s (100 control steps) for the features tasks, of 1 s
    # (25 steps) for the vision tasks, whose frames render in software on CI's machines.
    episode_steps = 25 if name in manipulation_batch.BATCHED_VISION else 100
    difference = _first_difference(
        name,
        steps=episode_steps * 5 // 2,
        time_limit=episode_steps * CONTROL_TIMESTEP,
        autoreset_mode=autoreset_mode,
    )
    assert difference is None


def test_the_exact_equivalence_report_of_the_cpu_batch_passes_with_zero_bounds():
    report = equivalence.compare(
        lambda: Reach(observation_settings.FEATURES), num_envs=2, control_steps=5, device="cpu"
    )
    assert report.passed, report.first
    assert report.rounded_cpu_first is None
    assert set(report.worst.values()) == {0.0}


def test_the_exact_report_names_a_reward_one_ulp_off():
    class _OffByOneUlp(manipulation_batch.BatchReach):
        def get_reward(self, physics):
            reward = super().get_reward(physics)
            return np.nextafter(reward, np.inf)

    report = equivalence.compare(
        lambda: Reach(observation_settings.FEATURES),
        num_envs=2,
        control_steps=3,
        device="cpu",
        batch_task=_OffByOneUlp,
    )
    assert report.first is not None and report.first.quantity == "reward"


def test_the_physics_is_float64_on_mujoco_batch():
    env = manipulation_batch.load("reach_site_features", 2, seed=0, device="cpu")
    time_step = env.reset()
    assert env.physics.batch.nsim == 2
    assert env.physics.data.qpos.dtype == np.float64
    assert {value.dtype for value in time_step.observation.values()} == {np.dtype(np.float64)}
    assert env.step(np.zeros((2, 9))).reward.dtype == np.float64


def test_without_a_device_and_without_a_gpu_the_batch_is_the_cpu_batch():
    import warp as wp

    if wp.get_cuda_device_count():
        pytest.skip("Warp sees a CUDA device here; the default is cuda:0")
    env = batch.BatchEnvironment(Reach(observation_settings.FEATURES), 2)
    assert not env.physics.on_warp


def test_threads_are_checked_by_name():
    task = Reach(observation_settings.FEATURES)
    with pytest.raises(ValueError, match=r"threads: expected an integer >= 1, got 0"):
        batch.BatchEnvironment(task, 2, device="cpu", threads=0)
    with pytest.raises(ValueError, match=r"threads: 2 sets the CPU batch's C threads"):
        batch.BatchEnvironment(task, 2, device="warp-cpu", threads=2)
    env = batch.BatchEnvironment(task, 2, device="cpu", threads=1)
    assert env.physics.batch.nthread == 1


def test_an_unknown_device_names_the_choices():
    with pytest.raises(ValueError, match=r"device: expected 'cpu' \(mujoco.batch\), 'warp-cpu'"):
        batch.BatchEnvironment(Reach(observation_settings.FEATURES), 2, device="gpu")


def test_a_mujoco_without_mujoco_batch_is_told_what_to_do(monkeypatch):
    real_import = builtins.__import__

    def no_batch(name, globals=None, locals=None, fromlist=(), level=0):
        if name == "mujoco" and fromlist and "batch" in fromlist:
            raise ImportError("cannot import name 'batch' from 'mujoco'")
        return real_import(name, globals, locals, fromlist, level)

    monkeypatch.setattr(builtins, "__import__", no_batch)
    with pytest.raises(
        ImportError, match=r"mujoco.batch, which MuJoCo \S+ does not have.*warp-cpu"
    ):
        batch.BatchEnvironment(Reach(observation_settings.FEATURES), 2, device="cpu")


def test_a_forward_of_some_worlds_leaves_the_others_as_they_were():
    env = manipulation_batch.load("reach_site_features", 3, seed=0, device="cpu")
    env.reset()
    physics = env.physics
    before = physics.data.xpos.copy()
    qpos = physics.data.qpos.copy()
    qpos[:, 0] += 0.3
    physics.data.qpos[...] = qpos
    physics.forward(np.array([False, True, False]))
    after = physics.data.xpos
    np.testing.assert_array_equal(after[[0, 2]], before[[0, 2]])
    assert not np.array_equal(after[1], before[1])


def test_the_batch_loads_as_manipulation_load_does():
    # The same task, built by name: its CPU twin is `manipulation.load`.
    env = manipulation_batch.load("reach_duplo_features", 1, random_states=[5], device="cpu")
    cpu = manipulation.load("reach_duplo_features", seed=5)
    observation = env.reset().observation
    for key, value in cpu.reset().observation.items():
        np.testing.assert_array_equal(observation[key][0], value)


class _SlowReach(Reach):
    """Reach whose every episode start burns `BURN_SECONDS` of its thread's CPU time."""

    BURN_SECONDS = 0.02

    def initialize_episode(self, physics, random_state):
        super().initialize_episode(physics, random_state)
        end = time.thread_time() + self.BURN_SECONDS
        while time.thread_time() < end:
            pass


def test_initial_state_stats_count_the_producers_cpu_time():
    task = manipulation_batch.BatchReach(_SlowReach(observation_settings.FEATURES))
    env = batch.BatchEnvironment(task, 2, random_state=3, device="cpu", slots_per_world=2)
    process_cpu = time.process_time()
    env.reset()  # fills both slots of both worlds, waiting for them
    process_cpu = time.process_time() - process_cpu
    produced = env.initial_state_stats().producer_cpu_seconds
    env.close()
    # 4 states of at least BURN_SECONDS each, made within this process's CPU time.
    assert 4 * _SlowReach.BURN_SECONDS <= produced <= process_cpu


def test_the_cpu_batch_needs_no_extra_beyond_the_runtime_dependencies(fresh_python):
    # array-api-compat comes with [warp] and [test] only; without it the CPU batch computes
    # in NumPy's own namespace, with the same results.
    result = fresh_python(
        """
        import sys
        sys.modules["array_api_compat"] = None  # a plain `pip install` of the project
        import numpy as np
        import manipulation
        from manipulation import batch
        env = batch.load("lift_brick_features", 2, random_states=[5, 6], device="cpu")
        cpus = [manipulation.load("lift_brick_features", seed=s) for s in (5, 6)]
        step, cpu_steps = env.reset(), [cpu.reset() for cpu in cpus]
        actions = np.random.RandomState(0).uniform(-0.5, 0.5, (30, 2, 9))
        differences = 0
        for action in actions:
            for i, cpu_step in enumerate(cpu_steps):
                for key, value in cpu_step.observation.items():
                    differences += int(not np.array_equal(step.observation[key][i], value))
                if cpu_step.reward is not None:
                    differences += int(step.reward[i] != cpu_step.reward)
            step = env.step(action)
            cpu_steps = [cpu.step(a) for cpu, a in zip(cpus, action)]
        print(type(env.xp).__name__, env.xp.__name__, differences)
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["module", "numpy", "0"]
