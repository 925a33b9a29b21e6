"""Value types of MJCF attributes: conversion of user input and formatting for XML.

Which attribute has which type is decided by `mjcf.attribute_table`.
"""

from __future__ import annotations

import numpy as np

from mjcf.asset import Asset

# Kinds, used by the XML writer to dispatch without isinstance checks.
STRING = 0
IDENTIFIER = 1
REFERENCE = 2
FILE = 3
OTHER = 4
NAME_PREFIX = 5


def format_float(value: float, precision: int, zero_threshold: float) -> str:
    """Formats one float for XML: shortest exact form at full precision, no trailing '.0'."""
    if zero_threshold and abs(value) < zero_threshold:
        return "0"
    if precision >= 17:
        text = repr(value)
    else:
        text = f"{value:.{precision}g}"
    if text.endswith(".0"):
        return text[:-2]
    return text


_ESCAPES = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"})


def escape(text: str) -> str:
    """Escapes text for use inside a double-quoted XML attribute."""
    if "&" in text or "<" in text or ">" in text or '"' in text:
        return text.translate(_ESCAPES)
    return text


def xml_text(name: str, attribute_type, value, precision: int = 17, zero_threshold=0) -> str:
    """' name="value"' for a plain (not identifier, reference or file) attribute."""
    if attribute_type.kind == STRING:
        return f' {name}="{escape(value)}"'
    return f' {name}="{attribute_type.format(value, precision, zero_threshold)}"'


def _join_floats(values, precision: int, zero_threshold: float) -> str:
    if precision >= 17 and not zero_threshold:
        # repr is the shortest exact form; drop the '.0' of whole numbers.
        return (" ".join(map(repr, values)) + " ").replace(".0 ", " ")[:-1]
    return " ".join(format_float(v, precision, zero_threshold) for v in values)


def _describe_length(lengths: tuple[int, int | None]) -> str:
    low, high = lengths
    if high is None:
        return f"at least {low}"
    if low == high:
        return f"exactly {low}"
    return f"{low} to {high}"


class AttributeType:
    """Base of all attribute types: `convert` validates input, `format` writes XML text."""

    __slots__ = ()
    kind = OTHER
    description = "a string"

    def convert(self, value):
        if isinstance(value, str):
            return value
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, (list, tuple, np.ndarray)):
            items = np.asarray(value).ravel().tolist()
            return " ".join(
                format_float(v, 17, 0) if isinstance(v, float) else str(v) for v in items
            )
        if isinstance(value, float):
            return format_float(value, 17, 0)
        return str(value)

    def format(self, value, precision: int, zero_threshold: float) -> str:
        return value


class String(AttributeType):
    """Free text, written as given."""

    __slots__ = ()
    kind = STRING


class NamePrefix(String):
    """Text MuJoCo puts before the names it copies in (`<attach prefix>`): written after the
    scope prefix of the model that holds it, so that a model attached twice names each
    copy's copies apart."""

    __slots__ = ()
    kind = NAME_PREFIX


class Identifier(AttributeType):
    """A name that is unique within its namespace (`name`, or `class` of a default)."""

    __slots__ = ()
    kind = IDENTIFIER
    description = "an identifier string"

    def convert(self, value):
        if not isinstance(value, str):
            raise ValueError(f"expected a string identifier, got {value!r}")
        return value


# `objtype` values whose namespace differs from their name.
_OBJTYPE_NAMESPACES = {"xbody": "body"}


class Reference(AttributeType):
    """A reference to another element: an `Element` or its (possibly scoped) identifier.

    `namespace` is the namespace of the target, or None when another attribute of the same
    element names it (`namespace_attribute`, e.g. `objtype` for `objname`).
    """

    __slots__ = ("namespace", "namespace_attribute")
    kind = REFERENCE
    description = "an element or an identifier string"

    def __init__(self, namespace: str | None, namespace_attribute: str | None = None):
        self.namespace = namespace
        self.namespace_attribute = namespace_attribute

    def target_namespace(self, attributes: dict) -> str | None:
        """Namespace of the target, given the attributes of the referring element."""
        if self.namespace is not None:
            return self.namespace
        kind = attributes.get(self.namespace_attribute)
        if kind is None:
            return None
        return _OBJTYPE_NAMESPACES.get(kind, kind)

    def convert(self, value):
        if isinstance(value, str):
            return value
        tag = getattr(value, "_spec", None)
        if tag is None:
            raise ValueError(f"expected an mjcf element or a string, got {value!r}")
        return value


