"""Tests for composer.variation.math."""

import numpy as np

from composer.variation import deterministic, math


def test_math_ops_apply_numpy_functions_to_evaluated_arguments():
    vector = deterministic.Constant(np.array([3.0, -4.0]))
    assert math.Norm(vector)() == 5.0
    assert math.Max(vector)() == 3.0
    assert math.Min(vector)() == -4.0
    assert math.Log(deterministic.Constant(np.e))() == 1.0
