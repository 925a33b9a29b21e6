"""`physics.named.model.<field>[name]` and `physics.named.data.<field>[name]`.

Each MjModel/MjData array field gets a `FieldIndexer` on first access. Rows of fields
that belong to an object family (`mujoco_physics.field_layout`) are addressed by the
objects' names in the compiled model: `named.data.xpos['torso']`,
`named.model.geom_rgba[['a', 'b']]`,
`named.data.qpos['free_joint']` (7 values), `named.data.sensordata['accelerometer']`.
Integers, slices and arrays index rows directly, as in NumPy; a tuple key indexes rows then
columns, and labelled columns accept names (`named.data.xpos['torso', 'z']`).
"""

import collections

import numpy as np

from mujoco_physics import field_layout
from mujoco_physics.field_layout import ModelLayout

NamedIndexStructs = collections.namedtuple("NamedIndexStructs", ["model", "data"])

Axes = collections.namedtuple("Axes", ["row", "col"], defaults=[None])
Axes.__doc__ = "The row and column axes of a field (`FieldIndexer.axes`); col is None for 1-D."


class Axis:
    """One axis of a field: `names` lists the labels it accepts, or is None when unnamed.

    For rows, `names` holds one name per object of the field's family in id order ('' for
    unnamed objects), also when an object owns several rows (`qpos` of a free joint).
    `convert_key_item(key)` turns a key for this axis (a name, a list of names, or anything
    NumPy accepts) into the NumPy index it selects, as the field indexer does.
    """

    __slots__ = ("names", "_convert")

    def __init__(self, names, convert=None):
        self.names = names
        self._convert = convert

    def convert_key_item(self, key_item):
        """Returns the NumPy index `key_item` selects on this axis.

        Raises:
          KeyError: for a name this axis does not have.
        """
        return key_item if self._convert is None else self._convert(key_item)

    def __repr__(self):
        return f"Axis(names={self.names!r})"


class _Rows:
    """Converts row keys of one field: names to indices, everything else passed through."""

    def __init__(self, layout: ModelLayout, family, rule, field: str):
        self._layout = layout
        self._family = family
        self._rule = rule
        self._field = field
        # Names and lists of names already converted: a model's names never change, and
        # task code reads the same names every step.
        self._converted = {}

    def convert(self, key):
        if isinstance(key, str):
            index = self._converted.get(key)
            if index is None:
                index = self._converted[key] = self._layout.single_index(self._rule, self._id(key))
            return index
        if isinstance(key, np.ndarray) and key.ndim > 1 and key.size and _is_name(key.flat[0]):
            # A grid of names (as np.ix_ makes): one row per name, in the grid's shape.
            rows = self._layout.multi_index(self._rule, [self._id(name) for name in key.flat])
            if rows.size != key.size:
                raise IndexError(
                    f"{self._field!r}: a {key.ndim}-D array of names needs objects with one "
                    f"row each, but some of {key.ravel().tolist()} own several rows"
                )
            return rows.reshape(key.shape)
        if isinstance(key, (list, np.ndarray)) and len(key) and _is_name(key[0]):
            if key.__class__ is list:
                try:
                    return self._converted[tuple(key)]
                except (KeyError, TypeError):
                    pass
            rows = self._layout.multi_index(self._rule, [self._id(name) for name in key])
            rows.flags.writeable = False
            if key.__class__ is list and all(map(_is_name, key)):
                self._converted[tuple(key)] = rows
            return rows
        return key

    def names(self) -> list | None:
        """One name per object of the family, in id order; None for unnamed rows."""
        family = self._family
        if family is None:
            return None
        layout = self._layout
        return [layout.object_name(family, i) for i in range(layout.object_count(family))]

    def labels(self, length: int) -> list:
        """The object name of each of `length` rows ('' where unknown)."""
        labels = [""] * length
        if self._family is None:
            return labels
        layout = self._layout
        for object_id in range(layout.object_count(self._family)):
            name = layout.object_name(self._family, object_id)
            index = layout.single_index(self._rule, object_id)
            if isinstance(index, slice):
                for row in range(index.start, index.stop):
                    labels[row] = name
            else:
                labels[index] = name
        return labels

    def _id(self, name) -> int:
        family = self._family
        if family is None:
            raise KeyError(f"rows of {self._field!r} have no names; index it with integers")
        object_id = self._layout.object_id(family, str(name))
        if object_id < 0:
            raise KeyError(
                f"{self._field!r}: no {family.namespace} named {str(name)!r} in this model"
            )
        rule = self._rule
        if rule is not None and rule.width == field_layout.AT_MOST_ONE:
            if self._layout.owned_rows(rule, object_id) == 0:
                raise KeyError(f"{self._field!r}: {family.namespace} {str(name)!r} has no row")
        return object_id


def _is_name(item) -> bool:
    return isinstance(item, (str, np.str_))