class File(AttributeType):
    """A file asset: a path, an `mjcf.Asset`, or raw bytes."""

    __slots__ = ()
    kind = FILE
    description = "a path, bytes or an mjcf.Asset"

    def convert(self, value):
        if isinstance(value, (Asset, str)):
            return value
        if isinstance(value, (bytes, bytearray)):
            return Asset(bytes(value), "")
        raise ValueError(f"expected {self.description}, got {value!r}")


class Keyword(AttributeType):
    """One of a fixed set of words; matched without regard to case, stored as MuJoCo spells it."""

    __slots__ = ("values", "_lookup")

    def __init__(self, values):
        self.values = tuple(values)
        self._lookup = {v.lower(): v for v in self.values}

    @property
    def description(self) -> str:
        return "one of " + ", ".join(repr(v) for v in self.values)

    def convert(self, value):
        if isinstance(value, (bool, np.bool_)) and "true" in self._lookup:
            return "true" if value else "false"
        if isinstance(value, str):
            found = self._lookup.get(value.lower())
            if found is not None:
                return found
        raise ValueError(f"expected {self.description}, got {value!r}")


class Number(AttributeType):
    """A single float or int, read back as a Python number."""

    __slots__ = ("dtype",)

    def __init__(self, dtype: type):
        self.dtype = dtype

    @property
    def description(self) -> str:
        return "an int" if self.dtype is int else "a float"

    def convert(self, value):
        if isinstance(value, str):
            value = value.split()
            if len(value) != 1:
                raise ValueError(f"expected {self.description}, got {value!r}")
            value = value[0]
        elif isinstance(value, (list, tuple, np.ndarray)):
            flat = np.asarray(value).ravel()
            if flat.size != 1:
                raise ValueError(f"expected {self.description}, got {flat.size} values {value!r}")
            value = flat[0]
        try:
            if self.dtype is int:
                number = float(value)
                if number != int(number):
                    raise ValueError
                return int(number)
            return float(value)
        except (TypeError, ValueError):
            raise ValueError(f"expected {self.description}, got {value!r}") from None

    def format(self, value, precision: int, zero_threshold: float) -> str:
        if self.dtype is int:
            return str(value)
        return format_float(value, precision, zero_threshold)


class Array(AttributeType):
    """A NumPy array of floats or ints with an allowed range of lengths (high None: any)."""

    __slots__ = ("dtype", "lengths")

    def __init__(self, dtype: type, low: int = 1, high: int | None = None):
        self.dtype = np.float64 if dtype is float else np.int64
        self.lengths = (low, high)

    @property
    def description(self) -> str:
        word = "floats" if self.dtype is np.float64 else "ints"
        return f"{_describe_length(self.lengths)} {word}"

    def convert(self, value):
        if isinstance(value, str):
            value = value.split()
        try:
            array = np.array(value, dtype=np.float64).ravel()
        except (TypeError, ValueError):
            raise ValueError(f"expected {self.description}, got {value!r}") from None
        low, high = self.lengths
        if array.size < low or (high is not None and array.size > high):
            raise ValueError(f"expected {self.description}, got {array.size}: {value!r}")
        if self.dtype is np.int64:
            as_int = array.astype(np.int64)
            if not np.array_equal(as_int, array):
                raise ValueError(f"expected {self.description}, got {value!r}")
            array = as_int
        array.flags.writeable = False
        return array

    def format(self, value, precision: int, zero_threshold: float) -> str:
        if self.dtype is np.int64:
            return " ".join(map(str, value.tolist()))
        return _join_floats(value.tolist(), precision, zero_threshold)
