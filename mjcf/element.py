"""The MJCF object model: `Element`, the model root `RootElement`, and child-list views."""

from __future__ import annotations

import difflib
from typing import NamedTuple

import mujoco
import numpy as np
from lxml import etree

from mjcf import (
    attribute_array,
    attribute_types,
    constants,
    element_list,
    mujoco_compat,
    schema,
    scoped_lookup,
)
from mjcf.asset import Asset
from mjcf.namescope import UNNAMED_MODEL, NameScope

_SEP = constants.PREFIX_SEPARATOR
# Sets a private slot without going through Element.__setattr__ (which handles XML attributes).
_set_slot = object.__setattr__
_ESCAPED_SEP = constants.PREFIX_SEPARATOR_ESCAPE + constants.PREFIX_SEPARATOR
# Single children that exist only once added (reading them gives None until then), as in
# dm_control; every other single child exists from the start (created on first access here).
_ON_DEMAND = frozenset(("inertial", "freejoint"))
# The world body's identifier in the compiled model (an attached model's world body is its
# attachment frame, named by the model's scope prefix).
_WORLD = "world"
# How many distinct (element, attribute) changes a model records between structural changes.
_MAX_RECORDED_CHANGES = 4096


def _close_matches(word: str, candidates) -> str:
    matches = difflib.get_close_matches(word, list(candidates), n=3, cutoff=0.6)
    if not matches:
        return ""
    return " (did you mean " + " or ".join(repr(m) for m in matches) + "?)"


class AttributeChange(NamedTuple):
    """One attribute whose value was set or unset (`RootElement.attribute_changes_since`).

    Attributes:
      element: the element (possibly a template under `<default>`).
      attribute: the attribute's XML name (`class`, not `dclass`).
    """

    element: Element
    attribute: str


class AttributeChanges(tuple):
    """The `AttributeChange`s of a model since a modification count, in the order of their
    last changes (`RootElement.attribute_changes_since`): a tuple that also says whether
    each attribute was set at that count.

    Attributes:
      root: the model whose record the changes come from.
      since: the modification count they are counted from.
    """

    root: RootElement
    since: int

    def __new__(cls, changes, root: RootElement, since: int):
        self = super().__new__(cls, changes)
        self.root = root
        self.since = since
        return self

    def was_set_before(self, change: AttributeChange) -> bool:
        """Whether `change`'s element had its own value of the attribute at `since`."""
        return self.root.attribute_was_set_at(change, self.since)


class _UnknownAttributeError(AttributeError):
    """AttributeError whose message (with close matches) is only built when shown.

    `getattr(element, name, default)` and `hasattr` probe names often; building the
    suggestions eagerly would make every probe slow.
    """

    def __init__(self, element, name: str):
        super().__init__(name)
        self.element = element
        self.name = name

    def __str__(self) -> str:
        return self.element._unknown_message(self.name)


def registry_namespace(spec: schema.ElementSpec) -> str | None:
    """Namespace an element's identifier is registered under ('default' for classes)."""
    if spec.identifier == "class":
        return constants.DEFAULT
    return spec.namespace


