"""ThreadedVectorEnv: batching, Gymnasium's autoreset modes, seeding, errors and closing."""

import threading

import gymnasium
import numpy as np
import pytest
from gym_scene import CounterEnv, slider_environment
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import manipulation
from composer.gym import GymnasiumEnv, SubEnvironmentError, ThreadedVectorEnv


def _counters(lengths, **kwargs):
    return [lambda length=length: CounterEnv(length, **kwargs) for length in lengths]


def _obs(observations):
    return observations[:, 0].tolist()


def _worker_threads(ignore=()):
    """The live worker threads, less those in `ignore` (left by other tests)."""
    return [
        t
        for t in threading.enumerate()
        if t.name.startswith("ThreadedVectorEnv") and t not in ignore
    ]


class _ThreadRecorder(gymnasium.Env):
    """Records the thread of each call: built, reset, stepped, rendered and closed."""

    observation_space = gymnasium.spaces.Box(-1.0, 1.0, (1,))
    action_space = gymnasium.spaces.Box(-1.0, 1.0, (1,))
    render_mode = "rgb_array"

    def __init__(self):
        self.threads = [threading.get_ident()]

    def reset(self, *, seed=None, options=None):
        self.threads.append(threading.get_ident())
        return np.zeros(1, dtype=np.float32), {}

    def step(self, action):
        self.threads.append(threading.get_ident())
        return np.zeros(1, dtype=np.float32), 0.0, False, False, {}

    def render(self):
        self.threads.append(threading.get_ident())

    def close(self):
        self.threads.append(threading.get_ident())


def test_each_sub_env_lives_on_one_thread_and_the_callers_share_on_the_caller():
    envs = ThreadedVectorEnv([_ThreadRecorder] * 4, num_threads=2)
    envs.reset(seed=0)
    for _ in range(3):
        envs.step(np.zeros((4, 1)))
    envs.reset(options={"reset_mask": np.array([False, True, False, False])})
    envs.render()
    sub_envs = envs.envs
    envs.close()
    threads = [set(env.threads) for env in sub_envs]
    assert [len(env.threads) for env in sub_envs] == [7, 8, 7, 7]
    assert threads[0] == threads[2] == {threading.get_ident()}
    assert threads[1] == threads[3] != threads[0]
    assert len(threads[1]) == 1


def test_is_a_gymnasium_vector_env_with_batched_spaces():
    envs = ThreadedVectorEnv(_counters([3, 3, 3]), num_threads=2)
    assert isinstance(envs, gymnasium.vector.VectorEnv)
    assert envs.num_envs == 3
    assert envs.observation_space.shape == (3, 1)
    assert envs.action_space.shape == (3, 1)
    assert envs.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    envs.close()


def test_default_thread_count_is_one_per_core_at_most_one_per_env(monkeypatch):
    monkeypatch.setattr("os.cpu_count", lambda: 3)
    envs = ThreadedVectorEnv(_counters([2] * 5))
    assert envs.num_threads == 3
    envs.close()
    envs = ThreadedVectorEnv(_counters([2] * 2))
    assert envs.num_threads == 2
    envs.close()


def test_next_step_autoreset_resets_on_the_step_after_the_end():
    envs = ThreadedVectorEnv(_counters([1, 2]), num_threads=2)
    observations, _ = envs.reset(seed=[0, 1])
    assert _obs(observations) == [0, 100]
    observations, rewards, terminated, truncated, _ = envs.step(np.zeros((2, 1)))
    assert _obs(observations) == [1, 101]
    assert terminated.tolist() == [True, False]
    # Sub-env 0 is reset (its action ignored): reset observation, reward 0, not done.
    observations, rewards, terminated, truncated, infos = envs.step(np.zeros((2, 1)))
    assert _obs(observations) == [10, 102]
    assert rewards.tolist() == [0.0, 2.0]
    assert terminated.tolist() == [False, True]
    assert infos["_reset"].tolist() == [True, False]
    envs.close()


