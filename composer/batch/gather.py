"""Observations read by one kernel: every entry a fixed function of a few field entries.

A `FieldGather` is a batched reader whose every entry is the sum of a few entries of one
float field of a world (float64 on the CPU batch, float32 on MuJoCo Warp), each times a
fixed weight, optionally passed through sin or cos: an MJCF feature's selected entries
(weight 1), a joint torque (a sensor's 3-vector on the joint's axis), a joint angle's sine
and cosine. `ObservationGather` reads all of a batch's `FieldGather`s into a new block of
device memory per read, so that a result the caller keeps is never written again (see
`composer.batch.arrays`): with one launch of `kernels.gather_columns`, one thread per world,
where task code runs in torch (CUDA, and `namespace="torch"` on Warp's CPU device); with a
few NumPy calls per observable, written straight into the block, where it runs in NumPy (the
CPU batch, Warp's CPU device): a slice or a `numpy.take`, one BLAS product for weighted
sums, sine and cosine of entries taken once (`_numpy_plan`), because Warp's CPU kernels
gather about six times slower than `numpy.take` (about 10 ns an entry against 1.5, measured
on the development machine, 2026-11). Both execute the same plan, the `FieldGather`s'
entries, weights and ops; the torch tests compare the two.

Kernel blocks are cut from chunks of `ObservationGather.CHUNK_BYTES` (at least one read each):
a chunk is allocated once per so many reads and stays alive while any of its reads is
referenced. The kernel reads the fields at the addresses they had when the gather was made:
MuJoCo Warp's arrays are allocated once, with the data and the model.
"""

from typing import Any, NamedTuple

import numpy as np

from composer.batch import _warp, arrays, kernels

__all__ = ["FieldGather", "ObservationGather"]

#: `FieldGather` ops: the sum as it is, its sine, its cosine.
OPS = {"identity": 0, "sin": 1, "cos": 2}


class FieldGather:
    """A reader of every world's value of one observable, a fixed function of one field.

    Entry i of a world's value is `op[i](sum over t of weights[i, t] * row[entries[i, t]])`,
    where `row` is the world's row of the field, flattened.

    Args:
      physics: the `BatchPhysics`.
      field: the `FieldView` read.
      entries: int array of shape (*value shape, terms): flat indices into a world's row.
      weights: float array of the same shape (None: all ones).
      ops: array of `OPS` names of the value's shape (None: "identity" everywhere).
    """

    def __init__(self, physics, field, entries, weights=None, ops=None):
        entries = np.asarray(entries, dtype=np.int64)
        if entries.ndim < 1:
            raise ValueError(f"entries: expected an array ending in a terms axis, got {entries!r}")
        self._physics = physics
        self.field = field
        self.shape = entries.shape[:-1]
        self.entries = entries.reshape(-1, entries.shape[-1])
        floats = physics.float_dtype
        self.weights = (
            np.ones(self.entries.shape, floats)
            if weights is None
            else np.asarray(weights, floats).reshape(self.entries.shape)
        )
        names = np.full(self.shape, "identity") if ops is None else np.asarray(ops)
        unknown = sorted(set(names.ravel()) - set(OPS))
        if unknown:
            raise ValueError(f"ops: expected names among {list(OPS)}, got {unknown}")
        self.ops = np.vectorize(OPS.__getitem__, otypes=[np.int32])(names).reshape(-1)
        #: Whether `ObservationGather` can read it (a field of the batch's float dtype).
        self.gatherable = field.gatherable
        flat = self.entries[:, 0]
        plain = (
            self.entries.shape[1] == 1 and not self.ops.any() and bool(np.all(self.weights == 1.0))
        )
        # A run of consecutive entries (a body's position, an arm's joints) read alone is a
        # slice, a view, where a gather would copy.
        self._slice = (
            slice(int(flat[0]), int(flat[0]) + flat.size)
            if plain and flat.size and np.array_equal(flat, np.arange(flat[0], flat[0] + flat.size))
            else None
        )
        self._plain = plain
        self._numpy_plan = None if plain else _numpy_plan(self.entries, self.weights, self.ops)
        self._slice_items: _RowItems | None = None  # made at the first NumPy read
        self._device_entries = physics.arrays.asarray(self.entries.ravel())
        self._device_weights = physics.arrays.asarray(self.weights)
        self._device_ops = physics.arrays.asarray(self.ops)

    def take_into(self, out) -> None:
        """Writes the value in every world into `out`, a NumPy (num_envs, entries) array (the
        NumPy namespace only)."""
        rows = self.field.view
        flat = rows.reshape(rows.shape[0], -1)
        if self._plain:
            if self._slice is not None:
                if self._slice_items is None:  # the field's memory never moves
                    self._slice_items = _RowItems(flat[:, self._slice])
                self._slice_items.copy_to(out)
            elif rows.shape[0] == out.shape[0]:
                # "clip" (the entries are in range) writes straight into `out`, unbuffered.
                np.take(flat, self.entries[:, 0], axis=1, out=out, mode="clip")
            else:  # a model field shared by every world
                out[...] = flat[:, self.entries[:, 0]]
            return
        plan = self._numpy_plan
        if isinstance(plan, _Product):
            if flat.shape[0] == out.shape[0]:
                np.dot(flat[:, plan.span], plan.matrix, out=out)
            else:  # a model field shared by every world
                out[...] = np.dot(flat[:, plan.span], plan.matrix)
            return
        if isinstance(plan, _Trigonometric):
            sources = plan.sources
            if isinstance(sources, slice) and sources.step in (None, 1):
                if self._slice_items is None:
                    self._slice_items = _RowItems(flat[:, sources])
                values = np.empty((out.shape[0], sources.stop - sources.start), out.dtype)
                self._slice_items.copy_to(values)
            elif isinstance(sources, slice):
                values = np.ascontiguousarray(flat[:, sources])
            else:
                values = np.take(flat, sources, axis=1)
            for function, columns, picks in plan.columns:
                picked = values if picks is None else np.ascontiguousarray(values[:, picks])
                # On contiguous values: NumPy's vectorised sin and cos skip strided ones.
                out[:, columns] = picked if function is None else function(picked)
            return
        summed = np.einsum("wct,ct->wc", flat[:, self.entries], self.weights)
        out[...] = summed
        for name in ("sin", "cos"):
            columns = np.flatnonzero(self.ops == OPS[name])
            if columns.size:
                out[:, columns] = getattr(np, name)(summed[:, columns])

    def __call__(self) -> Any:
        """The value in every world, (num_envs, *value shape), in the batch's namespace."""
        xp, physics = self._physics.xp, self._physics
        values = self.field.read()
        flat = xp.reshape(values, (values.shape[0], -1))
        if self._slice is not None:
            taken = flat[:, self._slice]
        else:
            taken = xp.take(flat, self._device_entries, axis=1)
        if not self._plain:
            taken = xp.reshape(taken, (physics.num_envs, *self.entries.shape))
            taken = xp.sum(taken * self._device_weights, axis=-1)
            taken = xp.where(
                self._device_ops == OPS["sin"],
                xp.sin(taken),
                xp.where(self._device_ops == OPS["cos"], xp.cos(taken), taken),
            )
        return xp.reshape(taken, (physics.num_envs, *self.shape))


