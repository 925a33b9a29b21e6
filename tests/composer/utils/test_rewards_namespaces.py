"""Tests for composer.utils.rewards.tolerance on non-NumPy arrays (array_api_strict, torch, JAX).

The NumPy path, pinned to known values by test_rewards.py, is the reference.
"""

import math
import sys
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import pytest

from composer.utils import rewards

ALL_SIGMOIDS = rewards.SIGMOIDS

# (bounds, margin, value_at_margin): a point target, an interval, both one-sided intervals,
# and the indicator of an interval (margin 0).
CASES = (
    ((0.0, 0.0), 1.0, 0.1),
    ((-1.0, 2.0), 0.7, 0.5),
    ((-math.inf, 0.5), 2.0, 0.1),
    ((0.0, math.inf), 0.3, 0.9),
    ((1.0, 1.5), 0.0, 0.1),
)
CASE_IDS = ("point", "interval", "below_inf", "above_inf", "indicator")

# Inside, on and outside the bounds of every case, up to far past every sigmoid's support.
POINTS = np.concatenate([np.linspace(-4.0, 5.0, 37), [-1e6, 1e6]])

# float32 carries about 7 digits; the far tail of a sigmoid underflows sooner than in float64.
TOLERANCES = {np.float32: dict(rtol=1e-5, atol=1e-6), np.float64: dict(rtol=1e-12, atol=1e-15)}


class _Backend(NamedTuple):
    asarray: Callable  # NumPy array -> array of the backend, same dtype
    to_numpy: Callable  # array of the backend -> NumPy array (a copy in tests is fine)
    array_type: type
    has_float64: bool


def _array_api_strict() -> _Backend:
    xp = pytest.importorskip(
        "array_api_strict", reason="array_api_strict is not installed: pip install array-api-strict"
    )
    return _Backend(xp.asarray, np.from_dlpack, type(xp.asarray(0.0)), True)


def _torch() -> _Backend:
    torch = pytest.importorskip(
        "torch", reason="torch is not installed: pip install torch (a CPU build is enough)"
    )
    return _Backend(torch.asarray, lambda a: a.detach().numpy(), torch.Tensor, True)


def _jax() -> _Backend:
    jax = pytest.importorskip("jax", reason="jax is not installed: pip install jax")
    jnp = jax.numpy
    return _Backend(jnp.asarray, np.asarray, jax.Array, bool(jax.config.jax_enable_x64))


@pytest.fixture(params=[_array_api_strict, _torch, _jax], ids=["array_api_strict", "torch", "jax"])
def backend(request) -> _Backend:
    return request.param()


# NumPy, and array_api_strict on top of it, warn when cosh overflows, then give the limit 0.
@pytest.mark.filterwarnings("ignore:overflow encountered in cosh:RuntimeWarning")
@pytest.mark.parametrize("dtype", [np.float32, np.float64], ids=["float32", "float64"])
@pytest.mark.parametrize(("bounds", "margin", "value_at_margin"), CASES, ids=CASE_IDS)
@pytest.mark.parametrize("sigmoid", ALL_SIGMOIDS)
def test_every_sigmoid_matches_numpy_and_keeps_the_array_type_and_dtype(
    backend, sigmoid, bounds, margin, value_at_margin, dtype
):
    if dtype is np.float64 and not backend.has_float64:
        pytest.skip("float64 is disabled in this backend (jax_enable_x64 is off)")
    points = POINTS.astype(dtype)
    expected = rewards.tolerance(
        points.astype(np.float64), bounds, margin, sigmoid, value_at_margin
    )

    result = rewards.tolerance(backend.asarray(points), bounds, margin, sigmoid, value_at_margin)

    assert isinstance(result, backend.array_type)
    values = backend.to_numpy(result)
    assert values.dtype == dtype
    assert values.shape == points.shape
    np.testing.assert_allclose(values, expected, **TOLERANCES[dtype])


