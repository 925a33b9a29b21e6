"""Generates MJCF XML text from the object model, merging attached models into one document.

The text is assembled directly from string pieces. Each element caches the formatted text of
its plain attributes (per precision setting); identifiers, references and file names are
scoped at write time because they depend on where the model is attached. A model's first
whole-model write caches nothing on its elements (most models are written once) and gathers
the file assets on the way, for `get_assets`. Later whole-model writes cache each element's
opening tag, valid while the written model's naming stamp (see `NameScope`), the element's
scope prefix and its inherited default class stay the same. The whole text is kept, valid
while the model's modification count also stays the same.

Caches, and what invalidates them (the one place these rules are written down):

- `Element._xml_cache` (see `_HEAD_*` below): the element's plain attribute text for one
  precision setting, plus (from whole-model writes after a model's first) its opening tag.
  The plain text is valid while the precision setting is the same; the opening tag while
  the writer's stamp (format options, model and its naming stamp), the element's scope
  prefix and the class it inherits are too. `Element` clears it whenever an attribute of
  the element changes (so does the parser for the elements it fills in).
- `Element._text_cache` (`_TEXT_*`): the whole text of an element with children (or of
  a part of the document owned by an element, see `_Writer.kept`). Valid under the same text
  stamp (the stamp and pretty-printing options), scope prefix, inherited class and depth;
  `Element._changed` clears it on the changed element and every element enclosing it.
- `RootElement._xml_string_cache` (`_MODEL_*`): the whole model's text, valid while its key
  (modification count, naming stamp, scope prefix and format options)
  is the same.

A whole model is written so that every compiled object is addressable: unnamed elements that
compile to a named object get a generated name, and every element that accepts a default
class names its class explicitly. Unnamed `<asset>` and `<custom>` elements other than file
assets are the exception: one is written nameless, as the user gave it, until something
refers to it or asks for its name. Its generated name is made then, which renews the naming
stamp; when that happens during a write (the asset was already written nameless above the
reference), `element_to_string` writes the text again. Each model's global defaults live in
a class named after its scope prefix ('/' for the top model, 'child/' for a model attached
as 'child'), so the defaults of one model never leak into another.
"""

from __future__ import annotations

import sys

from mjcf import attribute_types, constants, schema, scoped_lookup, skin_file
from mjcf.asset import Asset
from mjcf.element import AttachmentFrame, Element, RootElement
from mjcf.option_merging import MERGED_OPTIONS

_SEP = constants.PREFIX_SEPARATOR
_STRING = attribute_types.STRING
_IDENTIFIER = attribute_types.IDENTIFIER
_OTHER = attribute_types.OTHER
_REFERENCE = attribute_types.REFERENCE
_FILE = attribute_types.FILE
_NAME_PREFIX = attribute_types.NAME_PREFIX
_FULL_PRECISION = (17, 0)
_DEFAULT = constants.DEFAULT
_JOINT = constants.JOINT
_MAIN = "main"
_WORLD = "world"
_NAMED_ON_DEMAND = constants.NAMED_ON_DEMAND_SECTIONS
_BODY = constants.BODY
_TOP_ONLY_SECTIONS = ("statistic",)
# An actuator shortcut (<position/>, <intvelocity/>, ...) in a default class sets the class's
# actuator settings even when it is empty, so it is written even then.
_ACTUATOR_TAGS = frozenset(schema.root_spec().children[constants.ACTUATOR].children)
# Writing takes a few Python frames per level of nesting, and MuJoCo reads models up to 499
# levels deep: more than Python's default limit of 1000 frames allows.
_FRAMES_NEEDED = 4000
# Top-level sections whose element text is only the model's own: the world (attached models
# hang below attachment frames), defaults (scoped per model) and the global settings.
_NOT_SHARED = (constants.WORLDBODY, constants.DEFAULT, *_TOP_ONLY_SECTIONS)
_NOT_SHARED += constants.GLOBAL_OPTION_SECTIONS


