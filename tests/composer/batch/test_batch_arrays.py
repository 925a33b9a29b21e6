"""composer.batch.arrays.ArrayBridge.to_host: host values of any namespace's array."""

import numpy as np
import pytest

pytestmark = pytest.mark.warp


def _bridge(namespace: str):
    from composer.batch import _warp, arrays

    wp = _warp.load().warp
    return arrays.ArrayBridge(wp, wp.get_device("cpu"), "numpy", namespace=namespace)


@pytest.mark.parametrize("namespace", ["numpy", "torch"])
def test_to_host_reads_numpy_lists_torch_and_warp_arrays_whatever_the_namespace(namespace):
    import warp as wp

    try:
        import torch
    except ImportError:
        torch = None
    if namespace == "torch" and torch is None:
        pytest.skip("torch is optional: pip install torch==2.13.0")
    bridge = _bridge(namespace)
    expected = np.array([3, 1, 4], np.int32)
    given = {
        "list": [3, 1, 4],
        "numpy": expected.copy(),
        "warp": wp.array(expected, dtype=wp.int32, device="cpu"),
    }
    if torch is not None:
        given["torch"] = torch.tensor([3, 1, 4], dtype=torch.int32)
    for kind, values in given.items():
        host = bridge.to_host(values)
        assert isinstance(host, np.ndarray), kind
        np.testing.assert_array_equal(host, expected, err_msg=kind)
