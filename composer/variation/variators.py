"""Apply bound variations to MJCF attributes (before compiling) or to compiled physics."""

from __future__ import annotations

import copy

from composer.variation.base import evaluate


class _VariationInfo:
    __slots__ = ("initial_value", "variation")

    def __init__(self, initial_value, variation):
        self.initial_value = initial_value
        self.variation = variation


class _Variator:
    def __init__(self):
        self._variations: dict = {}

    def _bind(self, element, initial_values: dict, variations: dict) -> None:
        bound = self._variations.setdefault(element, {})
        for name, variation in variations.items():
            if variation is None:
                bound.pop(name, None)
            else:
                bound[name] = _VariationInfo(initial_values.get(name), variation)
        if not bound:
            del self._variations[element]

    def clear(self) -> None:
        """Removes every bound variation."""
        self._variations.clear()

    def reset_initial_values(self) -> None:
        """Forgets the remembered initial values; the next application records them afresh."""
        for bound in self._variations.values():
            for info in bound.values():
                info.initial_value = None


def _no_attribute_error(element, name: str, owner: str) -> AttributeError:
    try:
        element_name = element.name
    except AttributeError:
        element_name = None
    described = (
        f"<{element.tag}>" if element_name is None else f"<{element.tag} name={element_name!r}>"
    )
    return AttributeError(f"{owner}: {described} has no attribute {name!r}")


class MJCFVariator(_Variator):
    """Sets MJCF element attributes from variations, e.g. once per episode before compiling.

    The value each attribute has when it is bound is remembered and passed to its variation
    as `initial_value` on every application, so non-cumulative noise does not drift.
    """

    def bind_attributes(self, element, **variations) -> None:
        """Binds variations to attributes of an MJCF element.

        Args:
          element: An `mjcf.Element`.
          **variations: Attribute name -> a `Variation` or a constant (set as is). None
            removes a previous binding of that attribute.

        Raises:
          AttributeError: If the element has no such attribute.
        """
        initial_values = {}
        for name, variation in variations.items():
            if variation is None:
                continue
            try:
                initial_values[name] = copy.copy(getattr(element, name))
            except AttributeError as error:
                raise _no_attribute_error(element, name, "MJCFVariator") from error
        self._bind(element, initial_values, variations)

    def apply_variations(self, random_state) -> None:
        """Evaluates every bound variation and writes the results into the MJCF elements."""
        for element, bound in self._variations.items():
            new_values = {}
            for name, info in bound.items():
                current_value = getattr(element, name)
                if info.initial_value is None:
                    info.initial_value = copy.copy(current_value)
                new_values[name] = evaluate(
                    info.variation, info.initial_value, current_value, random_state
                )
            element.set_attributes(**new_values)


class PhysicsVariator(_Variator):
    """Writes variations into a compiled model/data through `physics.bind`, e.g. per episode.

    Attribute names are those of `physics.bind(element)` (`rgba`, `mass`, `friction`, `qpos`,
    ...). The value found the first time a binding is applied is remembered and passed to the
    variation as `initial_value` on every application.
    """

    def bind_attributes(self, element, **variations) -> None:
        """Binds variations to the physics attributes of an MJCF element.

        Args:
          element: An `mjcf.Element` of a compiled object family (geom, body, joint, ...).
          **variations: Binding attribute name -> a `Variation` or a constant. None removes a
            previous binding of that attribute.
        """
        self._bind(element, {}, variations)

    def apply_variations(self, physics, random_state) -> None:
        """Evaluates every bound variation and writes the results into `physics`.

        Raises:
          AttributeError: If an element's physics binding has no such attribute.
        """
        for element, bound in self._variations.items():
            binding = physics.bind(element)
            for name, info in bound.items():
                try:
                    current_value = getattr(binding, name)
                except AttributeError as error:
                    raise _no_attribute_error(element, name, "PhysicsVariator") from error
                if info.initial_value is None:
                    info.initial_value = copy.copy(current_value)
                value = evaluate(info.variation, info.initial_value, current_value, random_state)
                setattr(binding, name, value)
