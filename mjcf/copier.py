"""Deep copies of whole models (`copy.copy(root)` / `copy.deepcopy(root)`)."""

from __future__ import annotations

import numpy as np

from mjcf import constants
from mjcf.attribute_array import frozen
from mjcf.element import AttachmentFrame, Element, RootElement, registry_namespace
from mjcf.option_merging import MERGED_OPTIONS


def copy_model(source: RootElement) -> RootElement:
    """An independent copy of `source` and of every model attached below it.

    References between elements of the copied models point into the copy; the copy is not
    attached to anything, even when `source` is.
    """
    memo: dict[int, Element] = {}
    copies: list[Element] = []

    def copy_root(model: RootElement) -> RootElement:
        scope = model._namescope
        new = RootElement(model_dir=scope.model_dir, assets=scope.assets)
        new._attributes = {k: frozen(v) for k, v in model._attributes.items()}
        new._texts = dict(model._texts)
        new._namescope._unnamed_counts = dict(scope._unnamed_counts)
        memo[id(model)] = new
        copy_children(model, new, new)
        return new

    def copy_children(old: Element, new: Element, root: RootElement) -> None:
        for child in old._children:
            if type(child) is AttachmentFrame:
                clone = AttachmentFrame._create(child._spec, new, root)
                attached = copy_root(child._attached)
                clone._attached = attached
                attached._frame = clone
                root._frames.append(clone)
            else:
                clone = Element._create(child._spec, new, root)
            clone._attributes = {k: frozen(v) for k, v in child._attributes.items()}
            clone._texts = dict(child._texts)
            clone._auto_id = child._auto_id
            memo[id(child)] = clone
            copies.append(clone)
            new._children.append(clone)
            copy_children(child, clone, root)

    new_root = copy_root(source)
    for element in copies:
        for name, value in element._attributes.items():
            if isinstance(value, Element):
                element._attributes[name] = memo.get(id(value), value)
    for element in copies:
        entry = element._identifier_entry()
        if entry is not None:
            element._root._namescope.add(entry[0], entry[1], element)
        if element._auto_id is not None:
            scope = element._root._namescope
            scope.add_unnamed(element._spec.namespace, element._auto_id, element)
    return new_root


def include_copy(
    destination: RootElement, source: RootElement, override_attributes: bool = False
) -> None:
    """Copies the contents of model `source` into model `destination`.

    Single children (`compiler`, `option`, ...) are merged into the destination's; repeated
    children are added as copies, except that with `override_attributes` an element whose
    identifier the destination already has is updated in place. Attributes the destination
    already sets must agree unless `override_attributes` (then the copied value wins);
    options that attached models may set differently combine as on attachment (see
    `mjcf.option_merging`). The destination keeps its model name. References between
    copied elements point to the copies afterwards.

    Raises:
      NotImplementedError: `source` has models attached to it.
      ValueError: conflicting attribute values, or an identifier that would clash.
    """
    if source._frames:
        raise NotImplementedError(
            f"include_copy: model {source._namescope.name!r} has attached models, which "
            "cannot be copied into another model; copy.deepcopy it and attach the copy"
        )
    counterparts: dict[int, Element] = {}
    _copy_into(destination, source, override_attributes, counterparts)
    for element in destination._iter_own_tree():
        for name, value in list(element._attributes.items()):
            if isinstance(value, Element) and id(value) in counterparts:
                element._attributes[name] = counterparts[id(value)]
                element._changed()


def _copy_into(destination: Element, source: Element, override: bool, counterparts) -> None:
    counterparts[id(source)] = destination
    _copy_attributes(destination, source, override)
    for child in source._children:
        spec = child._spec
        target = None
        identifier_attribute = spec.identifier
        if identifier_attribute is not None and override:
            identifier = child._attributes.get(identifier_attribute)
            if identifier is not None:
                target = destination.find(registry_namespace(spec), identifier)
                if target is not None and target._parent is not destination:
                    raise ValueError(
                        f"include_copy: {target._describe()} already exists elsewhere in "
                        f"the model, not in {destination._describe()}"
                    )
        if target is None and not spec.repeated:
            target = destination._child_view(destination._allowed_children()[spec.name])
        child_override = override
        if target is None:
            target = destination.add(spec.name)
            child_override = True
        _copy_into(target, child, child_override, counterparts)


def _copy_attributes(destination: Element, source: Element, override: bool) -> None:
    specs = destination._spec.attributes
    path = destination._section_path()
    updates = {}
    for name, value in source._attributes.items():
        if name == "model" and isinstance(destination, RootElement):
            continue
        mine = destination._attributes.get(name)
        if override or mine is None:
            updates[name] = value
            continue
        merge = MERGED_OPTIONS.get((tuple(path), name)) if path else None
        if merge is not None:
            updates[name] = merge(mine, value)
        elif name in constants.ASSET_DIRECTORY_ATTRIBUTES:
            continue
        elif not _same_value(mine, value):
            raise ValueError(
                f"include_copy: conflicting values for {destination._describe()} attribute "
                f"{specs[name].python_name!r}: {mine!r} here, {value!r} in the copied model "
                "(pass override_attributes=True to take the copied value)"
            )
    for name, value in updates.items():
        destination._set_attribute(specs[name].python_name, frozen(value))
    if updates:
        destination._changed()


def _same_value(first, second) -> bool:
    if isinstance(first, np.ndarray) or isinstance(second, np.ndarray):
        return np.array_equal(first, second)
    if isinstance(first, Element) or isinstance(second, Element):
        return getattr(first, "full_identifier", first) == getattr(
            second, "full_identifier", second
        )
    return first == second
