"""List views of an element's children with one tag (`body.geom`, `default.default`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mjcf.element import Element


class ElementList:
    """Read-only view of an element's children with one tag; index by position or name."""

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

    def __len__(self) -> int:
        return len(self._items())

    def __iter__(self):
        return iter(self._items())

    def __eq__(self, other) -> bool:
        if isinstance(other, ElementList):
            other = other._items()
        return self._items() == list(other)

    def __repr__(self) -> str:
        return f"ElementList({self._items()!r})"