class FieldIndexer:
    """One MuJoCo array field, indexable by object names as well as by integers.

    Reading returns what NumPy indexing of the field returns (views for names of objects
    with consecutive rows); assignment writes into MuJoCo's memory. Other attributes are
    those of the NumPy array (`shape`, `dtype`, `copy()`, ...); `axes` gives the row
    and column labels.
    """

    __slots__ = ("_struct", "_name", "_array", "_rows")

    def __init__(self, struct, name: str, rows: _Rows, static: bool):
        self._struct = struct
        self._name = name
        self._array = getattr(struct, name) if static else None
        self._rows = rows

    @property
    def field(self) -> np.ndarray:
        """The whole MuJoCo array."""
        array = self._array
        return getattr(self._struct, self._name) if array is None else array

    def __getitem__(self, key):
        return self.field[self._convert(key)]

    def __setitem__(self, key, value):
        self.field[self._convert(key)] = value

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self.field, name)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(dir(self.field)))

    @property
    def axes(self) -> Axes:
        """`Axes(row, col)`: row labels (object names) and, for 2-D fields, column labels."""
        array = self.field
        row = Axis(self._rows.names(), self._rows.convert)
        if array.ndim < 2:
            return Axes(row)
        columns = field_layout.column_names(self._name, array.shape[1])
        width = array.shape[1]
        return Axes(
            row,
            Axis(
                None if columns is None else list(columns),
                lambda item: self._convert_column(item, width, 1),
            ),
        )

    def __len__(self):
        return len(self.field)

    def __array__(self, dtype=None, copy=None):
        return np.asarray(self.field, dtype=dtype)

    def _convert(self, key):
        if not isinstance(key, tuple):
            return self._rows.convert(key)
        array = self.field
        if len(key) > array.ndim:
            raise IndexError(
                f"{self._name!r} has {array.ndim} dimension(s) but the key has {len(key)}: {key!r}"
            )
        converted = [self._rows.convert(key[0])]
        for axis, item in enumerate(key[1:], start=1):
            converted.append(self._convert_column(item, array.shape[axis], axis))
        return tuple(converted)

    def _convert_column(self, item, width: int, axis: int):
        names = field_layout.column_names(self._name, width) if axis == 1 else None
        if isinstance(item, str):
            return self._column_index(item, names)
        if isinstance(item, (list, tuple)) and item and isinstance(item[0], str):
            return [self._column_index(label, names) for label in item]
        if isinstance(item, np.ndarray) and item.size and _is_name(item.flat[0]):
            indices = [self._column_index(str(label), names) for label in item.flat]
            return np.array(indices, dtype=np.intp).reshape(item.shape)
        return item

    def _column_index(self, label: str, names) -> int:
        if names is None or label not in names:
            known = f"columns are {names}" if names else "its columns have no names"
            raise KeyError(f"{self._name!r} has no column {label!r}; {known}")
        return names.index(label)

    def __repr__(self):
        array = self.field
        labels = self._rows.labels(len(array))
        columns = field_layout.column_names(self._name, array.shape[1]) if array.ndim > 1 else None
        name_width = max([len(label) for label in labels] + [0])
        index_width = len(str(max(len(array) - 1, 0)))
        lines = [f"FieldIndexer({self._name}):"]
        if columns:
            width = max(max(len(column) for column in columns), 9) + 1
            header = "".join(f"{column:<{width}}" for column in columns)
            lines.append(" " * (index_width + name_width + 4) + header)
        if not len(array):
            lines.append("(empty)")
        for row, (label, values) in enumerate(zip(labels, array)):
            text = np.array2string(
                np.atleast_1d(values), suppress_small=True, formatter={"float_kind": _format_float}
            )
            lines.append(f"{row:>{index_width}} {label:>{name_width}} {text}")
        return "\n".join(lines)


def _format_float(value) -> str:
    return f"{value: < 9.3g}"


class StructIndexer:
    """Named access to every array field of an MjModel or MjData (`physics.named.data`)."""

    def __init__(self, struct, kind: str, layout: ModelLayout):
        self._struct = struct
        self._kind = kind
        self._layout = layout
        self._extents = field_layout.STRUCT_EXTENTS[kind]

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        extents = self.__dict__["_extents"]
        if name not in extents:
            raise AttributeError(f"{self._kind} has no array field {name!r}")
        family, rule = field_layout.ROW_OWNERS.get((self._kind, name), (None, None))
        rows = _Rows(self._layout, family, rule, name)
        static = self._kind == field_layout.MODEL or hasattr(self._layout.model, extents[name][0])
        indexer = FieldIndexer(self._struct, name, rows, static)
        self.__dict__[name] = indexer
        return indexer

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(self._extents))

    def __repr__(self):
        return f"StructIndexer({self._kind}: {len(self._extents)} fields)"


def make_struct_indexers(model, data, layout: ModelLayout) -> NamedIndexStructs:
    """`NamedIndexStructs(model=..., data=...)` for raw `mujoco` model and data."""
    return NamedIndexStructs(
        model=StructIndexer(model, field_layout.MODEL, layout),
        data=StructIndexer(data, field_layout.DATA, layout),
    )
