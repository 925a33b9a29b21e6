"""composer.episode_end: terminated or truncated, and autoreset, the one rule of every adapter.

The rule on its own (scalars and arrays), then the adapters that apply it, each with one
episode that the task ends (discount 0: terminated) beside one that the time limit ends
(truncated), under both autoreset modes: `GymnasiumEnv`, `ThreadedVectorEnv` and the
batch's `BatchVectorEnv`.
"""

import numpy as np
import pytest
from composer_scene import ReachTask

import composer
from composer.episode_end import Autoreset, EpisodeEnds, episode_ends

CONTROL_STEP = 0.02  # ReachTask's control timestep


@pytest.mark.parametrize(
    "last, discount, expected",
    [
        (False, 1.0, (False, False)),
        (False, 0.0, (False, False)),  # only a LAST step ends an episode
        (True, 0.0, (True, False)),
        (True, 1.0, (False, True)),
        (True, 0.9, (False, True)),  # a time limit keeps the task's discount
        (True, np.float32(0.0), (True, False)),
    ],
)
def test_discount_zero_is_terminated_and_any_other_last_discount_truncated(
    last, discount, expected
):
    assert tuple(episode_ends(last, discount)) == expected


def test_the_rule_applies_elementwise_to_numpy_and_torch_arrays():
    last = [False, True, True, True]
    discount = [0.0, 0.0, 1.0, 0.5]
    expected = EpisodeEnds([False, True, False, False], [False, False, True, True])
    ends = episode_ends(np.array(last), np.array(discount, np.float32))
    assert ends.terminated.tolist() == expected.terminated
    assert ends.truncated.tolist() == expected.truncated
    torch = pytest.importorskip("torch", reason="torch is optional: pip install torch")
    ends = episode_ends(torch.tensor(last), torch.tensor(discount))
    assert ends.terminated.tolist() == expected.terminated
    assert ends.truncated.tolist() == expected.truncated


@pytest.mark.parametrize(
    "name, expected",
    [
        ("next_step", Autoreset.NEXT_STEP),
        ("same_step", Autoreset.SAME_STEP),
        ("NextStep", Autoreset.NEXT_STEP),
        ("SameStep", Autoreset.SAME_STEP),
        ("Disabled", Autoreset.DISABLED),
    ],
)
def test_autoreset_reads_our_names_and_gymnasiums_values(name, expected):
    assert Autoreset.of(name) is expected


def test_autoreset_reads_gymnasiums_autoreset_mode():
    vector = pytest.importorskip("gymnasium.vector", reason="needs the extra [gym]")
    assert [Autoreset.of(mode) for mode in vector.AutoresetMode] == [
        Autoreset.NEXT_STEP,
        Autoreset.SAME_STEP,
        Autoreset.DISABLED,
    ]
    assert [vector.AutoresetMode(m.gymnasium_value) for m in Autoreset] == list(
        vector.AutoresetMode
    )


@pytest.mark.parametrize(
    "mode, shown", [("sometimes", "'sometimes'"), (["next_step"], "['next_step']")]
)
def test_an_unknown_autoreset_mode_is_refused_naming_the_argument(mode, shown):
    with pytest.raises(ValueError) as raised:
        Autoreset.of(mode)
    assert str(raised.value) == (
        "autoreset_mode: expected one of ['next_step', 'same_step', 'disabled'] or a "
        f"Gymnasium AutoresetMode, got {shown}"
    )


@pytest.mark.parametrize(
    "mode, before, refused, after, over",
    [
        # An episode over before the step / ended by it: reset before stepping, refuse the
        # step, reset after stepping, still over afterwards.
        (Autoreset.NEXT_STEP, True, False, False, True),
        (Autoreset.SAME_STEP, False, False, True, False),
        (Autoreset.DISABLED, False, True, False, True),
    ],
)
def test_each_mode_resets_an_ended_episode_where_gymnasium_says(mode, before, refused, after, over):
    assert (mode.resets_before_step(True), mode.refuses_step(True)) == (before, refused)
    assert (mode.resets_after_step(True), mode.over_after_step(True)) == (after, over)
    # An episode that did not end is left alone by every mode.
    assert not any(
        (
            mode.resets_before_step(False),
            mode.refuses_step(False),
            mode.resets_after_step(False),
            mode.over_after_step(False),
        )
    )
    masks = mode.resets_before_step(np.array([True, False]))
    assert masks.tolist() == [before, False]


class _EndsAfterTwoSteps(ReachTask):
    """ReachTask whose task ends every episode after two control steps, with discount 0."""

    def initialize_episode(self, physics, random_state):
        super().initialize_episode(physics, random_state)
        self.steps = 0

    def after_step(self, physics, random_state):
        self.steps += 1

    def should_terminate_episode(self, physics):
        return self.steps >= 2

    def get_discount(self, physics):
        return 0.0 if self.steps >= 2 else 1.0


def _gymnasium_env(task_ends: bool):
    """A GymnasiumEnv whose episode the task ends at step 2 (discount 0), or else whose
    time limit ends it at step 3 (discount 1)."""
    from composer.gym import GymnasiumEnv

    task = _EndsAfterTwoSteps() if task_ends else ReachTask()
    return GymnasiumEnv(composer.Environment(task, time_limit=3 * CONTROL_STEP))