def test_same_step_autoreset_returns_the_reset_observation_and_the_final_one_in_info():
    envs = ThreadedVectorEnv(_counters([1, 2]), 2, autoreset_mode=AutoresetMode.SAME_STEP)
    envs.reset(seed=[0, 1])
    observations, rewards, terminated, truncated, infos = envs.step(np.zeros((2, 1)))
    assert _obs(observations) == [10, 101]
    assert rewards.tolist() == [1.0, 1.0]
    assert terminated.tolist() == [True, False]
    assert infos["_final_obs"].tolist() == [True, False]
    assert infos["final_obs"][0].tolist() == [1.0]
    assert infos["final_info"]["step"][0] == 1
    observations, *_ = envs.step(np.zeros((2, 1)))
    # Both episodes end again (lengths 1 and 2) and are reset in the same step.
    assert _obs(observations) == [20, 110]
    envs.close()


def test_disabled_autoreset_needs_a_masked_reset_before_stepping_again():
    envs = ThreadedVectorEnv(_counters([1, 3], truncate=True), 2, autoreset_mode="Disabled")
    envs.reset(seed=[0, 1])
    _, _, terminated, truncated, _ = envs.step(np.zeros((2, 1)))
    assert truncated.tolist() == [True, False]
    with pytest.raises(RuntimeError, match=r"sub-environments \[0\] ended"):
        envs.step(np.zeros((2, 1)))
    observations, infos = envs.reset(options={"reset_mask": np.array([True, False])})
    assert _obs(observations) == [10, 101]
    assert infos["_reset"].tolist() == [True, False]
    observations, *_ = envs.step(np.zeros((2, 1)))
    assert _obs(observations) == [11, 102]
    envs.close()


def _assert_steps_match(ours, reference, mode, action, assert_observations) -> None:
    """Steps both vector envs 7 times with `action` (resetting the finished sub-envs
    first where autoreset is DISABLED) and asserts the same results at each step."""
    for _ in range(7):
        if mode is AutoresetMode.DISABLED:
            done = reference._terminations | reference._truncations
            if done.any():
                expected = reference.reset(options={"reset_mask": done.copy()})
                got = ours.reset(options={"reset_mask": done.copy()})
                assert_observations(got[0], expected[0])
        got, expected = ours.step(action), reference.step(action)
        assert_observations(got[0], expected[0])
        for mine, theirs in zip(got[1:4], expected[1:4]):
            np.testing.assert_array_equal(mine, theirs)
        assert got[4].keys() == expected[4].keys()
        if "final_obs" in expected[4]:
            np.testing.assert_array_equal(got[4]["_final_obs"], expected[4]["_final_obs"])
            for i in np.flatnonzero(expected[4]["_final_obs"]):
                assert_observations(got[4]["final_obs"][i], expected[4]["final_obs"][i])


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_every_autoreset_mode_matches_gymnasiums_sync_vector_env(mode):
    lengths = [1, 2, 3, 2]
    ours = ThreadedVectorEnv(_counters(lengths), 2, autoreset_mode=mode)
    reference = SyncVectorEnv(_counters(lengths), autoreset_mode=mode)
    for envs in (ours, reference):
        envs.reset(seed=5)
    _assert_steps_match(ours, reference, mode, np.zeros((4, 1)), np.testing.assert_array_equal)
    ours.close()


def _sliders(lengths):
    return [lambda n=n: GymnasiumEnv(slider_environment(end_after_steps=n)) for n in lengths]


