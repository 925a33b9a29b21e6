"""`physics.bind(element)`: the MuJoCo fields of MJCF elements as attributes.

A binding's attributes are the MjModel/MjData fields of the elements' object family with the
family prefix stripped (`geom_rgba` -> `rgba`, `jnt_range` -> `range`,
`dof_damping` -> `damping`, `ten_length` -> `length`), as listed by
`mujoco_physics.field_layout`. Index arrays are computed once per attribute; rows that are
consecutive are served as NumPy views, other rows are gathered into a reused buffer.

Writes through a binding to an MjModel field or a simulation input (qpos, qvel, ctrl, ...)
mark the physics dirty; the next read of a derived quantity (xpos, sensordata, ...) through
any binding first runs `mj_forward`. Writes to the model's appearance fields (colours,
materials; `mjcf.appearance.forward_neutral_fields`) do not, since `mj_forward` does not
read them.
"""

import difflib

import mujoco
import numpy as np

from mjcf import mujoco_compat
from mujoco_physics import field_layout
from mujoco_physics.field_layout import MODEL, Family, ModelLayout

# MjData fields that are simulation inputs, named after the components of MuJoCo's state.
_INPUT_FIELDS = frozenset(
    member[len("mjSTATE_") :].lower() for member in mujoco.mjtState.__members__
) & frozenset(field_layout.DATA_EXTENTS)

# Writing a frame offset must stop MuJoCo from reusing the parent or inertial frame, which
# it does for objects flagged as sharing a frame at compile time.
_FRAME_FLAGS_CLEARED_ON_WRITE = {
    "pos": ("sameframe",),
    "quat": ("sameframe",),
    "ipos": ("simple", "sameframe"),
    "iquat": ("simple", "sameframe"),
}


PICKLING_NOT_SUPPORTED = (
    "a {type} cannot be pickled: it reads and writes the live simulation; "
    "pickle a copy instead (np.array(bound_array))"
)


class _BoundArray(np.ndarray):
    """Rows of a MuJoCo array read through a binding; item assignment writes them back.

    When `_source` is set the array is a gathered copy of `_source[_rows]`: an item
    assignment updates the copy, then writes the rows it touched back to the source.
    Otherwise it is a view and assignment reaches MuJoCo directly. `_after_write` runs
    after every assignment (marks the physics dirty, clears frame flags).
    """

    _source = None
    _rows = None
    _after_write = None

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        source = self._source
        if source is not None:
            values = self.view(np.ndarray)
            row_key = key[0] if isinstance(key, tuple) and key else key
            try:
                touched = np.arange(len(values))[row_key]
            except IndexError:
                touched = slice(None)
            source[self._rows[touched]] = values[touched]
        after_write = self._after_write
        if after_write is not None:
            after_write()

    def __array_wrap__(self, array, context=None, return_scalar=False):
        if return_scalar:
            return array[()]
        return array.view(np.ndarray)

    def __repr__(self):
        return repr(self.view(np.ndarray))

    def copy(self, order="C"):
        return np.array(self, order=order)

    def __copy__(self):
        return self.copy()

    def __deepcopy__(self, memo):
        return self.copy()

    def __reduce__(self):
        # An unpickled copy could no longer write to MuJoCo: refuse, as dm_control does.
        raise NotImplementedError(PICKLING_NOT_SUPPORTED.format(type=type(self)))


def _bound_array(array: np.ndarray, source, rows, after_write) -> _BoundArray:
    bound = array.view(_BoundArray)
    bound._source = source
    bound._rows = rows
    bound._after_write = after_write
    return bound


def describe(element) -> str:
    """A short description of an MJCF element for error messages: <geom name='arm/box'>."""
    try:
        name = element.full_identifier
    except AttributeError:
        name = None
    tag = getattr(element, "tag", type(element).__name__)
    return f"<{tag} name={name!r}>" if name else f"<{tag}>"


def element_namespace(element) -> str | None:
    """The MuJoCo object family an element compiles to ('body' for the worldbody)."""
    if element.tag == "worldbody":
        return "body"
    return element.spec.namespace


class _BoundFieldAccessor:
    """Reads one field of a binding's elements: the class-level (non-data) descriptor of a
    binding attribute such as `xpos`, made once per object family."""

    __slots__ = ("name",)

    def __init__(self, name: str):
        self.name = name

    def __get__(self, binding, owner=None):
        if binding is None:
            return self
        getter = binding._getters.get(self.name)
        if getter is None:
            return binding._first_read(self.name)
        return getter()