class Element:
    """One element of an MJCF model, e.g. a `<body>`, `<geom>` or `<motor>`.

    Elements are created by `parent.add(tag, **attributes)` (or by parsing XML), never
    directly. XML attributes are Python attributes: `geom.size` is a NumPy array (None when
    unset), `geom.size = [0.1]` validates and sets it, `geom.size = None` or `del geom.size`
    unsets it; the XML `class` attribute is `dclass`. Array values may also be written in
    place (`geom.rgba[3] = 0.5`; see `mjcf.attribute_array`). Children that may appear at
    most once are attributes too: sections and settings (`root.worldbody`, `root.option`)
    always exist (created on first access), while `body.inertial` and `body.freejoint` are
    None until added. Repeated children are listed by tag (`body.geom[0]`,
    `body.geom['name']`).

    Identifiers (`name`, and `class` of a default) are unique per namespace within a model.
    Reference attributes (e.g. an actuator's `joint`) take an element or its identifier;
    identifiers may be scoped into attached models ('arm/elbow').
    """

    __slots__ = (
        "_spec",
        "_parent",
        "_root",
        "_attributes",
        "_texts",
        "_children",
        "_xml_cache",
        "_text_cache",
        "_auto_id",
        "_removed",
        "__weakref__",
    )

    # Attributes that `is_same_as` ignores.
    _UNCOMPARED_ATTRIBUTES: frozenset[str] = frozenset()

    # Whether this is the body an attached model hangs from (`AttachmentFrame` says True):
    # a class attribute, so that writers tell frames apart without a call per element.
    _is_attachment_frame: bool = False

    def __init__(self, *args, **kwargs):
        raise TypeError(
            "mjcf.Element cannot be created directly: use parent.add(tag, ...) or "
            "mjcf.RootElement()"
        )

    @classmethod
    def _create(cls, spec: schema.ElementSpec, parent: Element | None, root: RootElement):
        element = object.__new__(cls)
        element._init_slots(spec, parent, root)
        return element

    def _init_slots(
        self, spec: schema.ElementSpec, parent: Element | None, root: RootElement
    ) -> None:
        """Sets every slot of `Element` for a new, empty element of kind `spec`."""
        _set_slot(self, "_spec", spec)
        _set_slot(self, "_parent", parent)
        _set_slot(self, "_root", root)
        _set_slot(self, "_attributes", {})
        _set_slot(self, "_texts", {})
        _set_slot(self, "_children", [])
        _set_slot(self, "_xml_cache", None)
        _set_slot(self, "_text_cache", None)
        _set_slot(self, "_auto_id", None)
        _set_slot(self, "_removed", False)

    # ----------------------------------------------------------------- basic properties

    @property
    def tag(self) -> str:
        """The XML tag, e.g. 'geom'."""
        return self._spec.name

    @property
    def spec(self) -> schema.ElementSpec:
        """Schema of this element kind (`spec.namespace` is its MuJoCo object family)."""
        return self._spec

    @property
    def parent(self) -> Element | None:
        return self._parent

    @property
    def root(self) -> RootElement:
        """The RootElement of the model this element belongs to."""
        return self._root

    @property
    def namescope(self) -> NameScope:
        return self._root._namescope

    @property
    def is_removed(self) -> bool:
        return self._removed

    @property
    def full_identifier(self) -> str | None:
        """Name of this element in the compiled model of the top of its attachment chain.

        Unnamed elements that compile to a named MuJoCo object get a generated name (written
        into the XML as well), so every such element can be found by name after compiling.
        """
        return self.prefixed_identifier(self._root.root_model)

    def prefixed_identifier(self, prefix_root=None) -> str | None:
        """This element's identifier as seen from model `prefix_root` (None: its own model).

        The world body is 'world' in its own model and the scope prefix ('arm/', naming the
        attachment frame) when seen from a model it is attached below.
        """
        if self._spec.identifier is None and self._spec.name != constants.WORLDBODY:
            return None
        return self._scoped_name(self._root._namescope.full_prefix(prefix_root))

    def _scoped_name(self, prefix: str) -> str:
        """This element's identifier when its model's scope prefix is `prefix`."""
        if self._spec.name == constants.WORLDBODY:
            return prefix or _WORLD
        if self._spec.identifier == "class":
            if self._parent is self._root:
                return prefix or _SEP
            return prefix + self._attributes["class"]
        name = self._attributes.get("name")
        if name is not None:
            return self._parent._child_name(prefix, name)
        return self._generated_name(prefix)

    def _child_name(self, prefix: str, name: str) -> str:
        """The scoped name of this element's child named `name` when the prefix is `prefix`."""
        return prefix + name

    def _generated_name(self, prefix: str) -> str:
        """The name written for this unnamed element when its model's prefix is `prefix`."""
        parent = self._parent
        name = parent._unnamed_child_name(self, prefix) if parent is not None else None
        return name if name is not None else (prefix or _SEP) + self._unnamed_id()

    def _unnamed_child_name(self, child: Element, prefix: str) -> str | None:
        """The name this element gives its unnamed `child`, or None: the child's own id."""
        return None

    def _unnamed_id(self) -> str:
        auto_id = self._auto_id
        if auto_id is None:
            scope = self._root._namescope
            auto_id = scope.next_unnamed(self._spec.namespace, self)
            _set_slot(self, "_auto_id", auto_id)
            parent = self._parent
            if (
                parent is not None
                and parent._spec.name in constants.NAMED_ON_DEMAND_SECTIONS
                and "file" not in self._attributes
            ):
                # Its written text now carries the generated name (see `xml_writer`).
                scope.naming_changed()
        return auto_id

    def _describe(self) -> str:
        name = self._attributes.get(self._spec.identifier) if self._spec.identifier else None
        if name is not None:
            return f"<{self._spec.name} {self._spec.identifier}={name!r}>"
        return f"<{self._spec.name}>"

    def __repr__(self) -> str:
        return f"MJCF Element: {self}"

    def __str__(self) -> str:
        """The opening tag with attributes; children are elided as '...'."""
        return xml_writer.short_string(self)

    # ------------------------------------------------------------------------ attributes

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        if name in _CLASS_ATTRIBUTES:
            # A property of the class raised AttributeError: let that error through instead
            # of reporting an unknown attribute.
            return object.__getattribute__(self, name)
        spec = self._spec
        attribute = spec.python_attributes.get(name)
        if attribute is not None:
            value = self._attributes.get(attribute.name)
            if isinstance(value, np.ndarray):
                return self._writable_array(attribute.name, value)
            return value
        child_spec = self._allowed_children().get(name)
        if child_spec is not None:
            return self._child_view(child_spec)
        raise _UnknownAttributeError(self, name)

    def __setattr__(self, name: str, value) -> None:
        if name.startswith("_"):
            object.__setattr__(self, name, value)
            return
        self._set_one(name, value)

    def _set_one(self, name: str, value) -> None:
        """Sets (None: unsets) one attribute by Python name and records the change."""
        spec = self._spec.python_attributes.get(name)
        was_set = spec is not None and spec.name in self._attributes
        self._set_attribute(name, value)
        self._changed(spec.name, was_set=(was_set,))

    def __delattr__(self, name: str) -> None:
        """Unsets an attribute, or removes a single child (`del root.option`)."""
        if name.startswith("_"):
            object.__delattr__(self, name)
            return
        child_spec = self._allowed_children().get(name)
        if child_spec is not None and name not in self._spec.python_attributes:
            if child_spec.repeated:
                raise AttributeError(
                    f"{self._describe()}.{name} lists several children and cannot be "
                    f"deleted; use {name}.clear() to remove them all"
                )
            child = self._singleton_if_present(name)
            if child is not None:
                child.remove()
            return
        self._set_one(name, None)

    def __dir__(self):
        names = set(super().__dir__())
        names.update(self._spec.python_attributes)
        names.update(self._allowed_children())
        return sorted(names)

    def _unknown_message(self, name: str) -> str:
        missing = mujoco_compat.missing_mjcf(self._spec.path, name)
        if missing:
            return f"{self._describe()} has no attribute or child {name!r}: {missing}"
        known = list(self._spec.python_attributes) + list(self._allowed_children())
        return f"{self._describe()} has no attribute or child {name!r}{_close_matches(name, known)}"

    def get_attributes(self) -> dict:
        """All set attributes, keyed by Python name (`dclass` for `class`)."""
        attributes = self._spec.attributes
        return {
            attributes[k].python_name: (
                self._writable_array(k, v) if isinstance(v, np.ndarray) else v
            )
            for k, v in list(self._attributes.items())
        }

    def _writable_array(self, xml_name: str, value: np.ndarray) -> np.ndarray:
        """The array stored for `xml_name`, made writable in place (see `attribute_array`)."""
        if getattr(value, "_owner", None) is self:
            return value
        if self._removed:
            return value
        value = attribute_array.owned(value, self, xml_name)
        self._attributes[xml_name] = value
        return value

    def _array_written(self, xml_name: str, array: np.ndarray) -> None:
        """Called after `array`, this element's value of `xml_name`, was written in place."""
        if self._attributes.get(xml_name) is not array:
            return
        if xml_name in self._texts:
            self._texts[xml_name] = None  # formatted at the next write (see `_set_attribute`)
        _set_slot(self, "_xml_cache", None)
        self._changed(xml_name)

    def set_attributes(self, **attributes) -> None:
        """Sets several attributes at once; a value of None unsets that attribute.

        All or nothing: when one value is rejected, the attributes already set by this call
        get their previous values back before the error propagates.
        """
        if len(attributes) == 1:
            # One attribute (a variator's colour at every reset): nothing to roll back.
            ((name, value),) = attributes.items()
            self._set_one(name, value)
            return
        done = []
        try:
            for name, value in attributes.items():
                spec = self._spec.python_attributes.get(name)
                previous = self._attributes.get(spec.name) if spec is not None else None
                self._set_attribute(name, value)
                done.append((name, previous))
        except (ValueError, TypeError, AttributeError, FileNotFoundError):
            for name, previous in reversed(done):
                self._set_attribute(name, attribute_array.frozen(previous))
            raise
        finally:
            if done:
                python_attributes = self._spec.python_attributes
                self._changed(
                    *(python_attributes[name].name for name, _ in done),
                    was_set=tuple(previous is not None for _, previous in done),
                )

    def get_attribute_xml_string(self, attribute_name: str, prefix_root=None) -> str | None:
        """The attribute's value as it is written to XML, or None when unset."""
        spec = self._spec.python_attributes.get(attribute_name)
        if spec is None:
            raise AttributeError(self._unknown_message(attribute_name))
        return xml_writer.attribute_string(self, spec, prefix_root)

    def _set_attribute(self, name: str, value) -> None:
        spec = self._spec.python_attributes.get(name)
        if spec is None:
            raise AttributeError(self._unknown_message(name))
        if self._removed:
            raise RuntimeError(f"{self._describe()} has been removed from its model")
        xml_name = spec.name
        kind = spec.type.kind
        if kind == attribute_types.FILE:
            self._files_changed()
        if value is None:
            self._texts.pop(xml_name, None)
            old = self._attributes.pop(xml_name, None)
            if kind == attribute_types.IDENTIFIER and old is not None:
                self._root._namescope.remove(self._registry_namespace(), old)
            _set_slot(self, "_xml_cache", None)
            return
        try:
            converted = spec.type.convert(value)
        except ValueError as error:
            raise ValueError(f"{self._describe()} attribute {name!r}: {error}") from None
        if kind == attribute_types.IDENTIFIER:
            self._set_identifier(xml_name, converted)
            return
        if kind == attribute_types.REFERENCE and not isinstance(converted, str):
            self._check_reference_target(spec, converted)
        elif kind == attribute_types.FILE and isinstance(converted, str):
            converted = self._load_file(name, converted)
        elif kind == attribute_types.STRING or kind == attribute_types.OTHER:
            # `_texts` holds exactly the plain (string and other) attributes, in `_attributes`
            # order, with their full-precision text: formatted now for a new attribute (so
            # that a model's first write only joins text), or None until the next write
            # (`xml_writer.plain_text`) for one set again (a value set at every reset, as a
            # variator's colour, is seldom written).
            texts = self._texts
            if xml_name in texts:
                texts[xml_name] = None
            else:
                texts[xml_name] = attribute_types.xml_text(xml_name, spec.type, converted)
        self._attributes[xml_name] = converted
        _set_slot(self, "_xml_cache", None)

    def _set_identifier(self, xml_name: str, identifier: str) -> None:
        if not identifier:
            raise ValueError(f"{self._describe()} attribute {xml_name!r}: must not be empty")
        if _SEP in identifier.replace(_ESCAPED_SEP, ""):
            raise ValueError(
                f"{self._describe()} attribute {xml_name!r}: {identifier!r} contains "
                f"{_SEP!r}, which separates model scopes (parse with escape_separators=True "
                "to keep such names)"
            )
        namespace = self._registry_namespace()
        old = self._attributes.get(xml_name)
        if old == identifier:
            return
        scope = self._root._namescope
        if namespace == constants.DEFAULT and self._parent is self._root:
            self._attributes[xml_name] = identifier
            return
        if not self._removed and self._is_registered():
            scope.add(namespace, identifier, self)
            if old is not None:
                scope.remove(namespace, old)
        self._attributes[xml_name] = identifier
        self._xml_cache = None

    def _is_registered(self) -> bool:
        """Whether this element is part of its model's tree (not under construction)."""
        element = self
        while element._parent is not None:
            element = element._parent
        return element is self._root

    def _check_reference_target(self, spec, target: Element) -> None:
        wanted = spec.type.namespace
        if wanted is None:
            return
        if registry_namespace(target._spec) != wanted:
            raise ValueError(
                f"{self._describe()} attribute {spec.python_name!r}: expected a reference "
                f"to a {wanted!r} element, got {target._describe()}"
            )

    def _load_file(self, name: str, path: str) -> Asset:
        root = self._root
        compiler = root._singleton_if_present("compiler")
        scope = root._namescope
        return model_files.load(
            self._spec.name,
            path,
            where=f"{self._describe()} attribute {name!r}",
            compiler=compiler._attributes if compiler is not None else {},
            model_dir=scope.model_dir,
            assets=scope.assets,
        )

    # -------------------------------------------------------------------------- children

    def _allowed_children(self) -> dict:
        return self._spec.children

    def _singleton_if_present(self, tag: str) -> Element | None:
        # Through the `tag` property, so that an error inside it surfaces from `tag` itself
        # rather than from this lookup, as in dm_control.
        for child in self._children:
            if child.tag == tag:
                return child
        return None

    def _child_view(self, child_spec: schema.ElementSpec):
        """The list of children with a repeated tag, or the single child (None for an
        on-demand child not yet added)."""
        if child_spec.repeated:
            return element_list.ElementList(self, child_spec.name)
        if child_spec.name in _ON_DEMAND:
            return self._singleton_if_present(child_spec.name)
        return self._singleton(child_spec)

    def _singleton(self, child_spec: schema.ElementSpec) -> Element:
        existing = self._singleton_if_present(child_spec.name)
        if existing is not None:
            return existing
        child = Element._create(child_spec, self, self._root)
        self._children.append(child)
        return child

    def add(self, element_name: str, **attributes) -> Element:
        """Adds a child element with the given tag and attributes; returns it."""
        return self.insert(element_name, len(self._children), **attributes)

    def insert(self, element_name: str, position: int, **attributes) -> Element:
        """Inserts a child element at `position` among this element's children."""
        if self._removed:
            raise RuntimeError(f"{self._describe()} has been removed from its model")
        child_spec = self._allowed_children().get(element_name)
        if child_spec is None:
            missing = mujoco_compat.missing_mjcf(self._spec.path, element_name)
            if missing:
                raise AttributeError(
                    f"{self._describe()} cannot have a child <{element_name}>: {missing}"
                )
            # AttributeError, as dm_control raises for a tag that is not a valid child.
            raise AttributeError(
                f"{self._describe()} cannot have a child <{element_name}>"
                f"{_close_matches(element_name, self._allowed_children())}; allowed: "
                f"{', '.join(sorted(self._allowed_children()))}"
            )
        if not child_spec.repeated and (
            element_name not in _ON_DEMAND or self._singleton_if_present(element_name)
        ):
            raise ValueError(
                f"{self._describe()}: a <{element_name}> child already exists (there can be "
                f"only one); access it as .{element_name}"
            )
        child = Element._create(child_spec, None, self._root)
        for name, value in attributes.items():
            child._set_attribute(name, value)
        child._parent = self
        child._register_identifiers()
        self._children.insert(position, child)
        self._changed()
        return child

    def _identifier_entry(self) -> tuple[str, str] | None:
        """(namespace, identifier) this element is registered under, or None."""
        identifier_attr = self._spec.identifier
        if identifier_attr is None:
            return None
        value = self._attributes.get(identifier_attr)
        if value is None:
            return None
        namespace = self._registry_namespace()
        if namespace == constants.DEFAULT and self._parent is self._root:
            return None
        return namespace, value

    def _registry_namespace(self) -> str | None:
        """Namespace this element's identifier is registered under in its model.

        The joints of an attachment frame are named after the frame ('arm/' + 'x' + '/'),
        so their identifiers only need to be unique per frame: each frame has its own.
        """
        namespace = registry_namespace(self._spec)
        parent = self._parent
        return parent._child_namespace(namespace) if parent is not None else namespace

    def _child_namespace(self, namespace: str | None) -> str | None:
        """The namespace a child registers an identifier of `namespace` under."""
        return namespace

    def _register_identifiers(self) -> None:
        """Registers identifiers of this subtree; on a clash, leaves nothing registered."""
        done = []
        try:
            for element in self._iter_own_tree():
                entry = element._identifier_entry()
                if entry is not None:
                    element._root._namescope.add(entry[0], entry[1], element)
                    done.append((element, entry))
        except ValueError:
            for element, entry in done:
                element._root._namescope.remove(*entry)
            raise

    def _iter_own_tree(self):
        """Yields this element and its descendants in this model (not attached models)."""
        stack = [self]
        while stack:
            element = stack.pop()
            yield element
            stack.extend(reversed(element._children))

    def remove(self, affect_attachments: bool = False) -> None:
        """Removes this element (and its subtree) from the model.

        A single child that always exists (`root.option`, `root.visual.quality`) is emptied
        instead: its attributes are unset and its children removed. The global sections of
        a model (`option`, `contact`, ...) stand for those of every model attached below it
        as well, so emptying one of them needs `affect_attachments=True`, which empties the
        same section of the attached models too.

        Raises:
          ValueError: the element is not part of a model, or it is a global section of a
            model with attachments and `affect_attachments` is False.
        """
        parent = self._parent
        if parent is None or self._removed:
            raise ValueError(f"{self._describe()} is not part of a model, so cannot be removed")
        if self._spec.repeated or self._spec.name in _ON_DEMAND:
            self._detach()
            return
        path = self._section_path()
        if path is not None and self._root._frames:
            if not affect_attachments:
                raise ValueError(
                    f"{self._describe()} of model {self._root._namescope.name!r} also "
                    "stands for that of the models attached to it; use "
                    "remove(affect_attachments=True) to empty it in all of them"
                )
            for frame in self._root._frames:
                counterpart = frame._attached
                for tag in path:
                    counterpart = counterpart._singleton_if_present(tag)
                    if counterpart is None:
                        break
                if counterpart is not None:
                    counterpart.remove(affect_attachments=True)
        self._empty()

    def _section_path(self) -> list[str] | None:
        """Tags from the root down to this element when all of them are single children
        (a global section or a part of one), else None."""
        path = []
        element = self
        while element._parent is not None:
            if element._spec.repeated:
                return None
            path.append(element._spec.name)
            element = element._parent
        path.reverse()
        return path

    def _empty(self) -> None:
        """Unsets every attribute and removes every child, keeping this element."""
        for name in list(self._attributes):
            self._set_attribute(self._spec.attributes[name].python_name, None)
        for child in list(self._children):
            if child._spec.repeated or child._spec.name in _ON_DEMAND:
                child._detach()
            else:
                child._empty()
        self._changed()

    def _detach(self) -> None:
        """Takes this element and its subtree out of the model."""
        parent = self._parent
        for element in self._iter_own_tree():
            entry = element._identifier_entry()
            if entry is not None and element._root._namescope.find(*entry) is element:
                element._root._namescope.remove(*entry)
            if element._auto_id is not None:
                element._root._namescope.remove_unnamed(element._spec.namespace, element._auto_id)
            element._unlink()
            element._removed = True
        self._root._namescope.naming_changed()
        if self._spec.holds_files:
            self._files_changed()
        parent._children.remove(self)
        parent._changed()

    def _unlink(self) -> None:
        """Undoes what links this element to other models, as it is taken out of its own."""

    def get_children(self, element_name: str):
        """Children with the given tag: a list view for repeated tags, else the one child."""
        child_spec = self._allowed_children().get(element_name)
        if child_spec is None:
            raise ValueError(
                f"{self._describe()} has no child tag {element_name!r}"
                f"{_close_matches(element_name, self._allowed_children())}"
            )
        return self._child_view(child_spec)

    def all_children(self) -> list[Element]:
        """All children in order, attachment frames included.

        As in dm_control, a top-level section (`root.actuator`, `root.asset`, ...) also
        lists the repeated elements of the same section of each attached model, and an
        attachment frame the elements of its attached model's worldbody.
        """
        children = list(self._children)
        for section in self._attached_sections():
            children += [c for c in section.all_children() if c._spec.repeated]
        return children

    def _attached_sections(self) -> list[Element]:
        """The elements of attached models whose repeated children this element lists as its
        own (see `all_children`): for a top-level section other than worldbody and default,
        the same section of each attached model."""
        root = self._root
        tag = self._spec.name
        if (
            self._parent is not root
            or not root._frames
            or tag in (constants.WORLDBODY, constants.DEFAULT)
        ):
            return []
        sections = (frame._attached._singleton_if_present(tag) for frame in root._frames)
        return [section for section in sections if section is not None]

    # ------------------------------------------------------------------------ sameness

    def is_same_as(self, other) -> bool:
        """Whether `other` describes the same thing: the same kind of element with equal
        attributes and, recursively, equivalent children.

        Children are compared tag by tag in order (a body's geoms against the other's geoms,
        its sites against its sites), except in a tendon, whose path is its children in
        order. A single child that was never set up equals an empty one. References are
        compared by the identifier they name; a model's own name does not count. Meant for
        tests: equivalent models may still order `ctrl` differently when compiled.
        """
        if not isinstance(other, Element) or other._spec is not self._spec:
            return False
        if not self._same_attributes(other) or not self._same_attachment(other):
            return False
        mine = [c for c in self._children if _is_set(c)]
        theirs = [c for c in other._children if _is_set(c)]
        parent = self._parent
        if parent is not None and parent._spec.name == constants.TENDON:
            return len(mine) == len(theirs) and all(
                a.is_same_as(b) for a, b in zip(mine, theirs, strict=True)
            )
        tags = dict.fromkeys(c._spec.name for c in mine + theirs)
        for tag in tags:
            group = [c for c in mine if c._spec.name == tag]
            other_group = [c for c in theirs if c._spec.name == tag]
            if len(group) != len(other_group):
                return False
            if not all(a.is_same_as(b) for a, b in zip(group, other_group, strict=True)):
                return False
        return True

    def _same_attachment(self, other: Element) -> bool:
        """Whether `other` carries an equivalent attached model (both carry none here)."""
        return True

    def _same_attributes(self, other: Element) -> bool:
        names = set(self._attributes) | set(other._attributes)
        names.difference_update(self._UNCOMPARED_ATTRIBUTES)
        for name in names:
            mine = _comparable(self._attributes.get(name))
            theirs = _comparable(other._attributes.get(name))
            if isinstance(mine, np.ndarray) or isinstance(theirs, np.ndarray):
                if mine is None or theirs is None or not np.array_equal(mine, theirs):
                    return False
            elif mine != theirs:
                return False
        return True

    # ---------------------------------------------------------------------------- search

    def find(self, namespace: str, identifier: str) -> Element | None:
        """Finds the element named `identifier` in `namespace` in this element's subtree.

        `identifier` may be scoped into attached models, e.g. 'arm/hand/pinch_site'.
        Returns None when there is no such element.
        """
        namespace = _checked_namespace(namespace)
        found = scoped_lookup.lookup(self._root, namespace, identifier)
        if found is None or self is self._root:
            return found
        ancestor = found
        while ancestor is not None and ancestor is not self:
            ancestor = ancestor._parent if ancestor._parent is not None else _frame_of(ancestor)
        return found if ancestor is self else None

    def enter_scope(self, scope_identifier: str) -> RootElement | None:
        """The model attached below this element's model as `scope_identifier`, or None."""
        model = self._root
        for name in scope_identifier.split(_SEP):
            if not name:
                continue
            model = model._attached_model(name)
            if model is None:
                return None
        return model

    def find_all(
        self,
        namespace: str,
        immediate_children_only: bool = False,
        exclude_attachments: bool = False,
    ) -> list[Element]:
        """All elements of `namespace` below this element (itself excluded), in model order.

        Attached models are searched too unless `exclude_attachments`: their bodies where
        they are attached, and, when searching a whole model or one of its top-level sections
        (`root.actuator`, `root.asset`, ...), the same sections of every attached model.
        Default classes of attached models are not included (their classes are scoped
        separately). Attachment frames count as bodies and are found under the
        'attachment_frame' namespace.
        """
        namespace = _checked_namespace(namespace)
        found = []
        if immediate_children_only:
            for child in self._children:
                if child._listed_under(namespace):
                    found.append(child)
            return found
        self._collect_children(namespace, exclude_attachments, found)
        if exclude_attachments or namespace == constants.DEFAULT:
            return found
        root = self._root
        if self is root:
            root._collect_sections_of_attachments(namespace, found, None)
        elif self._parent is root and self._spec.name != constants.WORLDBODY:
            root._collect_sections_of_attachments(namespace, found, self._spec.name)
        return found

    def _collect(self, namespace, exclude_attachments, found) -> None:
        if self._listed_under(namespace):
            found.append(self)
        self._collect_children(namespace, exclude_attachments, found)

    def _collect_children(self, namespace, exclude_attachments, found) -> None:
        for child in self._children:
            child._collect(namespace, exclude_attachments, found)

    def _listed_under(self, namespace: str) -> bool:
        """Whether `find_all(namespace)` lists this element."""
        return registry_namespace(self._spec) == namespace

    # --------------------------------------------------------------------- bookkeeping

    def _changed(self, *attributes: str, was_set: tuple[bool, ...] | None = None) -> None:
        """Invalidates cached text and counts a modification in every enclosing model.

        `attributes` names the XML attributes of this element whose values changed, when
        that is all that changed; without them the change is structural (see
        `RootElement.attribute_changes_since`). `was_set` says, for each, whether this
        element had its own value of it before the change (None: it stays as it was, a
        value written in place).
        """
        _set_slot(self, "_xml_cache", None)
        # The cached text of every element that encloses this one (across attachments)
        # includes this one's.
        element = self
        while element is not None:
            if element._text_cache is not None:
                _set_slot(element, "_text_cache", None)
            parent = element._parent
            element = parent if parent is not None else _frame_of(element)
        model = self._root
        while model is not None:
            model._modification_count += 1
            model._note_change(self, attributes, was_set)
            frame = model._frame
            model = frame._root if frame is not None else None

    def _files_changed(self) -> None:
        """Marks the file assets of this model, and of those it is attached below, as stale."""
        model = self._root
        while model is not None:
            model._files_count += 1
            frame = model._frame
            model = frame._root if frame is not None else None

    # ------------------------------------------------------------------------------ XML

    def to_xml_string(
        self,
        prefix_root=None,
        self_only: bool = False,
        pretty_print: bool = True,
        debug_context=None,
        *,
        precision: int = 17,
        zero_threshold: float = 0,
        self_close: bool = True,
    ) -> str:
        """XML text of this element (for a RootElement: a complete, compilable model).

        Args:
          prefix_root: the model (RootElement or its NameScope) identifiers are scoped
            from; None: this element's own model.
          self_only: write only this element's own tag, with '...' for its children and
            without generated names (what `str(element)` shows).
          pretty_print: indent and end lines; the text then ends with a newline.
          debug_context: accepted for dm_control compatibility; unused.
          precision: significant digits of floats; 17 writes the shortest exact form.
          zero_threshold: floats smaller in magnitude are written as 0.
          self_close: write empty elements as `<tag/>` rather than `<tag></tag>`.
        """
        del debug_context
        if self_only:
            text = xml_writer.short_string(self, prefix_root)
            return text + "\n" if pretty_print else text
        return xml_writer.element_to_string(
            self, prefix_root, self_close, pretty_print, precision, zero_threshold
        )

    def to_xml(self, prefix_root=None, debug_context=None, *, precision=17, zero_threshold=0):
        """This element as an lxml element tree."""
        text = self.to_xml_string(
            prefix_root,
            pretty_print=False,
            debug_context=debug_context,
            precision=precision,
            zero_threshold=zero_threshold,
        )
        return etree.fromstring(text)

    # ----------------------------------------------------------------------- attachment

    def attach(self, attachment: RootElement):
        """Attaches model `attachment` here (a site, body or worldbody); returns its frame."""
        return attachment_module.attach(self, attachment)

    def __copy__(self):
        raise TypeError(
            f"{self._describe()}: only whole models (RootElement) can be copied; use "
            "copy.deepcopy(root) or copy.copy(root)"
        )

    def __deepcopy__(self, memo):
        return self.__copy__()


