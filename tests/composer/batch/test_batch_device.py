"""The device-first batch: masked resets leave the other worlds alone, SAME_STEP autoreset,
no device-to-host copy at a step, initial states from producers (threads or processes, the
same states), reuse of states counted, and the default device.

The batches are built on the default device: Warp's CPU device here, cuda:0 where Warp sees
a GPU (benchmarks/gpu_check.sh runs these tests there)."""

import re
import warnings

import numpy as np
import pytest

from composer.batch import BatchEnvironment
from manipulation import batch as manipulation_batch
from manipulation.tasks import observation_settings
from manipulation.tasks.reach import Reach

pytestmark = pytest.mark.warp
wp = pytest.importorskip("warp", reason="needs MuJoCo Warp: pip install -e '.[warp]'")

NUM_ENVS = 4
NAME = "reach_site_features"
CONTROL_TIMESTEP = 0.04


def _actions(env, steps, seed=0):
    spec = env.action_spec()
    rng = np.random.default_rng(seed)
    return rng.uniform(spec.minimum, spec.maximum, (steps, env.num_envs, *spec.shape))


class _EndsAt(manipulation_batch.BatchReach):
    """Reach whose world i ends its episodes after limits[i] control steps (simulated time)."""

    def __init__(self, limits):
        task = Reach(observation_settings.FEATURES)
        super().__init__(task)
        self._end_times = np.asarray(limits) * task.control_timestep - 0.5 * task.physics_timestep

    def should_terminate_episode(self, physics):
        return physics.data.time >= self._end_times


def test_a_world_that_resets_leaves_the_other_worlds_bit_for_bit_as_they_were():
    never = 10**6
    resetting = BatchEnvironment(_EndsAt([2, never, never, never]), NUM_ENVS, random_state=9)
    steady = BatchEnvironment(_EndsAt([never] * 4), NUM_ENVS, random_state=9)
    resetting.reset(), steady.reset()
    restarted = False
    for action in _actions(steady, 6):
        a, b = resetting.step(action), steady.step(action)
        restarted |= bool(a.first()[0])
        for key, value in b.observation.items():
            np.testing.assert_array_equal(a.observation[key][1:], value[1:], err_msg=key)
        np.testing.assert_array_equal(a.reward[1:], b.reward[1:])
    assert restarted  # world 0 did start a new episode in between


def test_same_step_returns_last_with_the_next_episodes_first_observation():
    kwargs = dict(seed=4, time_limit=3 * CONTROL_TIMESTEP)
    next_step = manipulation_batch.load(NAME, 2, **kwargs)
    same_step = manipulation_batch.load(NAME, 2, autoreset_mode="same_step", **kwargs)
    next_step.reset(), same_step.reset()
    actions = _actions(same_step, 4)
    for action in actions[:2]:
        next_step.step(action), same_step.step(action)
    ended_next, ended_same = next_step.step(actions[2]), same_step.step(actions[2])
    np.testing.assert_array_equal(ended_same.last(), [True, True])
    np.testing.assert_array_equal(ended_same.reward, ended_next.reward)
    for key, value in ended_next.observation.items():
        np.testing.assert_array_equal(same_step.final_observation[key], value, err_msg=key)
    # NEXT_STEP spends a step to start the next episode; SAME_STEP already shows it.
    first = next_step.step(actions[3])
    np.testing.assert_array_equal(first.first(), [True, True])
    for key, value in first.observation.items():
        np.testing.assert_array_equal(ended_same.observation[key], value, err_msg=key)
    assert same_step.step(actions[3]).mid().all()


class _TransferCounter:
    """Counts the calls that copy a Warp array or a tensor to the host."""

    def __init__(self, monkeypatch):
        self.count = 0
        originals = {(wp.array, "numpy"): wp.array.numpy, (wp.array, "list"): wp.array.list}
        try:
            import torch
        except ImportError:
            torch = None
        if torch is not None:
            for name in ("cpu", "numpy", "item", "tolist", "__bool__", "__int__", "__float__"):
                originals[(torch.Tensor, name)] = getattr(torch.Tensor, name)
        for (owner, name), original in originals.items():
            monkeypatch.setattr(owner, name, self._counted(original))

    def _counted(self, original):
        def counted(*args, **kwargs):
            self.count += 1
            return original(*args, **kwargs)

        return counted


