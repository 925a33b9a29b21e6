"""Deep copies of whole models (`copy.copy(root)` / `copy.deepcopy(root)`)."""

from __future__ import annotations

from mjcf.attribute_array import frozen
from mjcf.element import Element, RootElement


def copy_model(source: RootElement) -> RootElement:
    """An independent copy of `source` and of every model attached below it.

    References between elements of the copied models point into the copy; the copy is not
    attached to anything, even when `source` is.
    """
    from mjcf.attachment import AttachmentFrame

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
