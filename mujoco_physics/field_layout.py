"""Which MuJoCo object owns each row of an MjModel/MjData array.

Everything here is derived from the array extents that the installed `mujoco` package
publishes in `mujoco.introspect` (the X-macros of MuJoCo's C headers): an array whose first
extent is an object count (`ngeom`, `njnt`, ...) has one row per object of that family;
arrays sized by `nq`, `nv`, `nsensordata`, `na`, ... are addressed through the
per-object start/width arrays listed in `_ADDRESSING`. A field MuJoCo adds in a new release
is picked up without a change here.

`MODEL_FIELDS` and `DATA_FIELDS` list, from the same source, every field the bindings
expose on MjModel and MjData by kind (arrays of numbers, of characters, single numbers,
nested structs): code that walks a whole model or data reads them instead of `dir()`.
"""

import dataclasses
import re
from collections.abc import Sequence

import mujoco
import numpy as np
from mujoco.introspect import ast_nodes as _ast_nodes
from mujoco.introspect import structs as _introspect

MODEL = "model"
DATA = "data"

_NAME_ADDRESS_PREFIX = "name_"
_NAME_ADDRESS_SUFFIX = "adr"

# Column labels for the trailing axis of a field, chosen by the field's width and name.
_XYZ = ("x", "y", "z")
_QUATERNION = ("qw", "qx", "qy", "qz")
_RGBA = ("r", "g", "b", "a")
_ROTATION_MATRIX = ("xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz")


@dataclasses.dataclass(frozen=True)
class _Addressing:
    """How rows of arrays sized by one extent map onto the objects of a family.

    Attributes:
      family: namespace of the owning family.
      start: MjModel field holding each object's first row.
      width: MjModel field holding each object's row count; `NEXT_START` when an object's
        rows run up to the next object's first row; `AT_MOST_ONE` when an object owns one
        row, or none where `start` is -1.
      ragged: whether a single object yields an array even when it owns one row.
      prefix: an extra field-name prefix stripped for bindings of this family.
    """

    family: str
    start: str
    width: str
    ragged: bool
    prefix: str = ""


NEXT_START = "<next start>"
AT_MOST_ONE = "<at most one>"

# Arrays whose rows belong to objects but whose size is not the object count.
_ADDRESSING = {
    "nq": _Addressing("joint", "jnt_qposadr", NEXT_START, ragged=True),
    "nv": _Addressing("joint", "jnt_dofadr", NEXT_START, ragged=True, prefix="dof"),
    "nsensordata": _Addressing("sensor", "sensor_adr", "sensor_dim", ragged=True),
    "nnumericdata": _Addressing("numeric", "numeric_adr", "numeric_size", ragged=True),
    "na": _Addressing("actuator", "actuator_actadr", "actuator_actnum", ragged=False),
    "nu": _Addressing("actuator", "actuator_ctrladr", "actuator_ctrlnum", ragged=False),
    "nout": _Addressing("actuator", "actuator_outadr", "actuator_outnum", ragged=False),
    "nmocap": _Addressing("body", "body_mocapid", AT_MOST_ONE, ragged=False),
}


@dataclasses.dataclass(frozen=True)
class FieldRef:
    """One MjModel/MjData array as seen from an object family.

    Attributes:
      struct: `MODEL` or `DATA`.
      name: the MuJoCo field name (`geom_xpos`).
      addressing: `None` when the field has one row per object, else how rows map.
    """

    struct: str
    name: str
    addressing: _Addressing | None


@dataclasses.dataclass(frozen=True)
class Family:
    """A kind of named MuJoCo object (`geom`, `joint`, ...) and its fields.

    Attributes:
      namespace: the MJCF namespace, equal to the lowercase `mjtObj` name.
      obj_type: the `mujoco.mjtObj` value.
      count: the extent symbol counting the family's objects (`ngeom`).
      fields: binding attribute name (family prefix stripped) -> `FieldRef`.
    """

    namespace: str
    obj_type: mujoco.mjtObj
    count: str
    fields: dict


