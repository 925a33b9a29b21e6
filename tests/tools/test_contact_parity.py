"""tools/contact_parity.py's account of the plane-cylinder difference, without Warp: the
formula MuJoCo Warp uses loses the rim depth of a nearly upright cylinder in float32, and
the cross-product rim term keeps it (the analytic depth is center_z - h cos t - r sin t)."""

import numpy as np
import pytest

from tools import contact_parity

RADIUS, HALF_HEIGHT = 0.04, 0.02


def _pose(tilt: float):
    center = np.array([0.0, 0.0, 0.02])
    axis = np.array([0.0, -np.sin(tilt), np.cos(tilt)])  # tilted about x
    exact = center[2] - HALF_HEIGHT * np.cos(tilt) - RADIUS * np.sin(tilt)
    return center, axis, exact


@pytest.mark.parametrize("tilt", [1e-3, 1.63e-3, 3e-3])
def test_float32_formula_misses_a_nearly_upright_rim_by_micrometres(tilt):
    center, axis, exact = _pose(tilt)
    got = contact_parity._rim_depth(center, axis, RADIUS, HALF_HEIGHT, np.float32, False)
    # Cancellation in axis_z**2 - 1: an error of order r * 1e-7 / tilt, far above the
    # float32 rounding of a depth of this size (about 1e-9 m).
    assert abs(got - exact) > 1e-7


@pytest.mark.parametrize("tilt", [1e-3, 1.63e-3, 3e-3, 0.3])
def test_cross_product_rim_term_keeps_float32_precision(tilt):
    center, axis, exact = _pose(tilt)
    got = contact_parity._rim_depth(center, axis, RADIUS, HALF_HEIGHT, np.float32, True)
    assert abs(got - exact) < 1e-8


def test_float64_formula_is_exact():
    center, axis, exact = _pose(1.63e-3)
    got = contact_parity._rim_depth(center, axis, RADIUS, HALF_HEIGHT, np.float64, False)
    assert abs(got - exact) < 1e-15
