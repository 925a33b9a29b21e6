"""List views of an element's children with one tag (`body.geom`, `default.default`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mjcf.constants import PREFIX_SEPARATOR

if TYPE_CHECKING:
    from mjcf.element import Element


class ElementList:
    """Live view of an element's children with one tag, used like a list.

    Index by position, slice, or by identifier (`body.geom['trunk']`); `del view[i]` and
    `view.clear()` remove elements from the model; new ones are added with `parent.add`.
    As in dm_control, a top-level section's view (`root.actuator.motor`) also lists the
    elements of attached models (after its own; `['arm/drive']` finds one by scoped name),
    and an attachment frame's view the children of its model's worldbody.
    """

    __slots__ = ("_parent", "_tag")

    def __init__(self, parent: Element, tag: str):
        self._parent = parent
        self._tag = tag

    def _own(self) -> list[Element]:
        tag = self._tag
        return [c for c in self._parent._children if c._spec.name == tag]

    def _items(self) -> list[Element]:
        items = self._own()
        for _, scoped in self._scoped_views():
            items += scoped._items()
        return items

    def _scoped_views(self) -> list[tuple[str, ElementList]]:
        """(model name, same view in that model) for each model whose elements this view
        lists too: an attachment frame lists its model's worldbody children, a top-level
        section (`root.actuator`) the same section of each attached model."""
        return [
            (section._root._namescope.name, ElementList(section, self._tag))
            for section in self._parent._attached_sections()
        ]

    def __getitem__(self, index):
        if isinstance(index, str):
            return self._by_identifier(index)
        return self._items()[index]

    def _by_identifier(self, identifier: str) -> Element:
        scope, _, rest = identifier.partition(PREFIX_SEPARATOR)
        if rest:
            # 'arm/elbow': the element named 'elbow' of attached model 'arm'.
            for name, scoped in self._scoped_views():
                if name == scope:
                    try:
                        return scoped._by_identifier(rest)
                    except KeyError:
                        break
        else:
            for item in self._own():
                if item._attributes.get(item._spec.identifier or "name") == identifier:
                    return item
        raise KeyError(
            f"{self._parent._describe()} has no <{self._tag}> child named {identifier!r}"
        )

    def __delitem__(self, index) -> None:
        """Removes the element(s) at a position, slice or identifier from the model."""
        found = self[index]
        for element in found if isinstance(found, list) else [found]:
            element.remove()

    def clear(self) -> None:
        """Removes every element of this view from the model."""
        for element in self._items():
            element.remove()

    def __len__(self) -> int:
        return len(self._items())

    def __iter__(self):
        return iter(self._items())

    def __eq__(self, other) -> bool:
        if isinstance(other, ElementList):
            other = other._items()
        return self._items() == list(other)

    def __str__(self) -> str:
        return str([str(item) for item in self._items()])

    def __repr__(self) -> str:
        return f"MJCF Elements List: {self}"