def _assert_same_observations(got, expected):
    assert got.keys() == expected.keys()
    for key in expected:
        np.testing.assert_array_equal(got[key], expected[key], err_msg=key)


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_gymnasium_env_sub_envs_writing_into_their_rows_match_sync_vector_env(mode):
    # Each GymnasiumEnv writes its observations into its row of the batch; SyncVectorEnv
    # copies new ones in. Episodes of 1 to 3 steps cross every autoreset path.
    lengths = [1, 3, 2, 2]
    ours = ThreadedVectorEnv(_sliders(lengths), 2, autoreset_mode=mode, copy=False)
    reference = SyncVectorEnv(_sliders(lengths), autoreset_mode=mode)
    _assert_same_observations(ours.reset(seed=5)[0], reference.reset(seed=5)[0])
    action = np.full((4, 1), 0.5)
    _assert_steps_match(ours, reference, mode, action, _assert_same_observations)
    ours.close()


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_shards_of_unequal_size_match_a_loop_and_wake_each_worker_once_per_step(mode):
    # 7 sub-environments on 3 threads: the caller steps 0, 3, 6 and each worker two
    # or three, all in one wake-up per step; every output is the loop's.
    lengths = [1, 3, 2, 2, 4, 1, 3]
    ours = ThreadedVectorEnv(_sliders(lengths), 3, autoreset_mode=mode)
    reference = SyncVectorEnv(_sliders(lengths), autoreset_mode=mode)
    _assert_same_observations(ours.reset(seed=2)[0], reference.reset(seed=2)[0])
    actions = np.linspace(-1.0, 1.0, 7)[:, None]
    _assert_steps_match(ours, reference, mode, actions, _assert_same_observations)
    woken = []
    for _ in range(5):
        if mode is AutoresetMode.DISABLED:
            ours.reset()
        before = ours._pool.hand_offs
        ours.step(actions)
        woken.append(ours._pool.hand_offs - before)
    assert woken == [2] * 5
    ours.close()


class _InfoEnv(gymnasium.Env):
    """Returns infos of every kind Gymnasium batches: numbers of each type (and one key
    whose type differs between sub-environments), arrays, objects, nested dicts, keys
    that only some sub-environments have, and a key that is another key's mask name."""

    observation_space = gymnasium.spaces.Box(-1.0, 1.0, (1,))
    action_space = gymnasium.spaces.Box(-1.0, 1.0, (1,))

    def __init__(self, index):
        self.index = index

    def reset(self, *, seed=None, options=None):
        return np.zeros(1, dtype=np.float32), {}

    def step(self, action):
        info = {"discount": 0.5 * self.index, "pose": np.full(3, self.index)}
        info["flag"] = self.index % 2 == 1
        info["scale"] = np.float32(self.index / 3)
        # An int column from sub-environment 0, which the others' floats are cast into.
        info["mixed"] = self.index if self.index % 2 == 0 else self.index + 0.5
        info["seen"] = 2.0
        info["_seen"] = self.index  # written into the mask of "seen", as Gymnasium does
        if self.index % 2:
            info["odd"] = {"label": f"env {self.index}", "count": self.index}
        if self.index >= 2:
            info["late"] = self.index
        return np.zeros(1, dtype=np.float32), 0.0, False, False, info


def _assert_same_infos(got, expected):
    assert list(got) == list(expected)
    for key, value in expected.items():
        if isinstance(value, dict):
            _assert_same_infos(got[key], value)
        else:
            assert got[key].dtype == value.dtype, key
            np.testing.assert_array_equal(got[key], value)


def test_infos_are_batched_as_gymnasiums_sync_vector_env_batches_them():
    fns = [lambda i=i: _InfoEnv(i) for i in range(4)]
    ours, reference = ThreadedVectorEnv(fns, 2), SyncVectorEnv(fns)
    for envs in (ours, reference):
        envs.reset(seed=0)
    for _ in range(2):
        _assert_same_infos(ours.step(np.zeros((4, 1)))[4], reference.step(np.zeros((4, 1)))[4])
    ours.close()


@pytest.mark.parametrize("rows", [2, 4])
def test_actions_for_more_or_fewer_sub_envs_are_rejected_and_nothing_steps(rows):
    envs = ThreadedVectorEnv(_counters([5, 5, 5]), 2)
    envs.reset(seed=0)
    expected = rf"actions: expected one per sub-environment \(3\), got {rows}"
    with pytest.raises(ValueError, match=expected):
        envs.step(np.zeros((rows, 1)))
    observations = envs.step(np.zeros((3, 1)))[0]
    assert _obs(observations) == [1, 101, 201]  # the first step each one took
    envs.close()