def _is_set(element: Element) -> bool:
    """Whether `element` says anything: single children that were never set up do not."""
    if element._spec.repeated or element._spec.name in _ON_DEMAND or element._attributes:
        return True
    return any(_is_set(child) for child in element._children)


def _comparable(value):
    """An attribute value as `is_same_as` compares it: references by the name they give."""
    if isinstance(value, Element):
        return value.full_identifier
    return value


def _checked_namespace(namespace: str) -> str:
    """`namespace` ('keyframe' spelled 'key'); a ValueError if no element has it."""
    if namespace not in schema.namespaces():
        suggestion = _close_matches(namespace, schema.namespaces())
        raise ValueError(f"{namespace!r} is not a valid namespace{suggestion}")
    return "key" if namespace == "keyframe" else namespace


def _frame_of(element):
    """The attachment frame that holds `element`'s model, when `element` is that model's root."""
    if element is element._root:
        return element._frame
    return None


_FRAME_CHILDREN = ("joint", "freejoint", "inertial")
_HINGED = ("joint", "inertial")


class AttachmentFrame(Element):
    """The body that carries an attached model, placed where the model was attached.

    Its generated name is the attached model's scope prefix ('child/'); it accepts
    `<joint>`, `<freejoint>` and `<inertial>` children (e.g. `frame.add('freejoint')` makes
    the attached model free-floating) and pose attributes. Its contents in the generated
    XML are the attached model's worldbody.
    """

    __slots__ = ("_attached",)

    _is_attachment_frame = True

    @property
    def attached_model(self) -> RootElement:
        return self._attached

    def _allowed_children(self) -> dict:
        children = self._spec.children
        # Only a model attached to the world can float freely.
        allowed = _FRAME_CHILDREN if self._parent._spec.name == constants.WORLDBODY else _HINGED
        return {tag: children[tag] for tag in allowed if tag in children}

    def _attached_sections(self) -> list[Element]:
        """The attached model's worldbody, whose elements the frame lists after its own."""
        world = self._attached._singleton_if_present(constants.WORLDBODY)
        return [world] if world is not None else []

    def _scoped_name(self, prefix: str) -> str:
        return prefix + self._attached._namescope.name + constants.PREFIX_SEPARATOR

    def _child_name(self, prefix: str, name: str) -> str:
        # A frame's joints are named after the frame: 'arm/' + 'x' + '/'.
        return self._scoped_name(prefix) + name + _SEP

    def _unnamed_child_name(self, child: Element, prefix: str) -> str | None:
        if child._spec.namespace == constants.JOINT and child is self.unnamed_joint():
            return self._scoped_name(prefix)
        return None

    def _child_namespace(self, namespace: str | None) -> str | None:
        # The frame's joint names only need to be unique per frame: each has its own namespace.
        return f"{namespace}{constants.NAMESPACE_SEPARATOR}frame{id(self)}"

    def _unlink(self) -> None:
        self._root._frames.remove(self)
        self._attached._frame = None

    def _same_attachment(self, other: Element) -> bool:
        return isinstance(other, AttachmentFrame) and self._attached.is_same_as(other._attached)

    def _listed_under(self, namespace: str) -> bool:
        return namespace == constants.ATTACHMENT_FRAME or super()._listed_under(namespace)

    def unnamed_joint(self) -> Element | None:
        """The first unnamed joint or freejoint of this frame, which is named after the frame
        ('child/') in the compiled model, as dm_control names it."""
        for child in self._children:
            if child._spec.namespace == constants.JOINT and "name" not in child._attributes:
                return child
        return None

    def _describe(self) -> str:
        return f"<attachment frame of model {self._attached._namescope.name!r}>"

    def _set_attribute(self, name: str, value) -> None:
        if name in ("name", "childclass"):
            raise AttributeError(
                f"{self._describe()}: attribute {name!r} of an attachment frame is set by "
                "the attached model and cannot be changed"
            )
        super()._set_attribute(name, value)

    def _collect_children(self, namespace, exclude_attachments, found) -> None:
        for child in self._children:
            child._collect(namespace, exclude_attachments, found)
        if not exclude_attachments:
            world = self._attached._singleton_if_present(constants.WORLDBODY)
            if world is not None:
                world._collect_children(namespace, exclude_attachments, found)


