"""ActionValidator: the checks every action goes through before it reaches the controls."""

import numpy as np
import pytest
from dm_env import specs

from composer.action_validation import ActionValidator, action_validator


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


def test_a_list_of_specs_checks_one_action_per_agent():
    check = action_validator([specs.Array((2,), np.float64), specs.Array((1,), np.int32)])
    first, second = check([[0.1, 0.2], [3]])
    np.testing.assert_array_equal(first, [0.1, 0.2])
    assert second.dtype == np.int32


def test_a_dict_of_specs_checks_each_named_action():
    check = action_validator({"arm": specs.Array((2,), np.float64)})
    np.testing.assert_array_equal(check({"arm": (1, 2)})["arm"], [1.0, 2.0])
    with pytest.raises(ValueError, match=r"keys \['arm'\].*\['leg'\]"):
        check({"leg": (1, 2)})


def test_a_bad_leaf_is_named_by_its_position():
    check = action_validator([specs.Array((2,), np.float64), specs.Array((2,), np.float64)])
    with pytest.raises(ValueError, match=r"action\[1\]: expected shape \(2,\).*\(3,\)"):
        check([[0, 0], [0, 0, 0]])


def test_a_wrong_number_of_agent_actions_is_rejected():
    check = action_validator([specs.Array((2,), np.float64)] * 2)
    with pytest.raises(ValueError, match="sequence of 2 actions, got 3"):
        check([[0, 0]] * 3)
    with pytest.raises(ValueError, match="sequence of 2 actions, got float"):
        check(0.5)


def test_a_spec_that_is_not_an_array_spec_or_container_is_a_type_error():
    with pytest.raises(TypeError, match="action spec"):
        action_validator(None)