class Binding:
    """The MjModel/MjData fields of one MJCF element, or of a list of same-family elements.

    Attribute names are MuJoCo field names with the family prefix stripped: for a geom
    `xpos`, `xmat`, `size`, `rgba`, `pos`, `friction`, ...; for a joint `qpos`,
    `qvel`, `qfrc_actuator`, `range`, `axis`, `damping`, `armature`, ...; for an
    actuator `ctrl`, `act`, `force`, `length`, `gear`, `ctrlrange`, ...; for a
    sensor `sensordata`; for a mocap body `mocap_pos` and `mocap_quat`.

    For a single element, a field with one value per object reads as a NumPy scalar and a
    field with k values as a (k,) view; fields addressed by position (`qpos`, dof fields,
    `sensordata`) read as arrays as wide as the element's share (4 for a ball joint's qpos,
    3 for a 3-D sensor). For a list of n elements fields read as (n,) or (n, k) arrays, and
    position-addressed fields as the concatenation of each element's share. Arrays read from
    a binding write through on item assignment (`binding.rgba[:, 3] = 0.5`); attribute
    assignment (`binding.qpos = 0.3`) writes too. Arrays are reused between reads: copy
    them to keep a value.

    `binding['pos']` and `binding['pos', ['x', 'z']]` index by attribute name and, for
    fields with labelled columns (xyz, quaternions, rgba, rotation matrices), by column.
    """

    def __new__(cls, physics, namespace: str, named_index):
        family = field_layout.FAMILIES.get(namespace)
        if family is None:
            raise ValueError(
                f"elements of namespace {namespace!r} cannot be bound to physics; namespaces "
                f"with MuJoCo fields: {', '.join(sorted(field_layout.FAMILIES))}"
            )
        return object.__new__(_binding_class(family))

    def __init__(self, physics, namespace: str, named_index):
        """Binds the objects of `namespace` named `named_index` (a name, or a list of
        names, as in the compiled model) in `physics`; `physics.bind` is the usual way.

        Raises:
          ValueError: no MuJoCo fields for `namespace`, or no object of that name.
        """
        family = field_layout.FAMILIES[namespace]
        layout = physics.field_layout
        single = isinstance(named_index, str)
        names = [named_index] if single else list(named_index)
        ids = []
        for name in names:
            object_id = layout.object_id(family, name)
            if object_id < 0:
                raise ValueError(f"the model has no {namespace} named {name!r}")
            ids.append(object_id)
        label = f"<{namespace} name={named_index!r}>" if single else f"[{len(ids)} {namespace}]"
        self._setup(physics._sim, layout, family, ids[0] if single else tuple(ids), single, label)

    @classmethod
    def _from_ids(cls, sim, layout: ModelLayout, family: Family, ids, single: bool, label: str):
        binding = object.__new__(cls)
        binding._setup(sim, layout, family, ids, single, label)
        return binding

    def _setup(self, sim, layout: ModelLayout, family: Family, ids, single: bool, label: str):
        self.__dict__.update(
            _sim=sim,
            _layout=layout,
            _family=family,
            _ids=ids,
            _single=single,
            _label=label,
            _getters={},
            _setters={},
        )

    @property
    def element_id(self):
        """The MuJoCo id of the bound element (an int), or of each element (an int array)."""
        if self._single:
            return self._ids
        ids = np.array(self._ids, dtype=int)
        ids.flags.writeable = False
        return ids

    def __getattr__(self, name):
        # Only reached for names that are not attributes of this family.
        if name.startswith("__"):
            raise AttributeError(name)
        self._ref(name)
        return self._first_read(name)

    def __setattr__(self, name, value):
        setter = self._setters.get(name)
        if setter is None:
            setter = self._build(name)[1]
        setter(value)

    def __getitem__(self, key):
        name, columns = self._split_key(key)
        value = getattr(self, name)
        if columns is None:
            return value
        return value[..., columns]

    def __setitem__(self, key, value):
        name, columns = self._split_key(key)
        if columns is None:
            setattr(self, name, value)
        else:
            getattr(self, name)[..., columns] = value

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(self._family.fields))

    def __repr__(self):
        return f"Binding({self._label})"

    def _first_read(self, name: str):
        read = self._build(name)[0]
        value = read()
        if read.constant:
            # The value is a view that needs no refresh: later reads skip the descriptor.
            self.__dict__[name] = value
        return value

    def _split_key(self, key):
        if not isinstance(key, tuple):
            return key, None
        name, columns = key
        ref = self._ref(name)
        array = getattr(self._sim.model if ref.struct == MODEL else self._sim.data, ref.name)
        labels = field_layout.column_names(ref.name, array.shape[-1]) if array.ndim > 1 else None
        return name, _convert_columns(columns, labels, ref.name)

    def _ref(self, name: str) -> field_layout.FieldRef:
        ref = self._family.fields.get(name)
        if ref is None:
            missing = mujoco_compat.missing_binding(self._family.namespace, name)
            if missing:
                raise AttributeError(f"{self._label} has no attribute {name!r}: {missing}")
            close = difflib.get_close_matches(name, self._family.fields, n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise AttributeError(f"{self._label} has no attribute {name!r}{hint}")
        return ref

    def _build(self, name: str):
        """Creates, caches and returns the (getter, setter) pair for attribute `name`."""
        ref = self._ref(name)
        sim = self._sim
        array = getattr(sim.model if ref.struct == MODEL else sim.data, ref.name)
        index = self._index(ref, name)
        is_input = ref.struct == MODEL or ref.name in _INPUT_FIELDS
        after_write = self._after_write(ref, name) if is_input else None
        constant = False

        if isinstance(index, int) and array.ndim == 1:
            if is_input:

                def read():
                    return array[index]

            else:

                def read():
                    if sim.dirty:
                        sim.forward()
                    return array[index]

        elif isinstance(index, np.ndarray):
            buffer = _bound_array(array[index], array, index, after_write)
            take = array.take
            if is_input:

                def read():
                    take(index, 0, buffer, "clip")
                    return buffer

            else:

                def read():
                    if sim.dirty:
                        sim.forward()
                    take(index, 0, buffer, "clip")
                    return buffer

        elif is_input:
            view = _bound_array(array[index], None, None, after_write)
            constant = True

            def read():
                return view

        else:
            # A `_BoundArray` too, only so that pickling it is refused like the others.
            view = _bound_array(array[index], None, None, None)

            def read():
                if sim.dirty:
                    sim.forward()
                return view

        if after_write is None and is_input:

            def write(value):
                array[index] = value

        elif is_input:

            def write(value):
                array[index] = value
                after_write()

        else:

            def write(value):
                # Bring derived quantities up to date first, so that a later recompute
                # does not overwrite the value written.
                if sim.dirty:
                    sim.forward()
                array[index] = value

        read.constant = constant
        self._getters[name] = read
        self._setters[name] = write
        return read, write

    def _index(self, ref: field_layout.FieldRef, name: str):
        layout = self._layout
        rule = ref.addressing
        ids = [self._ids] if self._single else self._ids
        if rule is not None and rule.width == field_layout.AT_MOST_ONE:
            for object_id in ids:
                if layout.owned_rows(rule, object_id) == 0:
                    owner = self._layout.object_name(self._family, object_id)
                    raise AttributeError(
                        f"{self._label} has no attribute {name!r}: {self._family.namespace} "
                        f"{owner!r} has no row in {ref.name}"
                    )
        if self._single:
            return layout.single_index(rule, self._ids)
        return field_layout.compress(layout.multi_index(rule, self._ids))

    def _after_write(self, ref: field_layout.FieldRef, name: str):
        """What a write to input field `ref` must do next; None when nothing."""
        sim = self._sim
        if ref.name in sim.forward_neutral:
            return None
        cleared = []
        if ref.struct == MODEL and ref.addressing is None:
            for flag in _FRAME_FLAGS_CLEARED_ON_WRITE.get(name, ()):
                flag_ref = self._family.fields.get(flag)
                if flag_ref is not None and flag_ref.struct == MODEL:
                    cleared.append(getattr(sim.model, flag_ref.name))
        rows = self._ids if self._single else np.asarray(self._ids, dtype=np.intp)

        def after_write():
            sim.dirty = True
            for flags in cleared:
                flags[rows] = 0

        return after_write


def _convert_columns(columns, labels, field: str):
    """Column labels ('x', ['x', 'z']) -> integer column indices for `field`."""
    if isinstance(columns, str):
        columns_list, single = [columns], True
    elif isinstance(columns, (list, tuple)) and columns and isinstance(columns[0], str):
        columns_list, single = list(columns), False
    else:
        return columns
    if labels is None:
        raise KeyError(f"field {field!r} has no column labels; got {columns!r}")
    indices = []
    for label in columns_list:
        if label not in labels:
            raise KeyError(f"field {field!r} has no column {label!r}; columns are {labels}")
        indices.append(labels.index(label))
    return indices[0] if single else indices


class EmptyBinding:
    """What `physics.bind([])` returns: every attribute reads as an empty array."""

    __slots__ = ()

    _EMPTY = np.empty(0)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return self._EMPTY

    def __setattr__(self, name, value):
        raise ValueError(f"cannot assign {name!r}: this binding has no elements")

    def __repr__(self):
        return "Binding()"


EMPTY_BINDING = EmptyBinding()


def create(sim, layout: ModelLayout, root, elements, single: bool) -> Binding:
    """A binding of `elements` (one element when `single`) to the simulation `sim`.

    Args:
      sim: the physics' simulation state (`model`, `data`, `dirty`, `forward()`).
      layout: row look-ups for `sim.model`.
      root: the `mjcf.RootElement` compiled into `sim.model`, or None when unknown.
      elements: an element, or a tuple of elements of one family.
      single: whether `elements` is one element.

    Raises:
      ValueError: for elements with no compiled counterpart, of mixed families, or that
        belong to another model.
    """
    members = (elements,) if single else elements
    namespace = None
    for position, element in enumerate(members):
        if not hasattr(element, "tag"):
            raise ValueError(
                f"bind expects mjcf elements; item {position} is a {type(element).__name__}"
            )
        element_ns = element_namespace(element)
        if element_ns is None:
            raise ValueError(
                f"cannot bind {describe(element)}: <{element.tag}> elements are not compiled "
                "into a MuJoCo object"
            )
        if namespace is None:
            namespace, first = element_ns, element
        elif element_ns != namespace:
            raise ValueError(
                f"cannot bind elements of different kinds together: {describe(first)} is a "
                f"{namespace}, {describe(element)} is a {element_ns}"
            )
        elif element_ns == "body" and _is_mocap(element) != _is_mocap(first):
            # Mocap bodies have fields (mocap_pos, mocap_quat) that other bodies lack.
            mocap, other = (element, first) if _is_mocap(element) else (first, element)
            raise ValueError(
                f"cannot bind mocap and other bodies together: {describe(mocap)} is a mocap "
                f"body, {describe(other)} is not"
            )
    family = field_layout.FAMILIES.get(namespace)
    if family is None:
        raise ValueError(f"cannot bind {describe(members[0])}: no MuJoCo fields for {namespace!r}")
    ids = tuple(_object_id(layout, family, root, element) for element in members)
    if single:
        return _binding_class(family)._from_ids(
            sim, layout, family, ids[0], True, describe(elements)
        )
    label = f"{len(ids)} {namespace} elements" if len(ids) != 1 else describe(members[0])
    return _binding_class(family)._from_ids(sim, layout, family, ids, False, f"[{label}]")


def compiled_field(element, xml_name: str) -> field_layout.FieldRef | None:
    """The MuJoCo field that `element`'s attribute `xml_name` compiles into (the binding
    attribute of the same Python name: `rgba` of a geom is `geom_rgba`), or None."""
    spec = element.spec.attributes.get(xml_name)
    family = field_layout.FAMILIES.get(element_namespace(element) or "")
    if spec is None or family is None:
        return None
    return family.fields.get(spec.python_name)


def object_id(layout: ModelLayout, root, element) -> int:
    """The id of `element`'s compiled object in the model `layout` describes, compiled from
    `root`: what `create(...).element_id` gives, without making a binding.

    Raises:
      ValueError: for an element with no compiled counterpart, or of another model.
    """
    namespace = element_namespace(element)
    family = field_layout.FAMILIES.get(namespace) if namespace is not None else None
    if family is None:
        raise ValueError(f"{describe(element)} is not compiled into a MuJoCo object")
    return _object_id(layout, family, root, element)


def _is_mocap(element) -> bool:
    return getattr(element, "mocap", None) == "true"


_BINDING_CLASSES = {}


def _binding_class(family: Family) -> type:
    """The Binding subclass with one class-level accessor per attribute of `family`."""
    cls = _BINDING_CLASSES.get(family.namespace)
    if cls is None:
        accessors = {
            name: _BoundFieldAccessor(name) for name in family.fields if not hasattr(Binding, name)
        }
        cls = type(f"{family.namespace.title()}Binding", (Binding,), accessors)
        _BINDING_CLASSES[family.namespace] = cls
    return cls


def _object_id(layout: ModelLayout, family: Family, root, element) -> int:
    if element.tag == "worldbody" and (root is None or element.root is root):
        return 0
    # An attached model's worldbody is named after (and compiles to) its attachment frame.
    name = element.full_identifier
    if root is not None and not _belongs(root, element, family.namespace, name):
        hint = ""
        if _model_name(element.root) == _model_name(root):
            hint = (
                "; they are different objects of the same name (a copy made by pickling or "
                "copy.deepcopy binds its own elements, not the original's)"
            )
        raise ValueError(
            f"cannot bind {describe(element)}: it belongs to another model "
            f"({_model_name(element.root)}), not to the model compiled into this Physics "
            f"({_model_name(root)}){hint}"
        )
    object_id = layout.object_id(family, name)
    if object_id < 0:
        raise ValueError(
            f"cannot bind {describe(element)}: the model compiled into this Physics has no "
            f"{family.namespace} named {name!r}"
        )
    return object_id


def _belongs(root, element, namespace: str, name: str) -> bool:
    """Whether `element` is in `root`'s tree or in a model attached below it."""
    model = element.root
    if not hasattr(model, "parent_model"):
        return root.find(namespace, name) is element or any(
            candidate is element for candidate in root.find_all(namespace)
        )
    while model is not None:
        if model is root:
            return True
        model = model.parent_model
    return False


def _model_name(root) -> str:
    return repr(getattr(root, "model", None) or "unnamed model")
