"""What the SB3 adapter tests (test_sb3.py, test_sb3_batch.py) compare observations with."""

import numpy as np


def assert_observations_equal(actual, expected) -> None:
    """`actual` equals `expected`, entry for entry: two arrays, or two dicts of arrays with
    the same keys."""
    if isinstance(expected, dict):
        assert actual.keys() == expected.keys()
        for key in expected:
            np.testing.assert_array_equal(actual[key], expected[key], err_msg=key)
    else:
        np.testing.assert_array_equal(actual, expected)
