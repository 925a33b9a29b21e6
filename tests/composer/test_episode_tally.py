"""EpisodeTally: steps and returns over episodes, rewards summed, None rewards ignored."""

import numpy as np

from composer.episode_tally import EpisodeTally


def test_tally_counts_steps_and_sums_rewards_per_episode():
    tally = EpisodeTally()
    tally.start_episode()
    for reward in (1.0, None, np.array([0.5, 0.25])):
        tally.add_step(reward)
    assert (tally.steps, tally.episode_steps, tally.episodes) == (3, 3, 1)
    assert tally.episode_return == 1.75 and tally.last_reward == 0.75
    tally.start_episode()
    tally.add_step(2.0)
    assert (tally.steps, tally.episode_steps, tally.episodes) == (4, 1, 2)
    assert tally.episode_return == 2.0


def test_none_reward_is_the_last_reward_and_adds_nothing():
    tally = EpisodeTally()
    tally.start_episode()
    tally.add_step(3.0)
    tally.add_step(None)
    assert tally.last_reward is None and tally.episode_return == 3.0