class _Product(NamedTuple):
    """A reader of weighted sums as one BLAS product: value = row[span] @ matrix."""

    span: slice
    matrix: np.ndarray


class _Trigonometric(NamedTuple):
    """A reader of single entries, some through sin or cos: the `sources` entries of a
    row are taken once; then each (function or None, output columns, picks among the
    sources or None for all of them in order)."""

    sources: slice | np.ndarray
    columns: list[tuple[Any, slice | np.ndarray, slice | np.ndarray | None]]


def _numpy_plan(entries, weights, ops) -> "_Product | _Trigonometric | None":
    """How `FieldGather.take_into` reads a reader that is not a plain take, on NumPy.

    Weighted sums without sin or cos whose entries cover a span of the row (a joint
    torque: sensors' 3-vectors on the joints' axes) are one matrix product over the span,
    three times faster than a gather and a sum at a thousand worlds (development machine);
    every entry of the span belongs to the reader, so no other value enters a sum. Single
    entries through sin and cos (joint angles) take their sources once. None: the general
    gather, sum and ops.
    """
    if not ops.any():
        low, high = int(entries.min()), int(entries.max()) + 1
        if np.unique(entries).size == high - low:
            matrix = np.zeros((high - low, entries.shape[0]), weights.dtype)
            columns = np.broadcast_to(np.arange(entries.shape[0])[:, None], entries.shape)
            np.add.at(matrix, (entries - low, columns), weights)
            return _Product(slice(low, high), matrix)
        return None
    if entries.shape[1] != 1 or not np.all(weights == 1.0):
        return None
    sources = np.unique(entries[:, 0])
    position = np.searchsorted(sources, entries[:, 0])
    columns = []
    for name, code in OPS.items():
        chosen = np.flatnonzero(ops == code)
        if chosen.size:
            picks = position[chosen]
            in_order = np.array_equal(picks, np.arange(sources.size))
            function = None if name == "identity" else getattr(np, name)
            columns.append((function, _as_slice(chosen), None if in_order else _as_slice(picks)))
    return _Trigonometric(_as_slice(sources), columns)


class _RowItems:
    """Copies `rows` (n or 1, w), whose rows are contiguous, into C-contiguous (n, w)
    arrays of its dtype, each row as one item rather than entry by entry: a world's 3 to 9
    floats copy in about half the time at a thousand worlds (development machine, 2026-11).
    """

    def __init__(self, rows: np.ndarray):
        self._rows = rows
        self._items = arrays.row_items(rows) if rows.strides[-1] == rows.itemsize else None

    def copy_to(self, out: np.ndarray) -> None:
        if self._items is None:
            out[...] = self._rows
        else:  # the items' dtype, made once (making one costs microseconds)
            np.copyto(out.view(self._items.dtype)[:, 0], self._items)