# The caches are plain tuples, read through these field positions: they are built once per
# element write, where a NamedTuple's constructor would make a rebuild of a model's text
# about a tenth slower.
#
# `Element._xml_cache`: (precision key, plain attribute text, stamp, scope prefix, inherited
# class, opening tag, class the children inherit); the last five are None when only the
# plain attribute text is kept.
_HEAD_PRECISION, _HEAD_STATIC, _HEAD_STAMP, _HEAD_PREFIX, _HEAD_INHERITED = range(5)
_HEAD_TAG, _HEAD_DCLASS = 5, 6
# `Element._text_cache`: (text stamp, scope prefix, inherited class, depth, text); a text of
# None means the part was seen once but not kept.
_TEXT_STAMP, _TEXT_PREFIX, _TEXT_INHERITED, _TEXT_DEPTH, _TEXT = range(5)
# `RootElement._xml_string_cache`: (key, text).
_MODEL_KEY, _MODEL_TEXT = 0, 1

# Setting the element caches bypasses Element.__setattr__, which handles XML attributes.
_set_xml_cache = Element.__dict__["_xml_cache"].__set__
_set_text_cache = Element.__dict__["_text_cache"].__set__


_escape = attribute_types.escape


def plain_text(element: Element) -> str:
    """The full-precision text of `element`'s plain attributes, in the order of its
    `_attributes`.

    `Element._texts` holds exactly the plain attributes, each with its text or None when
    it was set since the last write: those are formatted here, once, and kept.
    """
    texts = element._texts
    try:
        return "".join(texts.values())
    except TypeError:  # some text is None: not formatted yet
        specs = element._spec.attributes
        attributes = element._attributes
        for name, text in texts.items():
            if text is None:
                texts[name] = attribute_types.xml_text(name, specs[name].type, attributes[name])
        return "".join(texts.values())


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
        "full_precision",
        "pretty",
        "self_close",
        "full",
        "prefix_root",
        "prefixes",
        "sections",
        "resolved",
        "class_texts",
        "stamp",
        "text_stamp",
        "empty_close",
        "open_end",
        "shallow",
        "visit",
        "caching",
        "assets",
        "names",
    )

    def __init__(self, prefix_root, self_close, pretty, precision, zero_threshold, full):
        self.out: list[str] = []
        self.precision = precision
        self.zero_threshold = zero_threshold
        self.key = (precision, zero_threshold)
        self.full_precision = self.key == _FULL_PRECISION
        self.pretty = pretty
        self.self_close = self_close
        self.full = full
        self.prefix_root = prefix_root
        self.prefixes: dict[int, str] = {}
        self.sections: dict[int, dict[str, Element]] = {}
        # (model, attribute type, name) -> XML text of a name found in that model's own
        # scope (the type stands for the namespace it refers to).
        self.resolved: dict[tuple, str] = {}
        self.class_texts: dict[str, str] = {}
        # Element heads of a whole-model write are cached under this stamp with their scope
        # prefix and inherited class (see `model`); other writes do not use the cache.
        self.stamp = None
        # Whole texts of elements with children are cached under this stamp, with their
        # scope prefix, inherited class and depth.
        self.text_stamp = None
        self.empty_close = ("/>\n" if pretty else "/>") if self_close else None
        self.open_end = ">\n" if pretty else ">"
        # Writes only the element's own tag, with '...' standing for its children.
        self.shallow = False
        # Writes one element: `element`, or `fresh_element` on a model's first write.
        self.visit = self.element
        # Whether built opening tags are cached on the elements (whole-model writes after
        # the first; see `model`).
        self.caching = False
        # VFS filename -> contents of the file assets met by `fresh_element`, or None.
        self.assets: dict[str, bytes] | None = None
        # Whether unnamed elements that compile to a named object get their generated name
        # (all writes but the short form of `str(element)`).
        self.names = True

    def indent(self, depth: int) -> str:
        return "  " * depth if self.pretty else ""

    def newline(self) -> str:
        return "\n" if self.pretty else ""

    # ------------------------------------------------------------------ attribute text

    def static_text(self, element: Element) -> str:
        """Text of the plain attributes: those that read the same wherever the model is.

        Identifiers, references and files are left out; they are scoped at write time.
        """
        cache = element._xml_cache
        if cache is not None and cache[_HEAD_PRECISION] == self.key:
            return cache[_HEAD_STATIC]
        if self.full_precision:
            static = plain_text(element)
        else:
            specs = element._spec.attributes
            plain = element._texts
            static = "".join(
                attribute_types.xml_text(
                    name, specs[name].type, value, self.precision, self.zero_threshold
                )
                for name, value in element._attributes.items()
                if name in plain
            )
        _set_xml_cache(element, (self.key, static, None, None, None, None, None))
        return static

    def prefix_of(self, model: RootElement) -> str | None:
        prefix = self.prefixes.get(id(model))
        if prefix is None and not self.full:
            prefix = model._namescope.full_prefix(self.prefix_root)
            self.prefixes[id(model)] = prefix
        return prefix

    def resolve(self, element: Element, name: str, value, value_type) -> str:
        """The scoped identifier a reference attribute names, as written to XML."""
        root = element._root
        if type(value) is str:
            namespace = value_type.namespace
            if namespace is None:
                namespace = value_type.target_namespace(element._attributes)
                if namespace is None:
                    return _escape(self.prefix_of(root) + value)
            key = (root, value_type, value)
            text = self.resolved.get(key)
            if text is not None:
                return text
            if _SEP not in value and not (namespace == _DEFAULT and value == _MAIN):
                # An unscoped name registered in the element's own model: the common case,
                # resolved without the general scoped lookup.
                names = root._namescope._namespaces.get(namespace)
                if names is not None and value in names:
                    text = self.resolved[key] = _escape(self.prefix_of(root) + value)
                    return text
            target = scoped_lookup.lookup(root, namespace, value)
            if target is None:
                if value == _WORLD and namespace == _BODY and not self.prefix_of(root):
                    # MuJoCo's name for the world body, which the top model may refer to.
                    return _WORLD
                if element._spec.namespace is None and _in_defaults(element):
                    # MuJoCo only checks references of defaults that something uses.
                    return _escape(self.prefix_of(root) + value)
                if self.full:
                    raise ValueError(
                        f"{element._describe()} attribute {name!r} refers to {value!r}, but "
                        f"model {root._namescope.name!r} has no {namespace!r} "
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
        return _escape(target._scoped_name(prefix))

    # ---------------------------------------------------------------------- elements

    def element(self, element: Element, depth: int, prefix: str, dclass: str | None) -> None:
        """Writes `element` of the model with scope `prefix`; `dclass`: inherited class.

        Reuses what an earlier whole-model write kept on the element under the same stamp,
        scope prefix and class: its whole text, or its opening tag ("head"); anything else
        is built by `fresh_element`.
        """
        stamp = self.stamp
        # An attachment frame's text is kept by `kept` (see `fresh_element`), not here.
        if stamp is not None and not element._is_attachment_frame:
            text = element._text_cache
            if (
                text is not None
                and text[_TEXT_STAMP] == self.text_stamp
                and text[_TEXT_PREFIX] == prefix
                and text[_TEXT_INHERITED] == dclass
                and text[_TEXT_DEPTH] == depth
            ):
                self.out.append(text[_TEXT])
                return
            cache = element._xml_cache
            if (
                cache is not None
                and cache[_HEAD_STAMP] == stamp
                and cache[_HEAD_PREFIX] == prefix
                and cache[_HEAD_INHERITED] == dclass
            ):
                # Written before under the same names: likely to be written again, so its
                # whole text is kept (not on a first write, which would pay for joining it).
                self.tree(
                    element, cache[_HEAD_TAG], depth, prefix, cache[_HEAD_DCLASS], True, dclass
                )
                return
        self.fresh_element(element, depth, prefix, dclass)

    def fresh_element(self, element: Element, depth: int, prefix: str, dclass: str | None):
        """Writes `element` (see `element`), building its opening tag.

        On a model's first write (`self.caching` False) nothing is cached on the element and
        the file assets met are gathered into `self.assets`, so that a first compile walks
        the model once. This runs once per element of a new model: keep it lean.
        """
        if element._is_attachment_frame:
            self.kept(element, depth, prefix, dclass, self.frame, element, depth, dclass)
            return
        spec = element._spec
        tag = spec.name
        attributes = element._attributes
        plain = element._texts
        cache = element._xml_cache
        if cache is not None and cache[_HEAD_PRECISION] == self.key:
            static = cache[_HEAD_STATIC]
        elif self.full_precision:
            try:  # `plain_text(element)`, inline where every text is formatted already
                static = "".join(plain.values())
            except TypeError:
                static = plain_text(element)
        else:
            static = self.static_text(element)
        # Attributes that are neither plain nor the name: references and files.
        scoped = len(attributes) - len(plain)
        # Name first, then the class, as dm_control writes them; the joints of an
        # attachment frame (named after the frame) write their name last.
        name_text = ""
        if spec.identifier == "name":
            identifier = attributes.get("name")
            if identifier is not None:
                scoped -= 1
                if element._parent._is_attachment_frame:
                    name_text = f' name="{_escape(element._scoped_name(prefix))}"'
                else:
                    name_text = f' name="{_escape(prefix + identifier)}"'
            elif not self.names:
                pass
            elif spec.namespace == _JOINT:
                # An attachment frame's first unnamed joint is named after the frame.
                name_text = f' name="{_escape(element._generated_name(prefix))}"'
            elif (
                element._auto_id is None
                and element._parent._spec.name in _NAMED_ON_DEMAND
                and "file" not in attributes
            ):
                # Nothing refers to it yet: MuJoCo decides whether it needs a name (a
                # material does, a skybox texture does not), and a generated one would hide
                # that error. The first reference gives it one (see `element_to_string`).
                pass
            else:
                auto_id = element._auto_id or element._unnamed_id()
                name_text = f' name="{prefix or _SEP}{auto_id}"'
        if name_text and not element._parent._is_attachment_frame:
            head = f"<{tag}{name_text}"
            name_text = ""
        else:
            head = f"<{tag}"
        if spec.takes_class:
            explicit = attributes.get("class")
            if explicit is not None:
                scoped -= 1
                class_type = spec.attributes["class"].type
                head += f' class="{self.resolve(element, "class", explicit, class_type)}"'
            elif dclass is not None:
                text = self.class_texts.get(dclass)
                head += text if text is not None else self.class_text(dclass)
        head += static
        if scoped:
            specs = spec.attributes
            resolved = self.resolved
            for name, value in attributes.items():
                if name in plain:
                    continue
                value_type = specs[name].type
                kind = value_type.kind
                if kind == _REFERENCE:
                    if name == "class":
                        continue
                    text = None
                    if type(value) is str:
                        text = resolved.get((element._root, value_type, value))
                    if text is None:
                        text = self.resolve(element, name, value, value_type)
                    head += f' {name}="{text}"'
                elif kind == _FILE:
                    if isinstance(value, Asset):
                        value = _file_asset(element, value, self.prefix_of(element._root))
                        filename = value.get_vfs_filename()
                        if self.assets is not None:
                            self.assets[filename] = value.contents
                            self.assets.update(value.dependencies)
                        value = filename
                    head += f' {name}="{_escape(value)}"'
                elif kind == _NAME_PREFIX:
                    head += f' {name}="{_escape(prefix + value)}"'
        head += name_text
        inherited = dclass
        if spec.sets_childclass:
            childclass = attributes.get("childclass")
            if childclass is not None:
                childclass_type = spec.attributes["childclass"].type
                dclass = self.resolve(element, "childclass", childclass, childclass_type)
        if self.caching:
            _set_xml_cache(element, (self.key, static, self.stamp, prefix, inherited, head, dclass))
        if element._children:
            self.tree(element, head, depth, prefix, dclass, False, inherited)
            return
        out = self.out
        if self.pretty:
            out.append("  " * depth)
        out.append(head)
        out.append(self.empty_close or self.close(tag))

    def tree(self, element, head: str, depth: int, prefix: str, dclass, keep, inherited) -> None:
        """Writes `element` with opening tag `head` and its children, which inherit class
        `dclass`. With `keep`, the whole text is kept on the element, filed under the class
        `inherited` that `element` itself inherits."""
        out = self.out
        start = len(out)
        if self.pretty:
            out.append("  " * depth)
        out.append(head)
        tag = element._spec.name
        children = element._children
        if children:
            if self.shallow:
                out.append(f">...</{tag}>")
                return
            mark = len(out)
            out.append(self.open_end)
            visit = self.visit
            for child in children:
                # Inlined _worth_writing: this loop visits every element of the model.
                if (
                    child._children
                    or child._attributes
                    or child._spec.repeated
                    or child._spec.namespace is not None
                ):
                    visit(child, depth + 1, prefix, dclass)
            if len(out) > mark + 1:
                out.append(f"{'  ' * depth}</{tag}>\n" if self.pretty else f"</{tag}>")
                if keep:
                    text = "".join(out[start:])
                    out[start:] = [text]
                    _set_text_cache(element, (self.text_stamp, prefix, inherited, depth, text))
                return
            del out[mark:]
        out.append(self.empty_close or self.close(tag))

    def kept(self, owner: Element, depth: int, prefix: str, dclass, write, *args) -> None:
        """Writes `owner`'s part of the document by calling `write(*args)`.

        From the second whole-model write of the same part on (same stamp, scope prefix,
        class and depth), its text is kept in `owner._text_cache` and reused.
        """
        stamp = self.text_stamp
        if stamp is None:
            write(*args)
            return
        out = self.out
        cache = owner._text_cache
        seen = (
            cache is not None
            and cache[_TEXT_STAMP] == stamp
            and cache[_TEXT_PREFIX] == prefix
            and cache[_TEXT_INHERITED] == dclass
            and cache[_TEXT_DEPTH] == depth
        )
        kept_text = cache[_TEXT] if seen else None
        if kept_text is not None:
            if kept_text:
                out.append(kept_text)
                # Files in the reused text were not met: leave the assets to get_assets.
                self.assets = None
            return
        start = len(out)
        write(*args)
        text = None
        if seen:
            text = "".join(out[start:])
            out[start:] = [text] if text else []
        _set_text_cache(owner, (stamp, prefix, dclass, depth, text))

    def children(self, parent: Element, depth: int, prefix: str, dclass: str | None) -> None:
        """Writes the children of `parent` that change the compiled model."""
        for child in parent._children:
            if _worth_writing(child):
                self.visit(child, depth, prefix, dclass)

    def class_text(self, dclass: str) -> str:
        """' class="..."' for an inherited default class (a few distinct ones per model)."""
        text = self.class_texts.get(dclass)
        if text is None:
            text = self.class_texts[dclass] = f' class="{_escape(dclass)}"'
        return text

    def close(self, tag: str) -> str:
        return ("/>" if self.self_close else f"></{tag}>") + self.newline()

    def frame(self, frame: AttachmentFrame, depth: int, dclass: str | None) -> None:
        model = frame._attached
        own_prefix = self.prefix_of(frame._root)
        child_prefix = self.prefix_of(model)
        static = self.static_text(frame)
        out = self.out
        out.append(f'{self.indent(depth)}<body{static} name="{_escape(child_prefix)}">')
        out.append(self.newline())
        for child in frame._children:
            self.visit(child, depth + 1, own_prefix, dclass)
        world = model._singleton_if_present(constants.WORLDBODY)
        if world is not None:
            self.children(world, depth + 1, child_prefix, child_prefix or _SEP)
        out.append(f"{self.indent(depth)}</body>{self.newline()}")

    def default_class(self, default: Element, depth: int, prefix: str, name: str) -> None:
        out = self.out
        out.append(f'{self.indent(depth)}<default class="{_escape(name)}"')
        if not default._children:
            out.append(self.close("default"))
            return
        out.append(">" + self.newline())
        for child in default._children:
            if child._spec.name == constants.DEFAULT:
                child_name = prefix + child._attributes.get("class", "")
                self.default_class(child, depth + 1, prefix, child_name)
            elif child._children or child._attributes or child._spec.name in _ACTUATOR_TAGS:
                self.visit(child, depth + 1, prefix, None)
        out.append(f"{self.indent(depth)}</default>{self.newline()}")

    # ------------------------------------------------------------------------- models

    def model(self, root: RootElement) -> None:
        # Everything a head depends on lies in `root` and the models below it, whose naming
        # changes all renew `root`'s naming stamp; the scope prefix covers where `root` is.
        self.stamp = (self.key, id(root), root._namescope.naming_stamp)
        self.text_stamp = (self.stamp, self.pretty, self.self_close)
        self.caching = root._xml_string_cache is not None
        if not self.caching:
            self.visit = self.fresh_element
            if self.prefix_root is root:
                # Gathered as get_assets would: skins scoped by prefixes relative to `root`.
                self.assets = {}
        models = self.scope_models(root)
        out = self.out
        name = root._attributes.get("model")
        out.append(f'<mujoco model="{_escape(name)}">' if name is not None else "<mujoco>")
        out.append(self.newline())
        for tag in schema.root_spec().children:
            if tag in constants.GLOBAL_OPTION_SECTIONS:
                found = [self.sections[id(model)].get(tag) for model in models]
                self.merged_singleton((tag,), [s for s in found if s is not None], 1)
            elif tag == constants.DEFAULT:
                self.defaults(models, 1)
            elif tag in _TOP_ONLY_SECTIONS:
                section = root._singleton_if_present(tag)
                if section is not None and (section._children or section._attributes):
                    self.visit(section, 1, self.prefixes[id(root)], None)
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
            section = self.sections[id(model)].get(tag)
            if section is None:
                continue
            prefix = self.prefixes[id(model)]
            dclass = prefix or _SEP
            self.kept(
                section,
                depth + 1,
                prefix,
                dclass,
                self.children,
                section,
                depth + 1,
                prefix,
                dclass,
            )
        if len(out) == mark + 1:
            del out[mark:]
            return
        out.append(f"{self.indent(depth)}</{tag}>{self.newline()}")

    def defaults(self, models, depth: int) -> None:
        """Writes the `<default>` section: each model's global class, named after its scope
        prefix, holding the model's classes."""
        out = self.out
        out.append(f"{self.indent(depth)}<default>{self.newline()}")
        inner = depth + 1
        for model in models:
            prefix = self.prefixes[id(model)]
            default = self.sections[id(model)].get(constants.DEFAULT)
            if default is None:
                out.append(f'{self.indent(inner)}<default class="{_escape(prefix or _SEP)}"')
                out.append(self.close("default"))
            else:
                name = prefix or _SEP
                self.kept(
                    default, inner, prefix, name, self.default_class, default, inner, prefix, name
                )
        out.append(f"{self.indent(depth)}</default>{self.newline()}")

    def scope_models(self, root: RootElement) -> list[RootElement]:
        """Notes the scope prefix and sections of `root` and every model attached below it
        (see `model`); returns those models."""
        models = _models_below(root)
        for model in models:
            self.prefixes[id(model)] = model._namescope.full_prefix(self.prefix_root)
            # Section tag -> section, looked up once per tag per model below.
            self.sections[id(model)] = {c._spec.name: c for c in reversed(model._children)}
        return models

    def shared_section(self, section: Element) -> None:
        """Writes top-level `section` with the same section of every model attached below
        its model, as the whole model's text has it."""
        models = self.scope_models(section._root)
        mark = len(self.out)
        self.section(section._spec.name, models, 0)
        if len(self.out) == mark:
            tag = section._spec.name
            self.out.append(f"<{tag}/>" if self.self_close else f"<{tag}></{tag}>")
            self.out.append(self.newline())

    def merged_singleton(self, path: tuple[str, ...], elements: list, depth: int) -> None:
        """Writes the singletons at `path` of several models as one: the first value set
        wins, except for options that combine (see `mjcf.option_merging`)."""
        if not elements:
            return
        tag = path[-1]
        skip = constants.ASSET_DIRECTORY_ATTRIBUTES if tag == "compiler" else ()
        merged = {}
        for element in elements:
            for name, value in element._attributes.items():
                if name in skip:
                    continue
                if name not in merged:
                    merged[name] = (element, value)
                    continue
                merge = MERGED_OPTIONS.get((path, name))
                if merge is not None:
                    merged[name] = (merged[name][0], merge(merged[name][1], value))
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
            self.merged_singleton(path + (child_tag,), children, depth + 1)
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


def element_to_string(
    element: Element, prefix_root, self_close, pretty_print, precision, zero_threshold
) -> str:
    """XML text of `element`; a RootElement gives a complete model with attachments merged.

    Raises:
      ValueError: when the elements nest too deeply to write (far beyond what MuJoCo reads).
    """
    limit = sys.getrecursionlimit()
    if limit < _FRAMES_NEEDED:
        sys.setrecursionlimit(_FRAMES_NEEDED)
    scope = element._root._namescope
    stamp = scope.naming_stamp
    try:
        text = _element_to_string(
            element, prefix_root, self_close, pretty_print, precision, zero_threshold
        )
        if scope.naming_stamp != stamp:
            # A reference met while writing gave an unnamed asset, written nameless further
            # up, its generated name (which renews the stamp of its model and of the models
            # above it). Every reference has its name now, so a second write is final.
            text = _element_to_string(
                element, prefix_root, self_close, pretty_print, precision, zero_threshold
            )
        return text
    except RecursionError:
        raise ValueError(
            f"{element._describe()}: elements nest too deeply to write "
            "(MuJoCo reads at most 499 levels)"
        ) from None
    finally:
        sys.setrecursionlimit(limit)


def _element_to_string(
    element: Element, prefix_root, self_close, pretty_print, precision, zero_threshold
) -> str:
    if prefix_root is None:
        prefix_root = element._root
    if isinstance(element, RootElement):
        # An unchanged model keeps its text: nothing in it or below it changed, and its
        # identifiers are scoped as before.
        key = (
            element._modification_count,
            element._namescope.naming_stamp,
            element._namescope.full_prefix(prefix_root),
            self_close,
            pretty_print,
            precision,
            zero_threshold,
        )
        cache = element._xml_string_cache
        if cache is not None and cache[_MODEL_KEY] == key:
            return cache[_MODEL_TEXT]
        writer = _Writer(prefix_root, self_close, pretty_print, precision, zero_threshold, True)
        writer.model(element)
        text = "".join(writer.out)
        element._xml_string_cache = (key, text)
        if writer.assets is not None:
            element._assets_cache = (element._files_count, writer.assets)
        return text
    else:
        writer = _Writer(prefix_root, self_close, pretty_print, precision, zero_threshold, False)
        if element._spec.name == constants.DEFAULT and element._parent is element._root:
            # As in the whole model: the model's global class, then those of attached models.
            writer.scope_models(element._root)
            writer.defaults(_models_below(element._root), 0)
        elif element._spec.name == constants.DEFAULT and element._parent is not None:
            prefix = writer.prefix_of(element._root)
            writer.default_class(element, 0, prefix, prefix + element._attributes.get("class", ""))
        elif _is_shared_section(element):
            writer.shared_section(element)
        else:
            prefix = writer.prefix_of(element._root)
            writer.element(element, 0, prefix, _inherited_class(writer, element, prefix))
    return "".join(writer.out)


def _is_shared_section(element: Element) -> bool:
    """Whether `element` is a top-level section that stands for the same section of the
    models attached below its model too (`root.actuator`, `root.contact`, ...)."""
    root = element._root
    return (
        element._parent is root
        and bool(root._frames)
        and element._spec.name not in _NOT_SHARED
        and bool(element._children or any(f._attached._children for f in root._frames))
    )


def _inherited_class(writer: _Writer, element: Element, prefix: str) -> str | None:
    """The default class `element` inherits: its nearest `childclass`, else its model's
    global class (none inside `<default>`)."""
    parent = element._parent
    while parent is not None:
        spec = parent._spec
        if spec.name == _DEFAULT:
            return None
        if spec.sets_childclass:
            childclass = parent._attributes.get("childclass")
            if childclass is not None:
                value_type = spec.attributes["childclass"].type
                return writer.resolve(parent, "childclass", childclass, value_type)
        parent = parent._parent
    return prefix or _SEP


def short_string(element: Element, prefix_root=None) -> str:
    """The element's opening tag and attributes, with '...' standing for its children."""
    writer = _Writer(prefix_root or element._root, True, False, 17, 0, False)
    tag = element._spec.name
    if isinstance(element, RootElement):
        name = element._attributes.get("model")
        head = f'<mujoco model="{_escape(name)}"' if name is not None else "<mujoco"
    elif element._is_attachment_frame:
        static = writer.static_text(element)
        head = f'<body{static} name="{_escape(element.prefixed_identifier(element._root))}"'
    elif tag == constants.DEFAULT:
        identifier = element._attributes.get("class")
        head = f'<default class="{_escape(identifier)}"' if identifier else "<default"
    else:
        writer.shallow = True
        writer.names = False
        prefix = writer.prefix_of(element._root)
        writer.element(element, 0, prefix, _inherited_class(writer, element, prefix))
        return "".join(writer.out)
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
        return element._scoped_name(writer.prefix_of(element._root))
    if kind == _REFERENCE:
        return writer.resolve(element, spec.name, value, value_type)
    if kind == _FILE:
        return value.get_vfs_filename() if isinstance(value, Asset) else value
    if kind == _NAME_PREFIX:
        return writer.prefix_of(element._root) + value
    return value_type.format(value, 17, 0)


def collect_assets(root: RootElement) -> dict[str, bytes]:
    """VFS filename -> contents of every file asset in `root` and models attached below."""
    assets = {}
    for model in _models_below(root):
        prefix = model._namescope.full_prefix(root)
        # Depth first in document order, skipping subtrees that cannot hold files.
        stack = [model]
        while stack:
            element = stack.pop()
            spec_attributes = element._spec.attributes
            for name, value in element._attributes.items():
                if isinstance(value, Asset) and spec_attributes[name].type.kind == _FILE:
                    value = _file_asset(element, value, prefix)
                    assets[value.get_vfs_filename()] = value.contents
                    assets.update(value.dependencies)
            stack.extend([c for c in reversed(element._children) if c._spec.holds_files])
    return assets


def _file_asset(element: Element, asset: Asset, prefix: str) -> Asset:
    """The file as written for a model with scope `prefix` (skin bones name scoped bodies)."""
    if prefix and element._spec.name == constants.SKIN:
        return skin_file.scoped(asset, prefix)
    return asset