def test_hand_computed_values(backend):
    def tolerance(x, **kwargs):
        return backend.to_numpy(rewards.tolerance(backend.asarray(np.float32(x)), **kwargs))

    # Inside the bounds the value is exactly 1, whatever the sigmoid.
    assert tolerance([0.0, 0.4, 1.0], bounds=(0.0, 1.0), margin=1.0).tolist() == [1.0] * 3
    # At distance `margin` from a bound the value is `value_at_margin`.
    at_margin = tolerance([-0.5, 3.0], bounds=(0.0, 1.0), margin=2.0, value_at_margin=0.2)
    np.testing.assert_allclose(at_margin, [0.2 ** (0.25**2), 0.2], rtol=1e-6)
    # A linear decay that reaches 0 at the margin is 1/2 half way there.
    halfway = tolerance([1.5], bounds=(0.0, 1.0), margin=1.0, sigmoid="linear", value_at_margin=0)
    np.testing.assert_allclose(halfway, [0.5], rtol=1e-6)
    # An infinite bound: everything above the lower bound is inside.
    one_sided = tolerance([1e30, 0.0, -1.0], bounds=(0.0, math.inf), margin=1.0)
    np.testing.assert_allclose(one_sided, [1.0, 1.0, 0.1], rtol=1e-6)
    # Margin 0: the indicator of the bounds.
    assert tolerance([-0.1, 0.0, 1.0, 1.1], bounds=(0.0, 1.0)).tolist() == [0.0, 1.0, 1.0, 0.0]


def test_argument_errors_name_the_argument_as_for_numpy(backend):
    x = backend.asarray(np.zeros(3))
    with pytest.raises(ValueError, match="lower <= upper"):
        rewards.tolerance(x, bounds=(1.0, 0.0))
    with pytest.raises(ValueError, match="margin must be non-negative, got -1"):
        rewards.tolerance(x, margin=-1.0)
    with pytest.raises(ValueError, match="unknown sigmoid 'sigmund'.*gaussian"):
        rewards.tolerance(x, margin=1.0, sigmoid="sigmund")
    with pytest.raises(ValueError, match="value_at_margin for sigmoid 'gaussian'"):
        rewards.tolerance(x, margin=1.0, value_at_margin=0.0)


def test_array_api_strict_result_stays_on_the_device_of_x():
    xp = pytest.importorskip("array_api_strict", reason="array_api_strict is not installed")
    device = xp.Device("device1")
    for sigmoid in ALL_SIGMOIDS:
        x = xp.asarray([-1.0, 0.5, 3.0], device=device)
        assert rewards.tolerance(x, bounds=(0.0, 1.0), margin=1.0, sigmoid=sigmoid).device == device
    assert rewards.tolerance(x, bounds=(0.0, 1.0)).device == device


def test_integer_x_gives_the_default_float_dtype_of_its_device():
    xp = pytest.importorskip("array_api_strict", reason="array_api_strict is not installed")
    on_cpu = rewards.tolerance(xp.asarray([0, 1, 3]), bounds=(0, 1), margin=2.0)
    # array_api_strict's "no_float64" device has float32 as its default float.
    no_float64 = xp.asarray([0, 1, 3], device=xp.Device("no_float64"))
    on_no_float64 = rewards.tolerance(no_float64, bounds=(0, 1), margin=2.0)

    assert on_cpu.dtype == xp.float64
    assert on_no_float64.dtype == xp.float32
    np.testing.assert_allclose(np.from_dlpack(on_cpu), [1.0, 1.0, 0.1], rtol=1e-12)


def test_torch_integer_x_gives_torch_default_float():
    torch = pytest.importorskip("torch", reason="torch is not installed")
    value = rewards.tolerance(torch.tensor([0, 1, 3]), bounds=(0, 1), margin=2.0)
    assert value.dtype == torch.get_default_dtype()
    np.testing.assert_allclose(value.numpy(), [1.0, 1.0, 0.1], rtol=1e-6)


