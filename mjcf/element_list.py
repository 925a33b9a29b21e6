"""List views of an element's children with one tag (`body.geom`, `default.default`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mjcf.element import Element


class ElementList:
    """Live view of an element's children with one tag, used like a list.

    Index by position, slice, or by identifier (`body.geom['trunk']`); `del view[i]` and
    `view.clear()` remove elements from the model; new ones are added with `parent.add`.
    """

    __slots__ = ("_parent", "_tag")

    def __init__(self, parent: Element, tag: str):
        self._parent = parent
        self._tag = tag

    def _items(self) -> list[Element]:
        tag = self._tag
        return [c for c in self._parent._children if c._spec.name == tag]

    def __getitem__(self, index):
        items = self._items()
        if isinstance(index, str):
            for item in items:
                if item._attributes.get(item._spec.identifier or "name") == index:
                    return item
            raise KeyError(f"{self._parent._describe()} has no <{self._tag}> child named {index!r}")
        return items[index]

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