@pytest.mark.parametrize("array_type", ["warp", "torch", "jax"])
def test_a_step_copies_nothing_to_the_host_but_the_refill_read(array_type, monkeypatch):
    pytest.importorskip("torch", reason="torch is optional: pip install torch==2.13.0")
    if array_type == "jax":
        pytest.importorskip("jax", reason="JAX is optional and not installed (out of CI)")
    refill_interval = 4
    env = manipulation_batch.load(
        NAME,
        NUM_ENVS,
        seed=0,
        device="warp-cpu",
        array_type=array_type,
        refill_interval=refill_interval,
        # Task code on torch, and device actions unchecked: what runs on CUDA, where
        # checking their values would read one integer per step.
        namespace="torch",
        check_action_values=False,
    )
    env.reset()
    actions = [env.hand_out(a.astype(np.float32)) for a in _actions(env, 2 * refill_interval)]
    env.step(actions[0])
    counter = _TransferCounter(monkeypatch)
    counts = []
    for action in actions[1:]:
        before = counter.count
        env.step(action)
        counts.append(counter.count - before)
    # Steps 2..8: the refills at steps 4 and 8 read the episode counters once each.
    assert counts == [0, 0, 1, 0, 0, 0, 1]


def test_processes_and_threads_make_the_same_initial_states():
    kwargs = dict(seed=21, time_limit=2 * CONTROL_TIMESTEP, refill_interval=1)
    threads = manipulation_batch.load(NAME, 3, **kwargs)
    processes = manipulation_batch.load(NAME, 3, state_workers=2, state_processes=True, **kwargs)
    try:
        steps_a, steps_b = [threads.reset()], [processes.reset()]
        for action in _actions(threads, 7):
            steps_a.append(threads.step(action))
            steps_b.append(processes.step(action))
        assert sum(int(s.first().sum()) for s in steps_a) > 3  # episodes did restart
        for a, b in zip(steps_a, steps_b):
            for key, value in a.observation.items():
                np.testing.assert_array_equal(b.observation[key], value, err_msg=key)
        assert processes.initial_state_stats().reused == 0
        # How far ahead the producers have drawn between resets depends on when their jobs
        # finish; a reset asks for each world's next slots_per_world episodes in both.
        threads.reset(), processes.reset()
        # Worker processes send generator states back; each world's generator has drawn
        # the same episodes as with threads.
        for a, b in zip(threads.random_states, processes.random_states):
            np.testing.assert_array_equal(b.get_state()[1], a.get_state()[1])
            assert b.randint(2**31) == a.randint(2**31)
    finally:
        threads.close(), processes.close()


def test_reused_initial_states_are_counted_and_warned_about():
    # One slot per world, refilled every 8 steps, episodes of 2 steps: the episodes that
    # start at steps 3 and 6 find only the state their world used before.
    env = manipulation_batch.load(
        NAME, 2, seed=1, time_limit=2 * CONTROL_TIMESTEP, slots_per_world=1
    )
    env.reset()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for action in _actions(env, 8):
            env.step(action)
    stats = env.initial_state_stats()
    assert stats.reused >= 2 * 2
    messages = [str(w.message) for w in caught if "used before" in str(w.message)]
    assert messages
    # A world starts an episode every 3 control steps (2 steps and the restart): 2 worlds
    # need 2/3 of a state per control step, counted here with the reset's first episodes.
    assert re.search(
        r"2 worlds whose episodes last 2\.\d control steps on average need 0\.[678]", messages[0]
    )


def test_a_step_from_another_thread_runs_torch_on_warps_stream():
    if not wp.is_cuda_available():
        pytest.skip("torch's per-thread stream matters on CUDA only; Warp sees no GPU")
    import threading

    import torch

    env = manipulation_batch.load(NAME, NUM_ENVS, seed=0)
    env.reset()
    streams = []

    def step():
        env.step(np.zeros((NUM_ENVS, *env.action_spec().shape)))
        streams.append(torch.cuda.current_stream())

    thread = threading.Thread(target=step)
    thread.start()
    thread.join()
    assert streams == [wp.stream_to_torch(wp.get_stream(env.physics.device))]
    env.close()


def test_unknown_autoreset_mode_is_refused_by_name():
    with pytest.raises(ValueError, match=r"autoreset_mode: expected one of .*got 'later'"):
        BatchEnvironment(Reach(observation_settings.FEATURES), 2, autoreset_mode="later")


def test_changing_what_reset_returned_changes_no_later_step():
    env = manipulation_batch.load(NAME, 2, seed=6, time_limit=CONTROL_TIMESTEP)
    first = env.reset()
    first.reward[...] = 7.0
    first.discount[...] = 7.0
    first.step_type[...] = 2
    actions = _actions(env, 2)
    env.step(actions[0])  # LAST: the one-step limit
    restarted = env.step(actions[1])  # FIRST, reward 0 and discount 1 by definition
    np.testing.assert_array_equal(restarted.step_type, [0, 0])
    np.testing.assert_array_equal(restarted.reward, [0.0, 0.0])
    np.testing.assert_array_equal(restarted.discount, [1.0, 1.0])
