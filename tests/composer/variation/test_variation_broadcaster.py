"""Tests for composer.variation.variation_broadcaster."""

import numpy as np

from composer.variation import deterministic, distributions, variation_broadcaster


def test_all_proxies_see_the_same_value_each_round():
    broadcaster = variation_broadcaster.VariationBroadcaster(distributions.Uniform())
    proxies = [broadcaster.get_proxy() for _ in range(3)]
    random_state = np.random.RandomState(0)
    rounds = [[proxy(random_state=random_state) for proxy in proxies] for _ in range(4)]
    for values in rounds:
        assert values[0] == values[1] == values[2]
    assert len({values[0] for values in rounds}) == 4


def test_a_proxy_called_ahead_of_others_queues_values_for_them():
    broadcaster = variation_broadcaster.VariationBroadcaster(deterministic.Sequence([1, 2, 3]))
    first, second = broadcaster.get_proxy(), broadcaster.get_proxy()
    assert [first(), first()] == [1, 2]
    assert [second(), second(), second()] == [1, 2, 3]
    assert first() == 3


def test_proxies_work_inside_expressions():
    broadcaster = variation_broadcaster.VariationBroadcaster(deterministic.Sequence([1.0, 2.0]))
    doubled = broadcaster.get_proxy() * 2
    plain = broadcaster.get_proxy()
    assert (doubled(), plain()) == (2.0, 1.0)