# A pointer field's size as its doc comment gives it: "(nv x mjNREF)", "(ngeom x 1)".
_DOC_EXTENT = re.compile(r"\((n\w+) x (\w+)\)")


def _extent_from_doc(field) -> tuple | None:
    """The extents of a pointer field that `introspect` left without (mujoco 3.3.0 does so
    for `dof_solref`, `geom_margin` and a few more), read from its doc comment."""
    if not isinstance(field.type, _ast_nodes.PointerType):
        return None
    match = _DOC_EXTENT.search(field.doc)
    if match is None:
        return None
    count, width = match.groups()
    if width == "1":
        return (count,)
    return (count, int(width) if width.isdigit() else width)


def _array_extents(struct_name: str, python_type: type) -> dict:
    """Field name -> extents for every array field the Python bindings expose."""
    extents = {}
    for field in _introspect.STRUCTS[struct_name].fields:
        extent = getattr(field, "array_extent", None) or _extent_from_doc(field)
        if extent and isinstance(extent[0], str) and hasattr(python_type, field.name):
            extents[field.name] = tuple(extent)
    return extents


MODEL_EXTENTS = _array_extents("mjModel", mujoco.MjModel)
DATA_EXTENTS = _array_extents("mjData", mujoco.MjData)
STRUCT_EXTENTS = {MODEL: MODEL_EXTENTS, DATA: DATA_EXTENTS}


@dataclasses.dataclass(frozen=True)
class StructFields:
    """The fields the Python bindings expose on MjModel or MjData, by kind, each in the
    order of MuJoCo's header.

    Attributes:
      arrays: arrays of numbers, which read as NumPy arrays (`geom_size`, `qpos`,
        `solver_niter`).
      texts: arrays of characters: the name, path and text buffers (`names`, `paths`,
        `text_data`, which read as bytes) and `plugin_attr` (an int8 array).
      scalars: single numbers: sizes (`nq`, `ngeom`, `nbuffer`), flags (`flg_gravcomp`),
        `signature`; for MjData also `time`, `ncon`, ...
      structs: nested MuJoCo structs (`opt`, `vis`, `stat`).

    Arrays of structs (`data.contact`, `data.solver`) are in none of these.
    """

    arrays: tuple[str, ...]
    texts: tuple[str, ...]
    scalars: tuple[str, ...]
    structs: tuple[str, ...]


_CHARACTER = "char"
# The element type of raw memory (the model's buffer), which reads as no value.
_RAW = "void"


def _field_kind(field_type) -> str | None:
    """The `StructFields` attribute that lists a field of C type `field_type`, or None."""
    is_array = isinstance(field_type, (_ast_nodes.PointerType, _ast_nodes.ArrayType))
    element = field_type.inner_type if is_array else field_type
    if not isinstance(element, _ast_nodes.ValueType) or element.name == _RAW:
        return None
    if element.name in _introspect.STRUCTS:
        return None if is_array else "structs"
    if element.name == _CHARACTER:
        return "texts" if is_array else None
    return "arrays" if is_array else "scalars"


def _struct_fields(struct_name: str, python_type: type) -> StructFields:
    """The fields of C struct `struct_name` that `python_type` exposes, by kind."""
    listed = {kind.name: [] for kind in dataclasses.fields(StructFields)}
    for field in _introspect.STRUCTS[struct_name].fields:
        kind = _field_kind(field.type)
        if kind is not None and hasattr(python_type, field.name):
            listed[kind].append(field.name)
    return StructFields(**{kind: tuple(names) for kind, names in listed.items()})


MODEL_FIELDS = _struct_fields("mjModel", mujoco.MjModel)
DATA_FIELDS = _struct_fields("mjData", mujoco.MjData)


def _abbreviates(word: str, name: str) -> bool:
    """Whether `word` is `name` or an abbreviation of it ('jnt' of 'joint')."""
    if not word or word[0] != name[0]:
        return False
    remaining = iter(name)
    return all(letter in remaining for letter in word)


