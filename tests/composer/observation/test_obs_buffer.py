"""Tests for composer.observation.obs_buffer.Buffer."""

import collections

import numpy as np
import pytest

from composer.observation.obs_buffer import Buffer, LatestSampleBuffer


def test_read_before_buffer_fills_pads_front_with_zeros():
    buffer = Buffer(3, (2,), np.float64)
    buffer.insert(0, 0, [1.0, 2.0])
    np.testing.assert_array_equal(buffer.read(0), [[0, 0], [0, 0], [1, 2]])


def test_read_pads_with_first_value_when_requested():
    buffer = Buffer(3, (2,), np.float64, pad_with_initial_value=True)
    buffer.insert(0, 0, [1.0, 2.0])
    buffer.insert(1, 0, [3.0, 4.0])
    np.testing.assert_array_equal(buffer.read(1), [[1, 2], [1, 2], [3, 4]])


def test_read_returns_last_samples_oldest_first_after_wrapping():
    buffer = Buffer(3, (), np.int64)
    for t in range(5):
        buffer.insert(t, 0, t * 10)
    np.testing.assert_array_equal(buffer.read(4), [20, 30, 40])


def test_delayed_sample_is_invisible_until_it_arrives():
    buffer = Buffer(1, (), np.float64)
    buffer.insert(0, 2, 7.0)
    assert buffer.read(1)[0] == 0.0
    assert buffer.read(2)[0] == 7.0


def test_initial_value_padding_covers_a_delayed_first_sample():
    buffer = Buffer(2, (), np.float64, pad_with_initial_value=True)
    buffer.insert(0, 3, 5.0)
    np.testing.assert_array_equal(buffer.read(1), [5.0, 5.0])


def test_samples_are_delivered_in_arrival_order_not_timestamp_order():
    buffer = Buffer(2, (), np.int64)
    buffer.insert(1, 5, 1)  # arrives at 6
    buffer.insert(2, 1, 2)  # arrives at 3
    np.testing.assert_array_equal(buffer.read(6), [2, 1])


def test_equal_arrivals_keep_timestamp_order():
    buffer = Buffer(2, (), np.int64)
    buffer.insert(1, 3, 1)  # arrives at 4
    buffer.insert(2, 2, 2)  # arrives at 4
    np.testing.assert_array_equal(buffer.read(4), [1, 2])


def test_strip_singleton_buffer_dim_drops_leading_axis():
    buffer = Buffer(1, (3,), np.float64, strip_singleton_buffer_dim=True)
    buffer.insert(0, 0, [1.0, 2.0, 3.0])
    assert buffer.shape == (3,)
    np.testing.assert_array_equal(buffer.read(0), [1, 2, 3])


def test_strip_singleton_buffer_dim_keeps_axis_for_larger_buffers():
    buffer = Buffer(2, (3,), np.float64, strip_singleton_buffer_dim=True)
    assert buffer.shape == (2, 3)


def test_read_returns_an_array_later_inserts_do_not_change():
    buffer = Buffer(1, (2,), np.float64)
    buffer.insert(0, 0, [1.0, 1.0])
    first = buffer.read(0)
    buffer.insert(1, 0, [2.0, 2.0])
    np.testing.assert_array_equal(first, [[1, 1]])


def test_insert_copies_the_value_it_is_given():
    buffer = Buffer(1, (2,), np.float64)
    value = np.array([1.0, 1.0])
    buffer.insert(0, 1, value)
    value[:] = 9.0
    np.testing.assert_array_equal(buffer.read(1), [[1, 1]])


def test_negative_delay_is_rejected():
    buffer = Buffer(1, (), np.float64)
    with pytest.raises(ValueError, match="delay"):
        buffer.insert(0, -1, 1.0)


def test_wrong_shape_is_rejected_with_both_shapes():
    buffer = Buffer(1, (3,), np.float64)
    with pytest.raises(ValueError, match=r"\(2,\).*\(3,\)"):
        buffer.insert(0, 0, [1.0, 2.0])


@pytest.mark.parametrize("as_array", [False, True], ids=["python_float", "float_array"])
def test_float_sample_into_integer_buffer_is_rejected(as_array):
    buffer = Buffer(1, (), np.uint8)
    with pytest.raises(ValueError, match="dtype float64"):
        buffer.insert(0, 0, np.array(1.5) if as_array else 1.5)


def test_array_of_the_buffers_dtype_but_another_shape_is_rejected():
    buffer = Buffer(1, (2,), np.float64)
    with pytest.raises(ValueError, match=r"\(1,\).*\(2,\)"):
        buffer.insert(0, 0, np.ones(1))


@pytest.mark.parametrize(
    ("value", "dtype", "expected"),
    [([1, 2], np.float64, [1.0, 2.0]), (np.array([0.5, 1.5]), np.float32, [0.5, 1.5])],
    ids=["ints_into_float64", "float64_into_float32"],
)
def test_samples_of_the_same_kind_are_cast_to_the_buffers_dtype(value, dtype, expected):
    buffer = Buffer(1, (2,), dtype)
    buffer.insert(0, 0, value)
    read = buffer.read(0)
    assert read.dtype == dtype
    assert read.tolist() == [expected]


def test_timestamp_earlier_than_the_previous_one_is_rejected_naming_both():
    buffer = Buffer(1, (), np.float64)
    buffer.insert(5, 0, 1.0)
    buffer.insert(5, 0, 2.0)
    with pytest.raises(ValueError) as raised:
        buffer.insert(4, 0, 3.0)
    assert str(raised.value) == "timestamp 4 precedes the previous one (5)"


