"""ActionValidator: the checks every action goes through before it reaches the controls."""

import numpy as np
import pytest
from dm_env import specs

from composer.action_validation import ActionValidator


def test_finite_values_whose_sum_overflows_are_accepted():
    check = ActionValidator(specs.Array((2,), np.float64))
    np.testing.assert_array_equal(check([1e308, 1e308]), [1e308, 1e308])


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_value_among_large_ones_is_rejected(bad):
    check = ActionValidator(specs.Array((3,), np.float64))
    with pytest.raises(ValueError, match="non-finite"):
        check(np.array([1e308, bad, -1e308]))


def test_an_action_of_the_spec_dtype_is_returned_as_is():
    check = ActionValidator(specs.Array((2,), np.float64))
    action = np.array([0.1, 0.2])
    assert check(action) is action