def test_gymnasium_env_task_end_is_terminated_and_time_limit_end_truncated():
    pytest.importorskip("gymnasium", reason="needs the extra [gym]")
    flags = {}
    for task_ends in (True, False):
        env = _gymnasium_env(task_ends)
        env.reset(seed=0)
        steps = [env.step(np.zeros(2)) for _ in range(3 - task_ends)]
        flags[task_ends] = [(terminated, truncated) for _, _, terminated, truncated, _ in steps]
        assert type(steps[-1][2]) is bool and type(steps[-1][3]) is bool
        assert steps[-1][4]["discount"] == (0.0 if task_ends else 1.0)
    assert flags[True] == [(False, False), (True, False)]
    assert flags[False] == [(False, False), (False, False), (False, True)]


def _sub_env_zero_alone():
    """Sub-environment 0 stepped on its own, seeded as the vector env seeds it: its
    episode's last observation and the next episode's first."""
    env = _gymnasium_env(True)
    env.reset(seed=0)
    env.step(np.zeros(2))
    last, *_ = env.step(np.zeros(2))
    first, _ = env.reset()
    return last, first


def _assert_rows_equal(batch, row, expected):
    for key, value in expected.items():
        np.testing.assert_array_equal(batch[key][row], value, err_msg=key)


#: (terminated, truncated) of the two sub-environments over three steps: the first's task
#: ends its episode at step 2, the second's time limit ends its own at step 3.
_TWO_ENDS = [
    ([False, False], [False, False]),
    ([True, False], [False, False]),
    ([False, False], [False, True]),
]


def _three_steps(envs, action: np.ndarray) -> list:
    """Resets `envs` (seed 0), takes three steps of `action`, closes it, asserts the
    `_TWO_ENDS` flags and returns the three steps' results."""
    try:
        envs.reset(seed=0)
        steps = [envs.step(action) for _ in range(3)]
    finally:
        envs.close()
    flags = [(terminated.tolist(), truncated.tolist()) for _, _, terminated, truncated, _ in steps]
    assert flags == _TWO_ENDS
    return steps


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_threaded_vector_env_ends_and_restarts_episodes_as_the_mode_says(mode):
    pytest.importorskip("gymnasium", reason="needs the extra [gym]")
    from composer.gym import ThreadedVectorEnv

    last, first = _sub_env_zero_alone()
    envs = ThreadedVectorEnv(
        [lambda: _gymnasium_env(True), lambda: _gymnasium_env(False)], 1, autoreset_mode=mode
    )
    steps = _three_steps(envs, np.zeros((2, 2)))
    ended, ended_infos = steps[1][0], steps[1][4]
    restarted, rewards = steps[2][0], steps[2][1]
    if mode == "NextStep":
        # Step 2 returns the last observation; step 3 restarts sub-environment 0, reward 0.
        _assert_rows_equal(ended, 0, last)
        _assert_rows_equal(restarted, 0, first)
        assert rewards[0] == 0.0
        assert "final_obs" not in ended_infos
    else:
        # Step 2 restarts sub-environment 0 at once; its last observation is in the infos,
        # and step 3 is an ordinary step (ReachTask's reward, minus a distance, is not 0).
        _assert_rows_equal(ended, 0, first)
        assert ended_infos["_final_obs"].tolist() == [True, False]
        for key, value in last.items():
            np.testing.assert_array_equal(ended_infos["final_obs"][0][key], value, err_msg=key)
        assert rewards[0] < 0.0


def _batch_with_two_ends(mode: str):
    """Two worlds of reach_site_features as a `BatchVectorEnv`: world 0's task ends its
    episodes after two control steps with discount 0, world 1's time limit after three."""
    pytest.importorskip("mujoco_warp", reason="needs MuJoCo Warp: pip install -e '.[warp]'")
    from composer.batch import BatchEnvironment
    from composer.batch.gym import BatchVectorEnv
    from manipulation import batch as manipulation_batch
    from manipulation.tasks import observation_settings
    from manipulation.tasks.reach import Reach

    class EndsWorldZero(manipulation_batch.BatchReach):
        def __init__(self):
            task = Reach(observation_settings.FEATURES)
            super().__init__(task)
            # Two control steps of simulated time (half a physics step short of it).
            self._end = 2 * task.control_timestep - 0.5 * task.physics_timestep

        def should_terminate_episode(self, physics):
            return (physics.data.time >= self._end) & (np.arange(2) == 0)

        def get_discount(self, physics):
            return np.where(self.should_terminate_episode(physics), 0.0, 1.0)

    control_timestep = Reach(observation_settings.FEATURES).control_timestep
    batch = BatchEnvironment(
        EndsWorldZero(),
        2,
        device="warp-cpu",
        random_state=0,
        time_limit=3 * control_timestep,
        autoreset_mode=mode,
    )
    return BatchVectorEnv(batch)


@pytest.mark.warp
@pytest.mark.parametrize("mode", ["next_step", "same_step"])
def test_warp_vector_env_ends_and_restarts_worlds_as_the_mode_says(mode):
    steps = _three_steps(_batch_with_two_ends(mode), np.zeros((2, 9)))
    np.testing.assert_array_equal(steps[1][4]["discount"], [0.0, 1.0])
    rewards = steps[2][1]
    if mode == "next_step":
        # Step 3 restarts world 0: its action ignored, reward 0.
        assert rewards[0] == 0.0
        assert "final_obs" not in steps[1][4]
    else:
        # Step 2 restarted world 0: its observation is the next episode's, its last one is
        # in the infos, and step 3 is an ordinary step (reach's reward is not 0 there).
        infos = steps[1][4]
        assert infos["_final_obs"].tolist() == [True, False]
        for key, value in infos["final_obs"].items():
            assert not np.array_equal(steps[1][0][key][0], value[0]), key
            np.testing.assert_array_equal(steps[1][0][key][1], value[1], err_msg=key)
        assert rewards[0] != 0.0