@pytest.mark.parametrize("size", [0, -1, True, 2.0, "2", None])
def test_buffer_size_that_is_not_a_positive_integer_is_rejected(size):
    with pytest.raises(ValueError) as raised:
        Buffer(size, (), np.float64)
    assert str(raised.value) == f"Buffer: buffer_size must be an integer >= 1, got {size!r}"


def test_drop_removes_samples_displaced_before_the_next_read():
    buffer = Buffer(2, (), np.float64)
    schedule = [(t, 0) for t in range(1, 6)]
    buffer.drop_unobserved_upcoming_items(schedule, read_interval=5)
    assert schedule == [(4, 0), (5, 0)]


def test_drop_keeps_samples_arriving_at_a_later_read():
    buffer = Buffer(1, (), np.float64)
    schedule = collections.deque([(4, 0), (5, 3)])  # (5, 3) arrives at 8, read at 10
    buffer.drop_unobserved_upcoming_items(schedule, read_interval=5)
    assert list(schedule) == [(4, 0), (5, 3)]


def test_drop_counts_samples_already_in_flight():
    buffer = Buffer(1, (), np.float64)
    buffer.insert(0, 4, 1.0)  # arrives at 4, after the scheduled sample at 3
    schedule = [(3, 0)]
    buffer.drop_unobserved_upcoming_items(schedule, read_interval=5)
    assert schedule == []


def test_read_earlier_than_every_held_sample_is_a_clear_error():
    buffer = Buffer(1, (), np.float64)
    buffer.insert(5, 1, 1.0)  # arrives at 6
    buffer.insert(6, 1, 2.0)  # arrives at 7; the padding slot is gone
    with pytest.raises(ValueError, match="precedes"):
        buffer.read(4)


def test_latest_sample_buffer_holds_its_sample_in_the_storage_it_is_given():
    block = np.full(8, 7.0)
    buffer = LatestSampleBuffer((3,), np.float64, storage=block[2:5].reshape(1, 3))
    np.testing.assert_array_equal(block, [7, 7, 0, 0, 0, 7, 7, 7])
    buffer.insert(0, 0, np.array([1.0, 2.0, 3.0]))
    np.testing.assert_array_equal(block[2:5], [1, 2, 3])
    np.testing.assert_array_equal(buffer.read(0), [[1, 2, 3]])


def test_latest_sample_buffer_rejects_storage_of_another_shape():
    with pytest.raises(ValueError, match=r"storage must be .* shape \(1, 3\)"):
        LatestSampleBuffer((3,), np.float64, storage=np.zeros(3))


def test_latest_sample_buffer_rejects_storage_that_is_not_contiguous():
    with pytest.raises(ValueError, match="C-contiguous"):
        LatestSampleBuffer((3,), np.float64, storage=np.zeros((1, 6))[:, ::2])


def test_latest_sample_buffer_rejects_a_float_array_for_integer_samples():
    buffer = LatestSampleBuffer((2,), np.int32)
    with pytest.raises(ValueError, match="dtype float64"):
        buffer.insert(0, 0, np.array([0.5, 1.5]))


def test_latest_sample_buffer_refuses_a_delay_naming_it():
    with pytest.raises(ValueError) as raised:
        LatestSampleBuffer((), np.float64).insert(0, 2, 1.0)
    assert str(raised.value) == "LatestSampleBuffer: delay must be 0, got 2"


def test_a_sample_shape_may_be_given_as_an_integer():
    buffer = Buffer(2, 3, np.float64)
    buffer.insert(0, 0, [1.0, 2.0, 3.0])
    assert buffer.read(0).tolist() == [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]


def _expected_read(inserted, size, read_time):
    """The last `size` samples delivered by `read_time`, oldest first, zero-padded in front:
    delivery order is arrival time, then insertion order."""
    delivered = sorted(
        (arrival, order, value)
        for order, (arrival, value) in enumerate(inserted)
        if arrival <= read_time
    )
    values = [value for _, _, value in delivered][-size:]
    return [0] * (size - len(values)) + values


@pytest.mark.parametrize(
    ("size", "max_delay", "max_time_step"),
    [(1, 4, 1), (3, 8, 2), (5, 8, 1), (12, 19, 3), (10, 4, 0)],
    ids=["one", "three", "five", "twelve", "all_at_one_time"],
)
def test_random_delays_read_like_a_sorted_list_of_arrivals(size, max_delay, max_time_step):
    # Random delays make samples arrive out of order and keep many in flight, which makes
    # the buffer insert out of order and grow; every read must still be what a plain
    # sorted list of arrivals gives.
    rng = np.random.default_rng(size)
    buffer = Buffer(size, (), np.int32)
    inserted = []
    time = 0
    for value in range(1, 301):
        time += int(rng.integers(0, max_time_step + 1))
        delay = int(rng.integers(0, max_delay + 1))
        buffer.insert(time, delay, np.int32(value))
        inserted.append((time + delay, value))
        read = buffer.read(time)
        assert read.dtype == np.int32
        assert read.tolist() == _expected_read(inserted, size, time)


def test_drop_keeps_a_sample_that_arrives_with_an_older_one_already_held():
    # The held sample (taken at 1, delay 3) and the scheduled one (taken at 4, no delay)
    # both arrive at 4; the scheduled one is newer, so the read at 4 returns it.
    buffer = Buffer(1, (), np.float64)
    buffer.insert(1, 3, 1.0)
    schedule = [(4, 0)]
    buffer.drop_unobserved_upcoming_items(schedule, read_interval=1)
    assert schedule == [(4, 0)]
