"""Generates MJCF XML text from the object model, merging attached models into one document.

The text is assembled directly from string pieces. Each element caches the formatted text of
its plain attributes (per precision setting); identifiers, references and file names are
scoped at write time because they depend on where the model is attached.

A whole model is written so that every compiled object is addressable: unnamed elements that
compile to a named object get a generated name, and every element that accepts a default
class names its class explicitly. Each model's global defaults live in a class named after
its scope prefix ('/' for the top model, 'child/' for a model attached as 'child'), so the
defaults of one model never leak into another.
"""

from __future__ import annotations

from mjcf import attribute_types, constants, schema, skin_file
from mjcf.asset import Asset
from mjcf.attachment import AttachmentFrame
from mjcf.element import Element, RootElement
from mjcf.namescope import NameScope

_SEP = constants.PREFIX_SEPARATOR
_STRING = attribute_types.STRING
_IDENTIFIER = attribute_types.IDENTIFIER
_REFERENCE = attribute_types.REFERENCE
_FILE = attribute_types.FILE
_FULL_PRECISION = (17, 0)
_TOP_ONLY_SECTIONS = ("statistic",)
# Bypasses Element.__setattr__, which handles XML attributes.
_set_xml_cache = Element.__dict__["_xml_cache"].__set__


_escape = attribute_types.escape


def _worth_writing(element: Element) -> bool:
    """Whether `element` changes the compiled model: empty settings singletons do not."""
    spec = element._spec
    return bool(
        element._children or element._attributes or spec.repeated or spec.namespace is not None
    )


