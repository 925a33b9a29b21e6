"""`manipulation.batch.vectors`: the batched tasks' distances, as NumPy's norm gives them."""

import numpy as np

from manipulation.batch import vectors


def test_lengths_are_numpys_vector_norms_bit_for_bit():
    rng = np.random.default_rng(0)
    offsets = (rng.standard_normal((257, 4, 3)) * 10.0 ** rng.integers(-6, 3, (257, 4, 1))).astype(
        np.float32
    )
    got = vectors.lengths(np, offsets)
    assert got.dtype == np.float32 and got.shape == (257, 4)
    np.testing.assert_array_equal(got, np.linalg.vector_norm(offsets, axis=-1))
    np.testing.assert_array_equal(vectors.lengths(np, np.array([3.0, 4.0, 12.0])), 13.0)