def _namespaces_by_short_name() -> dict:
    """Short name used in field prefixes ('jnt') -> mjtObj namespace ('joint')."""
    object_names = [
        member[len("mjOBJ_") :].lower()
        for member in mujoco.mjtObj.__members__
        if member.startswith("mjOBJ_")
    ]
    short_names = [
        field[len(_NAME_ADDRESS_PREFIX) : -len(_NAME_ADDRESS_SUFFIX)]
        for field in MODEL_EXTENTS
        if field.startswith(_NAME_ADDRESS_PREFIX) and field.endswith(_NAME_ADDRESS_SUFFIX)
    ]
    exact = {short: short for short in short_names if short in object_names}
    unclaimed = [name for name in object_names if name not in exact]
    mapping = dict(exact)
    for short in short_names:
        if short in exact:
            continue
        matches = [name for name in unclaimed if _abbreviates(short, name)]
        if len(matches) == 1:
            mapping[short] = matches[0]
    return mapping


def _supported_addressings(namespace: str, count: str) -> dict:
    """The `_ADDRESSING` rules of family `namespace` that this MuJoCo version has."""
    return {
        extent: rule
        for extent, rule in _ADDRESSING.items()
        if rule.family == namespace
        and extent != count
        and rule.start in MODEL_EXTENTS
        and (rule.width in (NEXT_START, AT_MOST_ONE) or rule.width in MODEL_EXTENTS)
    }


# Namespace -> the extent symbol counting that family's objects ('geom' -> 'ngeom').
_FAMILY_COUNTS = {
    namespace: MODEL_EXTENTS[f"{_NAME_ADDRESS_PREFIX}{short}{_NAME_ADDRESS_SUFFIX}"][0]
    for short, namespace in _namespaces_by_short_name().items()
}


def _build_row_owners() -> dict:
    """(struct, field) -> (namespace, addressing or None) for fields whose rows are objects."""
    owners_by_extent = {}
    for namespace, count in _FAMILY_COUNTS.items():
        owners_by_extent[count] = (namespace, None)
        for extent, rule in _supported_addressings(namespace, count).items():
            owners_by_extent[extent] = (namespace, rule)
    return {
        (struct, field): owners_by_extent[extent[0]]
        for struct, extents in STRUCT_EXTENTS.items()
        for field, extent in extents.items()
        if extent[0] in owners_by_extent
    }


_ROW_OWNERS = _build_row_owners()

# Binding attributes are written in this order, so later kinds win a name clash.
_ATTRIBUTE_PRECEDENCE = {(True, DATA): 0, (True, MODEL): 1, (False, DATA): 2, (False, MODEL): 3}


def _family_fields(namespace: str) -> dict:
    """Binding attribute -> FieldRef for family `namespace`, prefixes stripped.

    A leading word is stripped when it abbreviates the namespace and prefixes the family's
    per-object fields ('jnt_', 'ten_'), or is the extra prefix of an addressing rule ('dof_').
    On a clash per-object fields win over addressed ones, and MjModel over MjData fields.
    """
    owned = [
        (struct, field, rule)
        for (struct, field), (owner, rule) in _ROW_OWNERS.items()
        if owner == namespace
    ]
    prefixes = {rule.prefix for _, _, rule in owned if rule is not None and rule.prefix}
    for _, field, rule in owned:
        word = field.split("_", 1)[0]
        if rule is None and "_" in field and _abbreviates(word, namespace):
            prefixes.add(word)
    fields = {}
    for struct, field, rule in sorted(
        owned, key=lambda item: _ATTRIBUTE_PRECEDENCE[item[2] is not None, item[0]]
    ):
        word, _, rest = field.partition("_")
        attribute = rest if rest and word in prefixes else field
        fields[attribute] = FieldRef(struct, field, rule)
    return fields