class _Writer:
    __slots__ = (
        "out",
        "precision",
        "zero_threshold",
        "key",
        "pretty",
        "self_close",
        "full",
        "prefix_root",
        "prefixes",
    )

    def __init__(self, prefix_root, self_close, pretty, precision, zero_threshold, full):
        self.out: list[str] = []
        self.precision = precision
        self.zero_threshold = zero_threshold
        self.key = (precision, zero_threshold)
        self.pretty = pretty
        self.self_close = self_close
        self.full = full
        self.prefix_root = prefix_root
        self.prefixes: dict[int, str] = {}

    def indent(self, depth: int) -> str:
        return "  " * depth if self.pretty else ""

    def newline(self) -> str:
        return "\n" if self.pretty else ""

    # ------------------------------------------------------------------ attribute text

    def cached_attributes(self, element: Element):
        cache = element._xml_cache
        if cache is not None and cache[0] == self.key:
            return cache[1], cache[2]
        attributes = element._spec.attributes
        full_precision = self.key == _FULL_PRECISION
        texts = element._texts
        parts = []
        dynamic = []
        for name, value in element._attributes.items():
            if full_precision:
                text = texts.get(name)
                if text is not None:
                    parts.append(text)
                    continue
            value_type = attributes[name].type
            kind = value_type.kind
            if kind == _STRING or kind == attribute_types.OTHER:
                parts.append(
                    attribute_types.xml_text(
                        name, value_type, value, self.precision, self.zero_threshold
                    )
                )
            elif kind != _IDENTIFIER:
                dynamic.append((name, kind, value, value_type))
        static = "".join(parts)
        dynamic = tuple(dynamic)
        _set_xml_cache(element, (self.key, static, dynamic, None, None, None))
        return static, dynamic

    def prefix_of(self, model: RootElement) -> str | None:
        prefix = self.prefixes.get(id(model))
        if prefix is None and not self.full:
            prefix = model._namescope.full_prefix(self.prefix_root)
            self.prefixes[id(model)] = prefix
        return prefix

    def resolve(self, element: Element, name: str, value, value_type) -> str:
        """The scoped identifier a reference attribute names, as written to XML."""
        if isinstance(value, str):
            namespace = value_type.target_namespace(element._attributes)
            if namespace is None:
                return _escape(self.prefix_of(element._root) + value)
            target = element._root.find(namespace, value)
            if target is None:
                if element._spec.namespace is None and _in_defaults(element):
                    # MuJoCo only checks references of defaults that something uses.
                    return _escape(self.prefix_of(element._root) + value)
                if self.full:
                    raise ValueError(
                        f"{element._describe()} attribute {name!r} refers to {value!r}, but "
                        f"model {element._root._namescope.name!r} has no {namespace!r} "
                        f"element with that name"
                    )
                return _escape(value)
        else:
            target = value
            if target._removed and self.full:
                raise ValueError(
                    f"{element._describe()} attribute {name!r} refers to "
                    f"{target._describe()}, which has been removed from its model"
                )
        prefix = self.prefix_of(target._root)
        if prefix is None:
            raise ValueError(
                f"{element._describe()} attribute {name!r} refers to {target._describe()} "
                f"of model {target._root._namescope.name!r}, which is not part of the model "
                "being written"
            )
        return _escape(_scoped_identifier(target, prefix))

    def dynamic_text(self, element: Element, dynamic) -> tuple[str, bool]:
        parts = []
        has_class = False
        for name, kind, value, value_type in dynamic:
            if kind == _REFERENCE:
                if name == "class":
                    has_class = True
                parts.append(f' {name}="{self.resolve(element, name, value, value_type)}"')
            elif kind == _FILE:
                if isinstance(value, Asset):
                    value = _file_asset(element, value, self.prefix_of(element._root))
                    text = value.get_vfs_filename()
                else:
                    text = value
                parts.append(f' {name}="{_escape(text)}"')
        return "".join(parts), has_class

    # ---------------------------------------------------------------------- elements

    def element(self, element: Element, depth: int, prefix: str, dclass: str | None) -> None:
        """Writes `element` of the model with scope `prefix`; `dclass`: inherited class."""
        if type(element) is AttachmentFrame:
            self.frame(element, depth, dclass)
            return
        head_key = (self.key, NameScope.epoch, prefix, dclass, self.full)
        cache = element._xml_cache
        if cache is not None and cache[3] == head_key:
            head = cache[4]
            dclass = cache[5]
        else:
            head, dclass = self.head(element, prefix, dclass, head_key)
        out = self.out
        pretty = self.pretty
        out.append("  " * depth + head if pretty else head)
        children = element._children
        if children:
            mark = len(out)
            out.append(">\n" if pretty else ">")
            for child in children:
                if _worth_writing(child):
                    self.element(child, depth + 1, prefix, dclass)
            if len(out) > mark + 1:
                tag = element._spec.name
                out.append(f"{'  ' * depth}</{tag}>\n" if pretty else f"</{tag}>")
                return
            del out[mark:]
        out.append(self.close(element._spec.name))

    def head(self, element: Element, prefix: str, dclass: str | None, head_key):
        """The opening tag without its closing bracket, and the class its children inherit."""
        spec = element._spec
        static, dynamic = self.cached_attributes(element)
        head = ["<", spec.name]
        if spec.identifier == "name":
            identifier = element._attributes.get("name")
            if identifier is not None:
                head.append(f' name="{_escape(prefix + identifier)}"')
            elif self.full:
                head.append(f' name="{prefix or _SEP}{element._unnamed_id()}"')
        head.append(static)
        has_class = False
        if dynamic:
            text, has_class = self.dynamic_text(element, dynamic)
            head.append(text)
        if dclass is not None and not has_class and "class" in spec.attributes:
            head.append(f' class="{_escape(dclass)}"')
        if spec.name == "body":
            childclass = element._attributes.get("childclass")
            if childclass is not None:
                childclass_type = spec.attributes["childclass"].type
                dclass = self.resolve(element, "childclass", childclass, childclass_type)
        text = "".join(head)
        cache = element._xml_cache
        _set_xml_cache(element, (cache[0], cache[1], cache[2], head_key, text, dclass))
        return text, dclass

    def close(self, tag: str) -> str:
        return ("/>" if self.self_close else f"></{tag}>") + self.newline()

    def frame(self, frame: AttachmentFrame, depth: int, dclass: str | None) -> None:
        model = frame._attached
        own_prefix = self.prefix_of(frame._root)
        child_prefix = self.prefix_of(model)
        static, dynamic = self.cached_attributes(frame)
        out = self.out
        out.append(f'{self.indent(depth)}<body name="{_escape(child_prefix)}"{static}>')
        out.append(self.newline())
        for child in frame._children:
            self.element(child, depth + 1, own_prefix, dclass)
        world = model._singleton_if_present(constants.WORLDBODY)
        if world is not None:
            child_class = (child_prefix or _SEP) if self.full else None
            for child in world._children:
                if _worth_writing(child):
                    self.element(child, depth + 1, child_prefix, child_class)
        out.append(f"{self.indent(depth)}</body>{self.newline()}")

    def default_class(self, default: Element, depth: int, prefix: str, name: str) -> None:
        out = self.out
        out.append(f'{self.indent(depth)}<default class="{_escape(name)}"')
        static, dynamic = self.cached_attributes(default)
        del static, dynamic
        if not default._children:
            out.append(self.close("default"))
            return
        out.append(">" + self.newline())
        for child in default._children:
            if child._spec.name == constants.DEFAULT:
                child_name = prefix + child._attributes.get("class", "")
                self.default_class(child, depth + 1, prefix, child_name)
            elif child._children or child._attributes:
                self.element(child, depth + 1, prefix, None)
        out.append(f"{self.indent(depth)}</default>{self.newline()}")

    # ------------------------------------------------------------------------- models

    def model(self, root: RootElement) -> None:
        models = _models_below(root)
        for model in models:
            self.prefixes[id(model)] = model._namescope.full_prefix(self.prefix_root)
        out = self.out
        name = root._attributes.get("model")
        out.append(f'<mujoco model="{_escape(name)}">' if name is not None else "<mujoco>")
        out.append(self.newline())
        for tag in schema.root_spec().children:
            if tag in constants.GLOBAL_OPTION_SECTIONS:
                self.merged_singleton(tag, _sections(models, tag), 1)
            elif tag == constants.DEFAULT:
                self.defaults(models)
            elif tag in _TOP_ONLY_SECTIONS:
                section = root._singleton_if_present(tag)
                if section is not None and (section._children or section._attributes):
                    self.element(section, 1, self.prefixes[id(root)], None)
            elif tag == constants.WORLDBODY:
                self.section(tag, [root], 1)
            else:
                self.section(tag, models, 1)
        out.append("</mujoco>" + self.newline())

    def section(self, tag: str, models, depth: int) -> None:
        out = self.out
        mark = len(out)
        out.append(f"{self.indent(depth)}<{tag}>{self.newline()}")
        for model in models:
            section = model._singleton_if_present(tag)
            if section is None:
                continue
            prefix = self.prefixes[id(model)]
            dclass = (prefix or _SEP) if self.full else None
            for child in section._children:
                if _worth_writing(child):
                    self.element(child, depth + 1, prefix, dclass)
        if len(out) == mark + 1:
            del out[mark:]
            return
        out.append(f"{self.indent(depth)}</{tag}>{self.newline()}")

    def defaults(self, models) -> None:
        out = self.out
        out.append(f"{self.indent(1)}<default>{self.newline()}")
        for model in models:
            prefix = self.prefixes[id(model)]
            default = model._singleton_if_present(constants.DEFAULT)
            if default is None:
                out.append(f'{self.indent(2)}<default class="{_escape(prefix or _SEP)}"')
                out.append(self.close("default"))
            else:
                self.default_class(default, 2, prefix, prefix or _SEP)
        out.append(f"{self.indent(1)}</default>{self.newline()}")

    def merged_singleton(self, tag: str, elements: list, depth: int) -> None:
        """Writes same-tag singletons of several models as one; the first value set wins."""
        if not elements:
            return
        skip = constants.ASSET_DIRECTORY_ATTRIBUTES if tag == "compiler" else ()
        merged = {}
        for element in elements:
            for name, value in element._attributes.items():
                if name not in skip and name not in merged:
                    merged[name] = (element, value)
        parts = [f"{self.indent(depth)}<{tag}"]
        for name, (element, value) in merged.items():
            value_type = element._spec.attributes[name].type
            if value_type.kind == _STRING:
                text = _escape(value)
            else:
                text = value_type.format(value, self.precision, self.zero_threshold)
            parts.append(f' {name}="{text}"')
        out = self.out
        mark = len(out)
        out.append("".join(parts))
        out.append(">" + self.newline())
        child_tags = []
        for element in elements:
            for child in element._children:
                if child._spec.name not in child_tags:
                    child_tags.append(child._spec.name)
        for child_tag in child_tags:
            children = [c for e in elements for c in e._children if c._spec.name == child_tag]
            self.merged_singleton(child_tag, children, depth + 1)
        if len(out) > mark + 2:
            out.append(f"{self.indent(depth)}</{tag}>{self.newline()}")
        elif merged:
            out[mark + 1 :] = [self.close(tag)]
        else:
            del out[mark:]