def test_torch_values_are_never_read_on_the_host():
    # A meta tensor has a shape and a dtype but no data: any float(), .item(), bool() or
    # NumPy conversion raises, as would a synchronising copy from a CUDA tensor.
    torch = pytest.importorskip("torch", reason="torch is not installed")
    x = torch.empty((4, 3), device="meta")
    for sigmoid in ALL_SIGMOIDS:
        for margin in (0.0, 0.5):
            value = rewards.tolerance(x, bounds=(-math.inf, 1.0), margin=margin, sigmoid=sigmoid)
            assert (value.device.type, value.shape, value.dtype) == ("meta", x.shape, x.dtype)


@pytest.mark.parametrize("sigmoid", ALL_SIGMOIDS)
def test_torch_gradient_is_finite_with_an_infinite_bound(sigmoid):
    torch = pytest.importorskip("torch", reason="torch is not installed")
    x = torch.tensor([-3.0, -0.2, 0.0, 5.0, 1e30], dtype=torch.float64, requires_grad=True)
    rewards.tolerance(x, bounds=(0.0, math.inf), margin=1.0, sigmoid=sigmoid).sum().backward()
    assert torch.isfinite(x.grad).all()
    # Inside the bounds the value is constant.
    assert x.grad[2:].tolist() == [0.0, 0.0, 0.0]


def test_device_array_arguments_are_rejected_naming_the_argument():
    torch = pytest.importorskip("torch", reason="torch is not installed")
    x = torch.zeros(3)
    with pytest.raises(TypeError, match=r"bounds\[1\] must be a Python or NumPy number"):
        rewards.tolerance(x, bounds=(0.0, torch.tensor(1.0)))
    with pytest.raises(TypeError, match="margin must be a Python or NumPy number"):
        rewards.tolerance(x, margin=torch.tensor(1.0))
    # NumPy numbers are host values and stay accepted.
    value = rewards.tolerance(x, bounds=(np.float32(0.0), np.array(1.0)), margin=np.float64(1))
    assert value.tolist() == [1.0, 1.0, 1.0]


def test_complex_x_is_rejected_naming_its_dtype():
    torch = pytest.importorskip("torch", reason="torch is not installed")
    with pytest.raises(TypeError, match="x must have a real dtype, got torch.complex64"):
        rewards.tolerance(torch.zeros(3, dtype=torch.complex64), margin=1.0)


def test_without_array_api_compat_a_non_numpy_array_asks_to_install_it(monkeypatch, backend):
    x = backend.asarray(np.zeros(3))
    monkeypatch.setitem(sys.modules, "array_api_compat", None)  # `import` now fails.
    with pytest.raises(ImportError, match="pip install array-api-compat"):
        rewards.tolerance(x, margin=1.0)


def test_without_array_api_compat_numpy_and_scalars_still_work(monkeypatch):
    monkeypatch.setitem(sys.modules, "array_api_compat", None)
    assert rewards.tolerance(2.0, bounds=(0.0, 1.0), margin=1.0) == pytest.approx(0.1)
    values = rewards.tolerance(np.array([0.5, 2.0]), bounds=(0.0, 1.0), margin=1.0)
    np.testing.assert_allclose(values, [1.0, 0.1])


def test_numpy_inputs_keep_numpy_results_and_scalars_give_floats():
    as_float32 = rewards.tolerance(np.array([0.5, 2.0], np.float32), bounds=(0, 1), margin=1.0)
    from_list = rewards.tolerance([0.5, 2.0], bounds=(0, 1), margin=1.0)
    zero_dim = rewards.tolerance(np.array(2.0), bounds=(0, 1), margin=1.0)

    assert type(as_float32) is np.ndarray and type(from_list) is np.ndarray
    np.testing.assert_allclose(from_list, [1.0, 0.1])
    assert type(zero_dim) is np.ndarray and zero_dim.shape == ()
    for scalar in (2, 2.0, np.float32(2.0), np.int64(2)):
        value = rewards.tolerance(scalar, bounds=(0, 1), margin=1.0)
        assert type(value) is float and value == pytest.approx(0.1)
