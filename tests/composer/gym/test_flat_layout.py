"""FlatLayout: a batch of observations in one byte buffer that another process can read."""

import numpy as np
import pytest
from gymnasium import spaces

from composer.gym.flat_layout import FlatBatch, FlatLayout, leaves

_SPACE = spaces.Dict(
    {
        "joints": spaces.Box(-1.0, 1.0, (1, 6, 2), np.float64),
        "mode": spaces.Discrete(3),
        "sensors": spaces.Tuple((spaces.MultiBinary(3), spaces.Box(0, 255, (2, 2, 3), np.uint8))),
    }
)


def test_a_batch_read_back_from_the_buffers_bytes_holds_the_values_written():
    layout = FlatLayout(_SPACE)
    buffer = layout.allocate(4)
    batch = layout.views(buffer)
    batch["joints"][2] = 0.25
    batch["mode"][3] = 2
    batch["sensors"][0][1] = [1, 0, 1]
    batch["sensors"][1][3] = 200
    # What another process makes of the bytes it received.
    received = layout.views(np.frombuffer(buffer.tobytes(), np.uint8).reshape(buffer.shape))
    assert received["joints"].shape == (4, 1, 6, 2)
    assert received["joints"][2].tolist() == np.full((1, 6, 2), 0.25).tolist()
    assert received["joints"][1].tolist() == np.zeros((1, 6, 2)).tolist()
    assert received["mode"].tolist() == [0, 0, 0, 2]
    assert received["sensors"][0][1].tolist() == [1, 0, 1]
    assert received["sensors"][1][3].tolist() == np.full((2, 2, 3), 200).tolist()
    assert received["sensors"][1].dtype == np.uint8


def test_leaves_are_8_byte_aligned_spans_of_each_row():
    layout = FlatLayout(_SPACE)
    # 96 bytes of joints, 8 of mode, 3 of MultiBinary padded to 8, 12 of image to 16.
    assert layout.row_bytes == 96 + 8 + 8 + 16
    batch = layout.views(layout.allocate(2))
    assert [leaf.dtype for leaf in leaves(batch)] == [
        np.float64,
        np.int64,
        np.int8,
        np.uint8,
    ]


def test_a_space_with_a_leaf_that_is_not_an_array_is_refused_naming_the_leaf():
    space = spaces.Dict({"name": spaces.Text(5), "x": spaces.Box(0, 1, (2,))})
    with pytest.raises(TypeError, match="leaf 0: expected an array of numbers, got str"):
        FlatLayout(space)


def test_an_empty_leaf_takes_no_bytes_and_keeps_its_shape():
    layout = FlatLayout(spaces.Dict({"none": spaces.Box(0, 1, (1, 0)), "x": spaces.Discrete(2)}))
    assert layout.row_bytes == 8
    batch = layout.views(layout.allocate(3))
    assert batch["none"].shape == (3, 1, 0)
    assert batch["x"].shape == (3,)


def test_a_flat_batch_writes_a_value_into_its_row_only():
    batch = FlatBatch(FlatLayout(_SPACE), 3)
    value = {
        "joints": np.full((1, 6, 2), 0.5),
        "mode": np.int64(1),
        "sensors": (np.ones(3, np.int8), np.full((2, 2, 3), 9, np.uint8)),
    }
    batch.write(1, value)
    assert batch.batch["joints"][:, 0, 0, 0].tolist() == [0.0, 0.5, 0.0]
    assert batch.batch["mode"].tolist() == [0, 1, 0]
    assert batch.batch["sensors"][1][1].tolist() == value["sensors"][1].tolist()
    # The bytes of row 1 are the value's: what `RayVectorEnv` sends for one action.
    other = FlatLayout(_SPACE).views(batch.buffer[1:2].copy())
    assert other["mode"].tolist() == [1]