def _in_defaults(element: Element) -> bool:
    parent = element._parent
    while parent is not None:
        if parent._spec.name == constants.DEFAULT:
            return True
        parent = parent._parent
    return False


def _sections(models, tag: str) -> list:
    found = []
    for model in models:
        section = model._singleton_if_present(tag)
        if section is not None:
            found.append(section)
    return found


def _models_below(root: RootElement) -> list[RootElement]:
    """`root` and every model attached below it, depth first in attachment order."""
    models = [root]
    index = 0
    while index < len(models):
        model = models[index]
        index += 1
        for offset, frame in enumerate(model._frames):
            models.insert(index + offset, frame._attached)
    return models


def _scoped_identifier(target: Element, prefix: str) -> str:
    spec = target._spec
    if type(target) is AttachmentFrame:
        return prefix + target._attached._namescope.name + _SEP
    if spec.identifier == "class":
        if target._parent is target._root:
            return prefix or _SEP
        return prefix + target._attributes["class"]
    name = target._attributes.get("name")
    if name is not None:
        return prefix + name
    return (prefix or _SEP) + target._unnamed_id()


def element_to_string(
    element: Element, prefix_root, self_close, pretty_print, precision, zero_threshold
) -> str:
    """XML text of `element`; a RootElement gives a complete model with attachments merged."""
    if prefix_root is None:
        prefix_root = element._root
    if isinstance(element, RootElement):
        # Unchanged models (same modification count, no renames anywhere) reuse their text.
        key = (
            element._modification_count,
            NameScope.epoch,
            id(prefix_root),
            self_close,
            pretty_print,
            precision,
            zero_threshold,
        )
        cache = element._xml_string_cache
        if cache is not None and cache[0] == key:
            return cache[1]
        writer = _Writer(prefix_root, self_close, pretty_print, precision, zero_threshold, True)
        writer.model(element)
        text = "".join(writer.out)
        text = text[:-1] if pretty_print and text.endswith("\n") else text
        element._xml_string_cache = (key, text)
        return text
    else:
        writer = _Writer(prefix_root, self_close, pretty_print, precision, zero_threshold, False)
        if element._spec.name == constants.DEFAULT and element._parent is not None:
            prefix = writer.prefix_of(element._root)
            name = prefix + element._attributes.get("class", "")
            if element._parent is element._root and "class" not in element._attributes:
                name = prefix or _SEP
            writer.default_class(element, 0, prefix, name)
        else:
            writer.element(element, 0, writer.prefix_of(element._root), None)
    text = "".join(writer.out)
    return text[:-1] if pretty_print and text.endswith("\n") else text


