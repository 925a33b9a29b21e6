"""`SizePatchCache`: what size patches of one compiled model looked up, kept for the next."""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

from mjcf import binding

__all__ = ["ElementsUsing", "FieldTarget", "SizePatchCache", "SpringdamperScan"]


class SpringdamperScan(NamedTuple):
    """Whether a joint of an MJCF model took `springdamper`, at a modification count."""

    modification_count: int
    found: bool


class ElementsUsing(NamedTuple):
    """The elements that take a default template's attribute, at a modification count."""

    modification_count: int
    elements: list


class FieldTarget(NamedTuple):
    """Where an element's attribute compiles to: `array[index]`, of `shape` and `size`, in
    the compiled model `model` (the array being a view of that model's memory)."""

    model: object
    array: object
    index: object
    shape: tuple
    size: int


@dataclasses.dataclass
class SizePatchCache:
    """What `mjcf.patching.geom_size_patch` (and `mjcf.patching.model_patch`, the ids of the
    elements it writes) looked up in one compiled model, for its later patches.

    Valid for the structure of the compiled model it was filled from (the ids and bodies
    of its elements), which attribute patches never change: `mjcf.Physics` holds one per
    model it loads and starts a new one when it loads another.

    Attributes:
      bodies: (element, `InertiaSettings`) -> its `CompiledBody`, None where its geoms
        cannot be patched.
      springdamper: the last look at the MJCF model's joints, None before the first.
      copies: the bodies' geoms and settings -> their `BodyCopies`.
      object_ids: element (a `<geom>` whose size changed, an element whose attribute
        `mjcf.patching.model_patch` wrote) -> its compiled id, None where it has none
        (`object_id`).
      field_targets: (element, XML attribute) that `mjcf.patching.model_patch` wrote -> its
        `FieldTarget` in the compiled model, None where it has none.
      elements_using: (default template, XML attribute) -> the `ElementsUsing` it.
    """

    bodies: dict = dataclasses.field(default_factory=dict)
    springdamper: SpringdamperScan | None = None
    copies: dict = dataclasses.field(default_factory=dict)
    object_ids: dict = dataclasses.field(default_factory=dict)
    field_targets: dict = dataclasses.field(default_factory=dict)
    elements_using: dict = dataclasses.field(default_factory=dict)

    def object_id(self, physics, element) -> int | None:
        """`element`'s compiled id in `physics`, None where it has none; looked up once."""
        if element not in self.object_ids:
            try:
                object_id = binding.object_id(physics.field_layout, physics.mjcf_model, element)
            except ValueError:
                object_id = None
            self.object_ids[element] = object_id
        return self.object_ids[element]
