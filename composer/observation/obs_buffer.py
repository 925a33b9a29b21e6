"""The buffer of one observable: delayed delivery and the last `buffer_size` delivered samples."""

import bisect
import functools
import numbers

import numpy as np


class IncompatibleSampleError(ValueError):
    """A sample whose shape or dtype does not match the buffer it is inserted into."""


def _checked_sample(value, shape: tuple, dtype: np.dtype) -> np.ndarray:
    """Returns `value` as an array of `shape` whose dtype casts to `dtype` ('same_kind')."""
    array = np.asarray(value)
    if array.shape != shape:
        raise IncompatibleSampleError(
            f"sample has shape {array.shape}, expected {shape} (dtype {dtype})"
        )
    if array.dtype != dtype and not np.can_cast(array.dtype, dtype, "same_kind"):
        raise IncompatibleSampleError(
            f"sample has dtype {array.dtype}, expected {dtype} (shape {shape})"
        )
    return array


def _drop_unobserved(schedule, read_interval: int, size: int, retained_arrivals) -> None:
    """Removes from `schedule` the samples that no read at a multiple of `read_interval`
    returns. Samples already retained by the buffer (`retained_arrivals`) were taken before
    any scheduled one, so they come first among equal arrival times."""
    known = sorted(
        [(arrival, -np.inf) for arrival in retained_arrivals]
        + [(timestamp + delay, timestamp) for timestamp, delay in schedule]
    )
    arrivals = [arrival for arrival, _ in known]
    kept = []
    for timestamp, delay in schedule:
        arrival = timestamp + delay
        first_read = -(-arrival // read_interval) * read_interval
        arriving_later = bisect.bisect_right(arrivals, first_read) - bisect.bisect_right(
            known, (arrival, timestamp)
        )
        if arriving_later < size:
            kept.append((timestamp, delay))
    schedule.clear()
    schedule.extend(kept)


def _check_buffer_size(buffer_size) -> int:
    if (
        not isinstance(buffer_size, numbers.Integral)
        or isinstance(buffer_size, bool)
        or buffer_size < 1
    ):
        raise ValueError(f"Buffer: buffer_size must be an integer >= 1, got {buffer_size!r}")
    return int(buffer_size)


@functools.lru_cache(maxsize=256)
def _wrapped_windows(capacity: int, size: int) -> tuple:
    """For each end slot of a ring of `capacity` slots, the indices of the `size` slots
    ending there (wrapping around), for `take`."""
    return tuple(np.arange(end - size + 1, end + 1) % capacity for end in range(capacity))


def _as_shape(shape) -> tuple:
    return (int(shape),) if isinstance(shape, numbers.Integral) else tuple(shape)


class Buffer:
    """Holds the most recent `buffer_size` delivered samples of one observable.

    A sample inserted at `timestamp` with `delay` is delivered at `timestamp + delay`;
    samples are delivered in order of arrival (ties: earlier timestamp first). `read`
    returns a new array the caller owns: the samples delivered by `current_time`, oldest
    first, along a leading axis of length `buffer_size` (absent when
    `strip_singleton_buffer_dim` is True and `buffer_size` is 1). Slots not yet filled hold
    zeros, or the first inserted value when `pad_with_initial_value` is True.

    Timestamps must not decrease from one insert to the next, and `read` is called with a
    time no earlier than the latest inserted timestamp.
    """

    def __init__(
        self,
        buffer_size: int,
        shape,
        dtype,
        pad_with_initial_value: bool = False,
        strip_singleton_buffer_dim: bool = False,
    ):
        self._size = _check_buffer_size(buffer_size)
        self._sample_shape = _as_shape(shape)
        self._dtype = np.dtype(dtype)
        self._strip = bool(strip_singleton_buffer_dim) and self._size == 1
        self._shape = self._sample_shape if self._strip else (self._size,) + self._sample_shape
        self._pad = bool(pad_with_initial_value)
        # All retained samples, delivered or not, sit in a ring in arrival order: the oldest
        # at `_next` (the slot the next sample overwrites), the newest just before it.
        # Padding entries arrive at -inf. The ring grows when delays keep samples in flight.
        self._values = np.zeros((self._size,) + self._sample_shape, self._dtype)
        self.clear()

    def clear(self) -> None:
        """Empties the buffer: it is then as a new one of the same size, sample shape and
        options (arrays that `read` returned are the caller's, and stay as they are)."""
        self._awaiting_initial_value = self._pad
        self._last_timestamp = -np.inf
        if len(self._values) == self._size:
            self._values.fill(0)
        else:  # the ring grew
            self._values = np.zeros((self._size,) + self._sample_shape, self._dtype)
        self._arrivals = [-np.inf] * self._size
        self._next = 0

    @property
    def shape(self) -> tuple:
        """Shape of the array `read` returns."""
        return self._shape

    @property
    def dtype(self) -> np.dtype:
        return self._dtype

    def _may_overwrite_oldest(self, timestamp, delay) -> bool:
        """Whether the oldest sample is no longer needed by any read at or after `timestamp`:
        `buffer_size` newer samples have been delivered by then."""
        arrivals = self._arrivals
        capacity = len(arrivals)
        newest = self._next - 1
        in_flight = 0
        while in_flight < capacity and arrivals[newest - in_flight] > timestamp:
            in_flight += 1
        return capacity - 1 - in_flight + (delay == 0) >= self._size

    def insert(self, timestamp, delay, value) -> None:
        """Adds a sample taken at `timestamp`, to be delivered `delay` time units later.

        Raises:
          ValueError: if `delay` is negative or `timestamp` precedes the previous insert.
          IncompatibleSampleError: if `value` does not have this buffer's sample shape and a
            dtype that casts to the buffer's.
        """
        if delay < 0:
            raise ValueError(f"delay must not be negative, got {delay!r}")
        if timestamp < self._last_timestamp:
            raise ValueError(
                f"timestamp {timestamp!r} precedes the previous one ({self._last_timestamp!r})"
            )
        if not (
            isinstance(value, np.ndarray)
            and value.dtype == self._dtype
            and value.shape == self._sample_shape
        ):
            value = _checked_sample(value, self._sample_shape, self._dtype)
        if self._awaiting_initial_value:
            self._values[...] = value
            self._awaiting_initial_value = False
        self._last_timestamp = timestamp
        arrival = timestamp + delay
        arrivals = self._arrivals
        slot = self._next
        newest_arrival = arrivals[slot - 1]
        # Fast path: the sample arrives last (always true for a fixed delay) and overwrites
        # a sample no read needs any more (checked without a call when nothing is in flight).
        if arrival >= newest_arrival and (
            (newest_arrival <= timestamp and len(arrivals) - (delay != 0) >= self._size)
            or self._may_overwrite_oldest(timestamp, delay)
        ):
            self._values[slot] = value
            arrivals[slot] = arrival
            slot += 1
            self._next = 0 if slot == len(arrivals) else slot
        else:
            self._insert_in_order(timestamp, delay, arrival, value)

    def _insert_in_order(self, timestamp, delay, arrival, value) -> None:
        """Inserts a sample that arrives before others, or that needs the ring to grow."""
        capacity = len(self._arrivals)
        oldest_first = np.roll(self._values, -self._next, axis=0)
        arrivals = self._arrivals[self._next :] + self._arrivals[: self._next]
        if self._may_overwrite_oldest(timestamp, delay):
            dropped, unused = 1, 0
            values = self._values
        else:
            # Grow by half (at least one slot); the new slots are older than every sample, so
            # no read reaches them.
            dropped, unused = 0, max(1, capacity // 2) - 1
            values = np.zeros((capacity + unused + 1,) + self._sample_shape, self._dtype)
        kept = oldest_first[dropped:]
        arrivals = [-np.inf] * unused + arrivals[dropped:]
        position = bisect.bisect_right(arrivals, arrival)
        arrivals.insert(position, arrival)
        values[unused:position] = kept[: position - unused]
        values[position] = value
        values[position + 1 :] = kept[position - unused :]
        self._values, self._arrivals, self._next = values, arrivals, 0

    def read(self, current_time) -> np.ndarray:
        """Returns a new array of the last `buffer_size` samples delivered by `current_time`."""
        newest = self._next - 1
        if self._arrivals[newest] > current_time:
            newest = self._newest_delivered(current_time)
        if self._strip:
            return self._values[newest, ...].copy()
        capacity = len(self._arrivals)
        newest %= capacity
        start = newest + 1 - self._size
        if start >= 0:
            return self._values[start : newest + 1].copy()
        return self._values.take(_wrapped_windows(capacity, self._size)[newest], axis=0)

    def _newest_delivered(self, current_time) -> int:
        """The slot of the newest sample delivered by `current_time` (counted back from the
        newest slot, so possibly negative)."""
        arrivals = self._arrivals
        newest = self._next - 1
        for _ in range(len(arrivals) - 1):
            newest -= 1
            if arrivals[newest] <= current_time:
                return newest
        raise ValueError(
            f"read({current_time!r}) precedes the samples this buffer still holds (the latest "
            f"was inserted at {self._last_timestamp!r})"
        )

    def drop_unobserved_upcoming_items(self, observation_schedule, read_interval: int) -> None:
        """Removes from a proposed schedule the samples no read would ever return.

        Reads are assumed to happen only at integer multiples of `read_interval`. A sample is
        observed iff fewer than `buffer_size` samples arrive after it by the first read at or
        after its arrival; samples already in this buffer and the whole proposed schedule
        count.

        Args:
          observation_schedule: list or deque of `(timestamp, delay)` proposed samples,
            edited in place.
          read_interval: time between two reads.
        """
        _drop_unobserved(observation_schedule, read_interval, self._size, self._arrivals)


class LatestSampleBuffer:
    """A buffer of size 1 whose samples are never delayed.

    Reads like `Buffer(1, shape, dtype, ...)` fed only undelayed samples, with less work per
    sample and a cheaper construction: the latest sample lives in one preallocated array,
    `storage`. A caller may pass that array in (zero-filled here), to fill it directly.

    Raises:
      ValueError: if `storage` is not a C-contiguous array of the read shape and dtype.
    """

    def __init__(self, shape, dtype, strip_singleton_buffer_dim: bool = False, storage=None):
        self._sample_shape = _as_shape(shape)
        self._dtype = np.dtype(dtype)
        self._shape = (
            self._sample_shape if strip_singleton_buffer_dim else (1,) + self._sample_shape
        )
        if storage is None:
            storage = np.zeros(self._shape, self._dtype)
        elif (
            not isinstance(storage, np.ndarray)
            or storage.shape != self._shape
            or storage.dtype != self._dtype
            or not storage.flags.c_contiguous
        ):
            raise ValueError(
                f"LatestSampleBuffer: storage must be a C-contiguous array of shape "
                f"{self._shape} and dtype {self._dtype}, got {storage!r}"
            )
        else:
            storage[...] = 0
        self._whole = storage
        self._slot = storage.reshape(self._sample_shape)

    @property
    def shape(self) -> tuple:
        """Shape of the array `read` returns."""
        return self._shape

    @property
    def dtype(self) -> np.dtype:
        return self._dtype

    @property
    def storage(self) -> np.ndarray:
        """The array holding the latest sample; `read` returns a copy of it."""
        return self._whole

    @property
    def sample_view(self) -> np.ndarray:
        """`storage` in the shape of one sample (a view: writing it replaces the sample)."""
        return self._slot

    def insert(self, timestamp, delay, value) -> None:
        """Replaces the held sample; `delay` must be 0 (see `Buffer.insert`)."""
        if delay != 0:
            raise ValueError(f"LatestSampleBuffer: delay must be 0, got {delay!r}")
        if not (
            isinstance(value, np.ndarray)
            and value.dtype == self._dtype
            and value.shape == self._sample_shape
        ):
            value = _checked_sample(value, self._sample_shape, self._dtype)
        self._slot[...] = value

    def read(self, current_time) -> np.ndarray:
        """Returns a new array holding the latest sample."""
        return self._whole.copy()

    def drop_unobserved_upcoming_items(self, observation_schedule, read_interval: int) -> None:
        """See `Buffer.drop_unobserved_upcoming_items`."""
        _drop_unobserved(observation_schedule, read_interval, 1, ())