def short_string(element: Element) -> str:
    """The element's opening tag and attributes, with '...' standing for its children."""
    writer = _Writer(element._root, True, False, 17, 0, False)
    tag = element._spec.name
    if isinstance(element, RootElement):
        name = element._attributes.get("model")
        head = f'<mujoco model="{_escape(name)}"' if name is not None else "<mujoco"
    elif type(element) is AttachmentFrame:
        static, _ = writer.cached_attributes(element)
        head = f'<body name="{_escape(element.prefixed_identifier(element._root))}"{static}'
    elif tag == constants.DEFAULT:
        identifier = element._attributes.get("class")
        head = f'<default class="{_escape(identifier)}"' if identifier else "<default"
    else:
        head, _ = writer.head(element, "", None, None)
    return f"{head}>...</{tag}>" if element._children else f"{head}/>"


def attribute_string(element: Element, spec, prefix_root) -> str | None:
    """XML text of one attribute of `element`, or None when it is unset."""
    value = element._attributes.get(spec.name)
    if value is None:
        return None
    writer = _Writer(prefix_root or element._root, True, False, 17, 0, False)
    value_type = spec.type
    kind = value_type.kind
    if kind == _STRING:
        return value
    if kind == _IDENTIFIER:
        return _scoped_identifier(element, writer.prefix_of(element._root))
    if kind == _REFERENCE:
        return writer.resolve(element, spec.name, value, value_type)
    if kind == _FILE:
        return value.get_vfs_filename() if isinstance(value, Asset) else value
    return value_type.format(value, 17, 0)


def collect_assets(root: RootElement) -> dict[str, bytes]:
    """VFS filename -> contents of every file asset in `root` and models attached below."""
    assets = {}
    for model in _models_below(root):
        prefix = model._namescope.full_prefix(root)
        for element in model._iter_own_tree():
            spec_attributes = element._spec.attributes
            for name, value in element._attributes.items():
                if isinstance(value, Asset) and spec_attributes[name].type.kind == _FILE:
                    value = _file_asset(element, value, prefix)
                    assets[value.get_vfs_filename()] = value.contents
    return assets


def _file_asset(element: Element, asset: Asset, prefix: str) -> Asset:
    """The file as written for a model with scope `prefix` (skin bones name scoped bodies)."""
    if prefix and element._spec.name == constants.SKIN:
        return skin_file.scoped(asset, prefix)
    return asset
