"""Decorators for declaring entity attributes: `cached_property` and `observable`."""

from collections.abc import Callable


class cached_property:
    """A read-only property computed on first access, then stored on the instance.

    After the first access the value lives in the instance's `__dict__`, so later reads are
    plain attribute look-ups with no Python call.
    """

    def __init__(self, func: Callable):
        self.func = func
        self.attrname = func.__name__
        self.__doc__ = func.__doc__
        self.__name__ = func.__name__
        self.__module__ = func.__module__

    def __set_name__(self, owner, name):
        self.attrname = name

    @property
    def fget(self) -> Callable:
        return self.func

    def __get__(self, instance, owner=None):
        if instance is None:
            return self
        value = self.func(instance)
        instance.__dict__[self.attrname] = value
        return value


class observable(cached_property):
    """Declares a method of an `Observables` class as an observable.

    The method returns an `Observable`; it is evaluated once, when the entity's
    `Observables` are built, and the `Observables` container lists it under the method's
    name.
    """