def _build_families() -> dict:
    """Namespace -> `Family` for every named MuJoCo object kind."""
    return {
        namespace: Family(
            namespace=namespace,
            obj_type=mujoco.mjtObj.__members__[f"mjOBJ_{namespace.upper()}"],
            count=count,
            fields=_family_fields(namespace),
        )
        for namespace, count in _FAMILY_COUNTS.items()
    }


FAMILIES = _build_families()

# (struct, field) -> (Family, addressing or None) for every field whose rows are objects.
ROW_OWNERS = {key: (FAMILIES[namespace], rule) for key, (namespace, rule) in _ROW_OWNERS.items()}


def column_names(field: str, width: int) -> tuple | None:
    """Labels for the trailing axis of `field` ('x', 'y', 'z' for positions), or None."""
    if width == 3:
        return _XYZ
    if width == 4 and "quat" in field:
        return _QUATERNION
    if width == 4 and "rgba" in field:
        return _RGBA
    if width == 9 and "mat" in field:
        return _ROTATION_MATRIX
    return None


class ModelLayout:
    """Row look-ups for one compiled `mujoco.MjModel`: object ids, names and row indices."""

    def __init__(self, model: mujoco.MjModel):
        self._model = model
        self._spans = {}

    @property
    def model(self) -> mujoco.MjModel:
        return self._model

    def object_id(self, family: Family, name: str) -> int:
        """The id of the `family` object called `name`, or -1 if there is none."""
        return mujoco.mj_name2id(self._model, family.obj_type, name)

    def object_name(self, family: Family, object_id: int) -> str:
        """The name of object `object_id` of `family` ('' when unnamed)."""
        return mujoco.mj_id2name(self._model, family.obj_type, object_id) or ""

    def object_count(self, family: Family) -> int:
        return int(getattr(self._model, family.count))

    def spans(self, rule: _Addressing) -> tuple:
        """(first rows, row counts) of every object of `rule.family`, as int arrays."""
        spans = self._spans.get(rule)
        if spans is None:
            starts = np.asarray(getattr(self._model, rule.start), dtype=np.intp).ravel()
            if rule.width == NEXT_START:
                total = int(getattr(self._model, _extent_of(rule)))
                widths = np.diff(np.append(starts, total))
            elif rule.width == AT_MOST_ONE:
                widths = (starts >= 0).astype(np.intp)
            else:
                widths = np.asarray(getattr(self._model, rule.width), dtype=np.intp).ravel()
            spans = (starts, widths)
            self._spans[rule] = spans
        return spans

    def single_index(self, rule: _Addressing | None, object_id: int):
        """Index into a field's rows selecting one object: an int or a slice."""
        if rule is None:
            return object_id
        starts, widths = self.spans(rule)
        start, width = int(starts[object_id]), int(widths[object_id])
        if width == 1 and not rule.ragged:
            return start
        return slice(start, start + width)

    def multi_index(self, rule: _Addressing | None, object_ids: Sequence[int]) -> np.ndarray:
        """Row indices of several objects, concatenated in the order given."""
        ids = np.asarray(object_ids, dtype=np.intp)
        if rule is None:
            return ids
        starts, widths = self.spans(rule)
        counts = widths[ids]
        firsts = starts[ids]
        total = int(counts.sum())
        offsets = np.repeat(firsts - np.cumsum(counts) + counts, counts)
        return offsets + np.arange(total, dtype=np.intp)

    def owned_rows(self, rule: _Addressing | None, object_id: int) -> int:
        """How many rows of a field object `object_id` owns."""
        if rule is None:
            return 1
        return int(self.spans(rule)[1][object_id])


def _extent_of(rule: _Addressing) -> str:
    return next(extent for extent, candidate in _ADDRESSING.items() if candidate is rule)


def compress(index: np.ndarray):
    """A basic slice equal to `index` when its rows are consecutive, else `index`."""
    if len(index) and index[-1] - index[0] == len(index) - 1:
        if len(index) == 1 or np.all(np.diff(index) == 1):
            return slice(int(index[0]), int(index[-1]) + 1)
    return index
