"""Array attribute values that may be written in place: `geom.rgba[3] = 0.5`.

Rule (the one place it is written down): an element stores array attributes as read-only
arrays, which copies of the element may share. The first time user code reads one
(`geom.rgba`), the element swaps in a writable copy it owns, an `AttributeArray`. Writing
into that array, or into a view of it, tells the owner, which then updates what it derived
from the value (its formatted XML text) and counts as modified exactly as after
`geom.rgba = ...`, unless the write left the array's bytes as they were (a variator that
writes the same value at every reset changes nothing a compile would see). Code inside the
package that hands a value to another element passes `frozen(value)`, so no two elements
ever share a writable array.
"""

from __future__ import annotations

import numpy as np


class AttributeArray(np.ndarray):
    """A writable array attribute value of an element; writes into it update the element.

    Arithmetic on it gives plain NumPy arrays; slicing gives views that are tied to the
    element as well.
    """

    def __array_finalize__(self, obj) -> None:
        # Views (slices, reshapes) write into the same memory: they report to the owner too.
        source = getattr(obj, "_source", None)
        base = self.base
        if source is not None and base is not None and (base is obj or base is obj.base):
            self._owner = obj._owner
            self._attribute = obj._attribute
            self._source = source
        else:
            self._owner = None
            self._attribute = None
            self._source = None

    def __setitem__(self, index, value) -> None:
        before = self._bytes()
        super().__setitem__(index, value)
        self._written(before)

    def __array_ufunc__(self, ufunc, method, *inputs, out=None, **kwargs):
        inputs = tuple(_plain(x) for x in inputs)
        if out is not None:
            kwargs["out"] = tuple(_plain(x) for x in out)
        watched = [x for x in out or () if isinstance(x, AttributeArray)]
        before = [x._bytes() for x in watched]
        result = getattr(ufunc, method)(*inputs, **kwargs)
        if out is None:
            return result
        for target, old in zip(watched, before):
            target._written(old)
        return out[0] if len(out) == 1 else out

    def __array_function__(self, func, types, args, kwargs):
        # np.copyto, np.put, np.place, np.putmask, ... write without item assignment or a
        # ufunc. Attribute arrays hold a few numbers, so compare them before and after.
        watched = [a for a in (*args, *kwargs.values()) if isinstance(a, AttributeArray)]
        before = [a._bytes() for a in watched]
        result = super().__array_function__(func, types, args, kwargs)
        for array, old in zip(watched, before):
            array._written(old)
        return result

    def fill(self, value) -> None:
        before = self._bytes()
        super().fill(value)
        self._written(before)

    def _bytes(self) -> bytes | None:
        """The bytes of the whole attribute value this array is (a view of), if owned."""
        source = self._source
        return None if source is None else source.tobytes()

    def _written(self, before: bytes | None) -> None:
        """Tells the owner, if the write changed the value's bytes from `before`."""
        owner = self._owner
        if owner is not None and self._source.tobytes() != before:
            owner._array_written(self._attribute, self._source)

    def __reduce__(self):
        return np.array(self).__reduce__()

    def __repr__(self) -> str:
        return repr(np.asarray(self))

    def __str__(self) -> str:
        return str(np.asarray(self))


def _plain(value):
    return value.view(np.ndarray) if isinstance(value, AttributeArray) else value


def owned(value: np.ndarray, owner, attribute: str) -> AttributeArray:
    """A writable copy of array `value` that reports writes to `owner._array_written`."""
    array = np.array(value).view(AttributeArray)
    array._owner = owner
    array._attribute = attribute
    array._source = array
    return array


def frozen(value):
    """`value`, with an element-owned writable array replaced by a read-only copy."""
    if isinstance(value, AttributeArray):
        value = np.array(value)
        value.flags.writeable = False
    return value
