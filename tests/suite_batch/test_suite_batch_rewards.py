"""`suite_batch.rewards.tolerance` equals dm_control's `rewards.tolerance` bit for bit, on
numbers and on arrays, for every sigmoid."""

import numpy as np
import pytest
from episodes import needs_suite

from suite_batch import rewards

pytestmark = needs_suite

SIGMOIDS = {
    "gaussian": (0.1, 0.5),
    "hyperbolic": (0.1, 0.5),
    "long_tail": (0.1, 0.5),
    "reciprocal": (0.1, 0.5),
    "cosine": (0.0, 0.1),
    "linear": (0.0, 0.1),
    "quadratic": (0.0, 0.1),
    "tanh_squared": (0.1, 0.5),
}
# Values from inside the bounds to beyond the margin, on both sides.
X = np.random.RandomState(0).uniform(-4.0, 4.0, 20_000)
CASES = [(sigmoid, value) for sigmoid, values in SIGMOIDS.items() for value in values]


@pytest.fixture(scope="module")
def dm_rewards(suite):
    from dm_control.utils import rewards as dm_rewards

    return dm_rewards


@pytest.mark.parametrize("sigmoid, value_at_margin", CASES)
def test_each_world_equals_dm_controls_tolerance_of_its_number(
    dm_rewards, sigmoid, value_at_margin
):
    arguments = dict(bounds=(-0.5, 0.25), margin=1.7, sigmoid=sigmoid)
    arguments["value_at_margin"] = value_at_margin
    expected = np.array([dm_rewards.tolerance(float(x), **arguments) for x in X])
    assert np.array_equal(rewards.tolerance(X, **arguments, scalar=True), expected)


@pytest.mark.parametrize("sigmoid, value_at_margin", CASES)
def test_each_world_equals_dm_controls_tolerance_of_its_array(dm_rewards, sigmoid, value_at_margin):
    arguments = dict(bounds=(-0.5, 0.25), margin=1.7, sigmoid=sigmoid)
    arguments["value_at_margin"] = value_at_margin
    rows = X.reshape(-1, 4)
    expected = np.stack([dm_rewards.tolerance(row, **arguments) for row in rows])
    assert np.array_equal(rewards.tolerance(rows, **arguments, scalar=False), expected)


def test_the_two_paths_differ_where_dm_controls_do(dm_rewards):
    # Guards the premise: were they equal, `scalar` would be needless.
    numbers = np.array([dm_rewards.tolerance(float(x), margin=2.0) for x in X])
    assert not np.array_equal(dm_rewards.tolerance(X, margin=2.0), numbers)
    assert not np.array_equal(rewards.tolerance(X, margin=2.0, scalar=False), numbers)


def test_no_margin_is_a_step(dm_rewards):
    assert np.array_equal(
        rewards.tolerance(X, bounds=(-1.0, 2.0), scalar=True),
        dm_rewards.tolerance(X, bounds=(-1.0, 2.0)),
    )


def test_bad_bounds_and_sigmoids_are_named():
    with pytest.raises(ValueError, match=r"bounds: lower bound 2.0 must be <= upper bound 1.0"):
        rewards.tolerance(X, bounds=(2.0, 1.0), scalar=True)
    with pytest.raises(ValueError, match=r"sigmoid: unknown sigmoid type 'square'"):
        rewards.tolerance(X, bounds=(0.0, 0.0), margin=1.0, sigmoid="square", scalar=True)
