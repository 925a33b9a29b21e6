"""Tests for composer.define: cached_property and observable."""

from composer import define


class _Counter:
    def __init__(self):
        self.calls = 0

    @define.cached_property
    def value(self):
        """The number of calls at first access."""
        self.calls += 1
        return self.calls


def test_cached_property_is_computed_once_per_instance():
    counter = _Counter()
    assert (counter.value, counter.value, counter.calls) == (1, 1, 1)


def test_cached_property_is_separate_for_each_instance():
    first, second = _Counter(), _Counter()
    assert (first.value, second.calls) == (1, 0)


def test_cached_property_on_the_class_is_the_descriptor_with_docstring():
    assert isinstance(_Counter.value, define.cached_property)
    assert _Counter.value.__doc__ == "The number of calls at first access."


def test_observable_decorator_is_a_cached_property():
    class Holder:
        @define.observable
        def thing(self):
            return object()

    holder = Holder()
    assert holder.thing is holder.thing
    assert isinstance(Holder.thing, define.cached_property)