def test_each_sub_env_is_seeded_with_seed_plus_its_index():
    envs = ThreadedVectorEnv(
        [lambda: GymnasiumEnv(manipulation.load("reach_site_features"))] * 3, num_threads=2
    )
    observations, _ = envs.reset(seed=11)
    for i in range(3):
        single, _ = GymnasiumEnv(manipulation.load("reach_site_features")).reset(seed=11 + i)
        for name, value in single.items():
            np.testing.assert_array_equal(observations[name][i], value)
    envs.close()


def test_seed_list_of_the_wrong_length_is_rejected():
    envs = ThreadedVectorEnv(_counters([2, 2]), 2)
    with pytest.raises(ValueError, match="expected None, an int or 2 seeds"):
        envs.reset(seed=[1, 2, 3])
    envs.close()


def test_observations_are_copies_unless_copy_is_false():
    envs = ThreadedVectorEnv(_counters([5, 5]), 2)
    first, _ = envs.reset(seed=0)
    envs.step(np.zeros((2, 1)))
    assert _obs(first) == [0, 100]
    envs.close()
    envs = ThreadedVectorEnv(_counters([5, 5]), 2, copy=False)
    first, _ = envs.reset(seed=0)
    second, *_ = envs.step(np.zeros((2, 1)))
    assert second is first
    envs.close()


def test_an_exception_in_a_sub_env_names_its_index_and_does_not_hang():
    earlier = _worker_threads()
    fns = _counters([5, 5, 5])
    fns[2] = lambda: CounterEnv(5, fail_at_step=2)
    envs = ThreadedVectorEnv(fns, num_threads=2)
    envs.reset(seed=0)
    envs.step(np.zeros((3, 1)))
    with pytest.raises(SubEnvironmentError, match="sub-environment 2 raised ValueError") as info:
        envs.step(np.zeros((3, 1)))
    assert info.value.index == 2
    assert isinstance(info.value.__cause__, ValueError)
    envs.close()
    assert _worker_threads(earlier) == []


def test_an_exception_while_building_a_sub_env_names_its_index_and_stops_the_threads():
    earlier = _worker_threads()

    def broken():
        raise OSError("no such model")

    with pytest.raises(SubEnvironmentError, match="sub-environment 1 raised OSError"):
        ThreadedVectorEnv([_counters([2])[0], broken], num_threads=2)
    assert _worker_threads(earlier) == []


def test_close_closes_the_sub_envs_and_joins_the_threads():
    earlier = _worker_threads()
    before = threading.active_count()
    envs = ThreadedVectorEnv(
        [lambda: GymnasiumEnv(manipulation.load("reach_site_features"))] * 2, num_threads=2
    )
    # Two threads step the sub-environments: this one and one worker.
    assert len(_worker_threads(earlier)) == 1
    sub_envs = envs.envs
    envs.close()
    assert envs.closed
    assert _worker_threads(earlier) == []
    assert threading.active_count() == before
    assert all(env.dm_env.physics is None for env in sub_envs)
    closed = "this ThreadedVectorEnv is closed"
    for call in (lambda: envs.step(np.zeros((2, 9))), envs.reset, envs.render):
        with pytest.raises(gymnasium.error.ClosedEnvironmentError, match=closed):
            call()
    with pytest.raises(gymnasium.error.ClosedEnvironmentError, match=closed):
        envs.call("render")
    with pytest.raises(gymnasium.error.ClosedEnvironmentError, match=closed):
        envs.set_attr("render_mode", None)


def test_sub_envs_with_different_spaces_are_rejected():
    earlier = _worker_threads()
    fns = [lambda: CounterEnv(2), lambda: GymnasiumEnv(manipulation.load("reach_site_features"))]
    with pytest.raises(ValueError, match="sub-environment 1: observation space"):
        ThreadedVectorEnv(fns, num_threads=1)
    assert _worker_threads(earlier) == []


