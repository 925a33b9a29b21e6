"""What an MJCF-bound observable reads: elements, a binding field, and keys into it."""

import dataclasses
import functools
from collections.abc import Callable
from typing import Any


@dataclasses.dataclass(frozen=True)
class MJCFSelection:
    """The part of `physics.bind(element).<field>` that an observable's value is.

    The one description of what such an observable reads, shared by its readers: the CPU
    observable reads `select(getattr(physics.bind(element), field))`, and its batched twin
    reads the same entries of every world (`composer.batch.observables.selection_reader`).

    Attributes:
      element: an `mjcf.Element`, or a list of elements of one kind, as `physics.bind`
        takes them.
      field: the binding attribute read, such as 'xpos', 'qpos' or 'sensordata'.
      indices: the keys applied in turn to the bound value (an int, a slice, an index
        array, ...); empty for the whole value.
    """

    element: Any
    field: str
    indices: tuple = ()

    def indexed(self, key) -> "MJCFSelection":
        """Returns this selection narrowed by `key`, applied after its own keys."""
        return dataclasses.replace(self, indices=self.indices + (key,))

    def select(self, value):
        """Returns `value`, the bound field or an array of its shape, indexed by `indices`."""
        for key in self.indices:
            value = value[key]
        return value

    def reader(self, physics) -> Callable[[], Any]:
        """Returns a zero-argument function reading the selection from `physics`.

        Args:
          physics: an `mjcf.Physics` whose model contains `element`.

        Returns:
          A function returning the selected value, as `select` gives it, at each call.
        """
        binding = physics.bind(self.element)
        if not self.indices:
            return functools.partial(getattr, binding, self.field)
        field, select = self.field, self.select
        return lambda: select(getattr(binding, field))
