"""A diverging world of the batched suite ends its own episode; the others go on.

The same absurd applied force is written into world 1 of a batch and into world 1's
`suite.load` env: its accelerations become huge, and MuJoCo resets the state. dm_control's
env raises its `PhysicsError`; the batch ends world 1's episode (LAST, reward 0, discount
0, a warning naming it), and worlds 0 and 2 stay equal to their CPU envs.
"""

import logging

import numpy as np
import pytest
from episodes import needs_suite

import suite_batch

pytestmark = needs_suite

SEEDS = (3, 4, 5)
HUGE = 1e30  # a force whose qacc passes MuJoCo's mjMAXVAL (1e10): mj_checkAcc resets


@pytest.mark.parametrize("autoreset_mode", ["next_step", "same_step"])
def test_a_diverging_world_ends_its_own_episode(suite, caplog, autoreset_mode):
    from dm_control.rl.control import PhysicsError

    batch = suite_batch.load(
        "cartpole", "swingup", len(SEEDS), random_states=SEEDS, autoreset_mode=autoreset_mode
    )
    cpus = [suite.load("cartpole", "swingup", task_kwargs={"random": seed}) for seed in SEEDS]
    actions = np.random.RandomState(0).uniform(-1, 1, (5, len(SEEDS), 1))
    batch.reset()
    for cpu in cpus:
        cpu.reset()
    for t in range(5):
        if t == 2:
            batch.physics.data.qfrc_applied[1, 0] = HUGE
            cpus[1].physics.data.qfrc_applied[0] = HUGE
            with pytest.raises(PhysicsError):
                cpus[1].step(actions[t, 1])
        with caplog.at_level(logging.WARNING):
            step = batch.step(actions[t])
        for world in (0, 2):
            cpu_step = cpus[world].step(actions[t, world])
            assert step.reward[world] == cpu_step.reward
            for key, value in cpu_step.observation.items():
                np.testing.assert_array_equal(step.observation[key][world], value)
        if t == 2:
            assert step.step_type.tolist() == [1, 2, 1]  # MID, LAST, MID
            assert (step.reward[1], step.discount[1]) == (0.0, 0.0)
            assert batch.episode_ends().terminated.tolist() == [False, True, False]
            assert "world 1: " in caplog.text and "mjWARN_BADQACC" in caplog.text
        if t == 3:  # world 1 starts its next episode (at once under same_step)
            expected = [1, 0, 1] if autoreset_mode == "next_step" else [1, 1, 1]
            assert step.step_type.tolist() == expected
    batch.close()


def test_a_bad_autoreset_mode_is_named(suite):
    with pytest.raises(ValueError, match=r"autoreset_mode: expected one of .*got 'never'"):
        suite_batch.load("cartpole", "swingup", 2, autoreset_mode="never")