class RootElement(Element):
    """A whole MJCF model: the `<mujoco>` element.

    Args:
      model: the model name; it scopes every identifier of this model when the model is
        attached to another ('model/identifier').
      model_dir: directory that relative file paths of assets are resolved against.
      assets: filename -> bytes; consulted before the disk when a file path is set.

    Attributes beyond `Element`:
      modification_count: an int that grows whenever anything in this model, or in any
        model attached below it, changes. Reading it is O(1).

    Besides the count, a model keeps a record of which attribute values changed since its
    last structural change (anything other than setting or unsetting an attribute's value:
    adding, removing, attaching, copying, committing defaults), so that a compiled model
    can be brought up to date without recompiling (`attribute_changes_since`). The record
    holds at most `_MAX_RECORDED_CHANGES` distinct (element, attribute) pairs; beyond that
    it is dropped and counts as a structural change. It also keeps when an attribute went
    from unset to set or back, so that a patch can tell a value that replaces another from
    one set where nothing was (`attribute_was_set_at`).
    """

    __slots__ = (
        "_namescope",
        "_frame",
        "_frames",
        "_modification_count",
        "_structure_count",
        "_attribute_changes",
        "_set_flips",
        "_files_count",
        "_xml_string_cache",
        "_assets_cache",
    )

    # A model's own name does not make it differ from another.
    _UNCOMPARED_ATTRIBUTES = frozenset(("model",))

    def __init__(self, model: str | None = None, model_dir: str = "", assets: dict | None = None):
        self._init_slots(schema.root_spec(), None, self)
        self._namescope = NameScope(self, model_dir, assets)
        self._frame = None
        self._frames = []
        self._modification_count = 0
        self._structure_count = 0
        self._attribute_changes = {}
        self._set_flips = {}
        self._files_count = 0
        self._xml_string_cache = None
        self._assets_cache = None
        self.model = model or UNNAMED_MODEL
        self._start_counting()

    def _start_counting(self) -> None:
        """Makes the model as built so far count as unmodified."""
        self._modification_count = 0
        self._structure_count = 0
        self._attribute_changes.clear()
        self._set_flips.clear()

    @property
    def modification_count(self) -> int:
        return self._modification_count

    def attribute_changes_since(self, count: int) -> tuple[AttributeChange, ...] | None:
        """What changed in this model (and models attached below it) since `count`.

        Args:
          count: an earlier `modification_count` of this model.

        Returns:
          `AttributeChanges`: an `AttributeChange` for each attribute whose value was set
          or unset since `count`, each once, in the order of their last changes, when
          nothing else changed; an empty tuple when nothing changed at all; None when the model's
          structure changed since `count` (or the record of changes was dropped), so that
          only a recompile can tell the difference.
        """
        if count < self._structure_count or count > self._modification_count:
            return None
        return AttributeChanges(
            (pair for pair, when in self._attribute_changes.items() if when > count), self, count
        )

    def attribute_was_set_at(self, change: AttributeChange, count: int) -> bool:
        """Whether `change.element` had its own value of `change.attribute` when this model's
        modification count was `count` (a count `attribute_changes_since(count)` accepts)."""
        for flip_count, was_set in self._set_flips.get(change, ()):
            if flip_count > count:
                return was_set
        return change.attribute in change.element._attributes

    def _note_change(
        self, element: Element, attributes: tuple[str, ...], was_set: tuple[bool, ...] | None
    ) -> None:
        """Records a change counted in `_modification_count` (see the class docstring)."""
        changes = self._attribute_changes
        if not attributes or len(changes) + len(attributes) > _MAX_RECORDED_CHANGES:
            self._structure_count = self._modification_count
            changes.clear()
            self._set_flips.clear()
            return
        count = self._modification_count
        for index, attribute in enumerate(attributes):
            # Re-inserted, so that the record stays ordered by the time of the last change.
            change = AttributeChange(element, attribute)
            changes.pop(change, None)
            changes[change] = count
            if was_set is not None and was_set[index] != (attribute in element._attributes):
                # Set where it was unset, or the reverse: what it was before `count`.
                flips = self._set_flips.setdefault(change, [])
                flips.append((count, was_set[index]))
                if len(flips) > _MAX_RECORDED_CHANGES:
                    self._structure_count = count
                    changes.clear()
                    self._set_flips.clear()

    @property
    def parent_model(self) -> RootElement | None:
        """The model this one is attached to, or None."""
        return self._frame._root if self._frame is not None else None

    def prefixed_identifier(self, prefix_root=None) -> str:
        """This model's scope prefix as seen from `prefix_root` ('' for the model itself,
        'arm/hand/' for a hand attached to an arm attached to `prefix_root`)."""
        return self._namescope.full_prefix(prefix_root)

    @property
    def root_model(self) -> RootElement:
        """The top of this model's attachment chain."""
        model = self
        while model._frame is not None:
            model = model._frame._root
        return model

    def _set_attribute(self, name: str, value) -> None:
        if name == "model" and value is None:
            value = UNNAMED_MODEL
        if name == "model":
            if not isinstance(value, str) or not value:
                raise ValueError(
                    f"<mujoco> attribute 'model': expected a non-empty string, got {value!r}"
                )
            if _SEP in value:
                raise ValueError(
                    f"<mujoco> attribute 'model': {value!r} contains {_SEP!r}, which "
                    "separates model scopes"
                )
            frame = self._frame
            if frame is not None:
                sibling = frame._root._attached_model(value)
                if sibling is not None and sibling is not self:
                    raise ValueError(
                        f"duplicate identifier: a model named {value!r} is already attached "
                        f"to model {frame._root._namescope.name!r}"
                    )
        super()._set_attribute(name, value)
        if name == "model":
            self._namescope.naming_changed()
            # Skin files name bones by their scoped body names.
            self._files_changed()

    def _attached_model(self, name: str) -> RootElement | None:
        for frame in self._frames:
            if frame._attached._namescope.name == name:
                return frame._attached
        return None

    def _collect_sections_of_attachments(self, namespace, found, section_tag) -> None:
        """Adds matches from the top-level sections of attached models (all but worldbody,
        whose contents hang below attachment frames), or only from `section_tag` ones."""
        for frame in self._frames:
            model = frame._attached
            for section in model._children:
                tag = section._spec.name
                if tag != constants.WORLDBODY and section_tag in (None, tag):
                    section._collect_children(namespace, False, found)
            model._collect_sections_of_attachments(namespace, found, section_tag)

    def attach(self, attachment: RootElement):
        """Attaches model `attachment` to this model's worldbody; returns its frame."""
        return self.worldbody.attach(attachment)

    def detach(self) -> None:
        """Detaches this model from the model it is attached to."""
        frame = self._frame
        if frame is None:
            raise RuntimeError(
                f"model {self._namescope.name!r} is not attached to any model, so cannot "
                "be detached"
            )
        frame.remove()

    def get_assets(self) -> dict[str, bytes]:
        """Every file asset of this model and attached models: VFS filename -> contents."""
        cache = self._assets_cache
        if cache is None or cache[0] != self._files_count:
            cache = (self._files_count, xml_writer.collect_assets(self))
            self._assets_cache = cache
        return dict(cache[1])

    def to_spec(self):
        """This model as a `mujoco.MjSpec` (compiled names equal `full_identifier`s)."""
        return mujoco.MjSpec.from_string(self.to_xml_string(), assets=self.get_assets())

    def remove(self, affect_attachments: bool = False) -> None:
        raise ValueError("the <mujoco> root element cannot be removed; use detach()")

    def include_copy(self, other: RootElement, override_attributes: bool = False) -> None:
        """Copies the contents of model `other` into this model (see
        `mjcf.copier.include_copy`)."""
        copier.include_copy(self, other, override_attributes)

    def resolve_references(self) -> None:
        """Replaces identifier strings in reference attributes (an actuator's `joint`, a
        geom's `material`) by the elements they name, where this model has such an element.
        """
        parser.resolve_reference_strings(self)

    def __copy__(self):
        return self.__deepcopy__({})

    def __deepcopy__(self, memo):
        return copier.copy_model(self)


# Names of the properties of the element classes (see `Element.__getattr__`).
_CLASS_ATTRIBUTES = frozenset(
    name
    for cls in (Element, RootElement)
    for name, value in vars(cls).items()
    if isinstance(value, property)
)

# dm_control compatibility, not our API: its private name for the element class, which MoMa
# imports.
_ElementImpl = Element

# These modules implement what the element classes' methods delegate to (XML writing,
# `attach`, copying, reference resolution, reading files), and they build and inspect elements
# (or, as `model_files`, parse through `parser`), so they import the classes above: imported
# last, they find them defined whichever is imported first.
from mjcf import attachment as attachment_module  # noqa: E402
from mjcf import copier, model_files, parser, xml_writer  # noqa: E402