def _as_slice(columns: np.ndarray) -> slice | np.ndarray:
    """Evenly spaced `columns` as a slice (a view, where an index array copies)."""
    if columns.size > 1:
        steps = np.diff(columns)
        if steps[0] > 0 and np.all(steps == steps[0]):
            return slice(int(columns[0]), int(columns[-1]) + 1, int(steps[0]))
    return columns


class ObservationGather:
    """Reads the `FieldGather`s of a batch's observables with one kernel launch.

    Args:
      physics: the `BatchPhysics`.
      readers: the gathered observables' readers by key.
    """

    #: The size of the device memory blocks' chunks (each holds one read at least).
    CHUNK_BYTES = 1 << 22

    def __init__(self, physics, readers: dict[str, FieldGather]):
        self._physics = physics
        self._readers = readers
        self._in_numpy = physics.arrays.library == "numpy"
        self._dtype = physics.float_dtype
        n = physics.num_envs
        if self._in_numpy:
            self._layout: dict[str, tuple[int, int, tuple[int, ...]]] = {}
            offset = 0
            for name, reader in readers.items():
                width = reader.entries.shape[0]
                self._layout[name] = (offset, n * width, reader.shape)
                offset += n * width
            self._size = offset
            return
        wp = _warp.load().warp
        self._wp = wp
        sources: dict[int, int] = {}  # device address -> source index
        pointers, rows, sizes = [], [], []
        column_source, column_out, column_terms, column_op = [], [], [], []
        terms = max(reader.entries.shape[1] for reader in readers.values())
        entries, weights = [], []
        self._layout: dict[str, tuple[int, int, tuple[int, ...]]] = {}
        offset = 0
        for name, reader in readers.items():
            array = reader.field.device_array
            index = sources.setdefault(array.ptr, len(pointers))
            if index == len(pointers):
                pointers.append(array.ptr)
                entries_per_row = int(np.prod(reader.field.c_shape))
                rows.append(entries_per_row if reader.field.per_world else 0)
                sizes.append(array.capacity // 4)
            width = reader.entries.shape[0]
            for k in range(width):
                column_source.append(index)
                column_out.append((offset + k, width))
                column_terms.append(reader.entries.shape[1])
                column_op.append(reader.ops[k])
                padded = np.zeros(terms, np.int32)
                padded[: reader.entries.shape[1]] = reader.entries[k]
                entries.append(padded)
                padded = np.zeros(terms, np.float32)
                padded[: reader.weights.shape[1]] = reader.weights[k]
                weights.append(padded)
            self._layout[name] = (offset, n * width, reader.shape)
            offset += n * width
        self._size = offset
        self._reads_per_chunk = max(1, self.CHUNK_BYTES // (4 * max(offset, 1)))
        device = physics.device

        def put(values, dtype):
            return wp.array(np.asarray(values), dtype=dtype, device=device)

        self._inputs = [
            put(np.asarray(pointers, np.uint64), wp.uint64),
            put(np.asarray(rows, np.int32), wp.int32),
            put(np.asarray(sizes, np.int32), wp.int32),
            put(np.asarray(column_source, np.int32), wp.int32),
            put(np.asarray(column_out, np.int32), wp.int32),
            put(np.asarray(column_terms, np.int32), wp.int32),
            put(np.stack(entries), wp.int32),
            put(np.stack(weights), wp.float32),
            put(np.asarray(column_op, np.int32), wp.int32),
        ]
        self._launch = None
        self._chunk_view = None
        self._next = self._reads_per_chunk  # the next read's row in the chunk

    def _new_chunk(self) -> None:
        chunk, self._chunk_view = self._physics.arrays.empty(
            (self._reads_per_chunk, self._size), np.float32
        )
        if self._launch is None:
            self._launch = self._wp.launch(
                kernels.kernels().gather_columns,
                dim=self._physics.num_envs,
                inputs=[*self._inputs, 0],
                outputs=[chunk],
                device=self._physics.device,
                record_cmd=True,
            )
        else:
            self._launch.set_param_by_name("out", chunk)
        self._next = 0

    def read(self) -> dict[str, Any]:
        """Every gathered observable of every world, by key, in new device memory.

        Returns:
          Arrays of the batch's namespace, (num_envs, *value shape), of the batch's float
          dtype.
        """
        n = self._physics.num_envs
        if self._in_numpy:
            block = np.empty(self._size, self._dtype)
            values = {}
            for name, (offset, size, shape) in self._layout.items():
                rows = block[offset : offset + size].reshape((n, size // n))
                self._readers[name].take_into(rows)
                values[name] = rows.reshape((n, *shape))
            return values
        if self._next == self._reads_per_chunk:
            self._new_chunk()
        row = self._next
        self._next += 1
        self._launch.set_param_by_name("slot", row)
        self._launch.launch()
        block = self._chunk_view[row]
        return {
            name: block[offset : offset + size].reshape((n, *shape))
            for name, (offset, size, shape) in self._layout.items()
        }