def test_call_get_attr_set_attr_and_render_reach_every_sub_env():
    envs = ThreadedVectorEnv(
        [
            lambda: GymnasiumEnv(
                manipulation.load("reach_site_features"),
                render_mode="rgb_array",
                width=32,
                height=24,
            )
        ]
        * 2,
        num_threads=2,
    )
    envs.reset(seed=0)
    assert [frame.shape for frame in envs.render()] == [(24, 32, 3)] * 2
    assert envs.get_attr("render_mode") == ("rgb_array", "rgb_array")
    envs.set_attr("marker", [1, 2])
    assert envs.get_attr("marker") == (1, 2)
    assert envs.call("render")[0].shape == (24, 32, 3)
    envs.close()


def _reset_with_seed(env, seed):
    """CounterEnv's first observation after a reset with `seed` (100 * seed), and its length."""
    return env.reset(seed=seed)[0][0], env.get_wrapper_attr("_length")


def test_apply_runs_on_the_chosen_sub_envs_only_in_the_order_given():
    envs = ThreadedVectorEnv(_counters([5, 6, 7]), num_threads=2)
    envs.reset(seed=0)
    assert envs.apply(_reset_with_seed, 4, indices=[2, 0]) == ((400.0, 7), (400.0, 5))
    observations, *_ = envs.step(np.zeros((3, 1)))
    assert _obs(observations) == [401.0, 101.0, 401.0]
    assert envs.apply(_reset_with_seed, 9) == ((900.0, 5), (900.0, 6), (900.0, 7))
    envs.close()


@pytest.mark.parametrize("indices", [[3], [-1], [0, 0], [True], ["1"]])
def test_apply_rejects_bad_indices_naming_them(indices):
    envs = ThreadedVectorEnv(_counters([5, 5, 5]), num_threads=1)
    with pytest.raises(ValueError, match=r"indices: expected distinct sub-environment indices"):
        envs.apply(_reset_with_seed, 0, indices=indices)
    envs.close()


def test_invalid_thread_count_is_rejected_naming_the_argument():
    with pytest.raises(ValueError, match="num_threads: expected an integer >= 1 or None, got 0"):
        ThreadedVectorEnv(_counters([2]), num_threads=0)


def test_vision_sub_envs_render_their_cameras_on_worker_threads():
    envs = ThreadedVectorEnv(
        [lambda: GymnasiumEnv(manipulation.load("reach_site_vision"))] * 2, num_threads=2
    )
    observations, _ = envs.reset(seed=0)
    observations, *_ = envs.step(np.zeros((2, 9)))
    images = observations["front_close"]
    assert images.shape == (2, 1, 84, 84, 3)
    assert images.dtype == np.uint8
    assert images.std() > 0  # a picture of the scene, not a blank buffer
    envs.close()


def test_vision_frames_from_unequal_shards_equal_a_loops_and_render_in_one_wake_up():
    # 3 vision sub-environments on 2 threads (the caller renders 0 and 2, the worker 1),
    # each rendering its cameras (observations) and `render()` with the GL context it
    # made on its own thread.
    def make():
        return GymnasiumEnv(
            manipulation.load("reach_site_vision"), render_mode="rgb_array", width=64, height=48
        )

    envs = ThreadedVectorEnv([make] * 3, num_threads=2)
    loop = [make() for _ in range(3)]
    actions = np.random.default_rng(1).uniform(-0.5, 0.5, (2, 3, 9)).astype(np.float32)
    observations, _ = envs.reset(seed=7)
    expected = [env.reset(seed=7 + i)[0]["front_close"] for i, env in enumerate(loop)]
    np.testing.assert_array_equal(observations["front_close"], np.stack(expected))
    for step_actions in actions:
        before = envs._pool.hand_offs
        observations, *_ = envs.step(step_actions)
        assert envs._pool.hand_offs - before == 1
        expected = [env.step(a)[0]["front_close"] for env, a in zip(loop, step_actions)]
        np.testing.assert_array_equal(observations["front_close"], np.stack(expected))
    assert observations["front_close"].std() > 0  # a picture, not a blank buffer
    frames = envs.render()
    for frame, env in zip(frames, loop):
        np.testing.assert_array_equal(frame, env.render())
    assert frames[0].shape == (48, 64, 3) and frames[0].std() > 0
    envs.close()
    for env in loop:
        env.close()
