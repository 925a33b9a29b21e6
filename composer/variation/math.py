"""Elementwise and reducing NumPy functions applied lazily to variations."""

from __future__ import annotations

import abc

import numpy as np

from composer.variation import base


class MathOp(base.Variation):
    """Applies `_callable` to the evaluated constructor arguments on every call."""

    def __init__(self, *args, **kwargs):
        self._args = args
        self._kwargs = kwargs

    @property
    @abc.abstractmethod
    def _callable(self):
        """The function applied to the evaluated arguments."""

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        args = base.evaluate(self._args, initial_value, current_value, random_state)
        kwargs = base.evaluate(self._kwargs, initial_value, current_value, random_state)
        return self._callable(*args, **kwargs)

    def __repr__(self):
        return f"{type(self).__name__}(args={self._args!r}, kwargs={self._kwargs!r})"


class Log(MathOp):
    """Natural logarithm (`np.log`)."""

    _callable = staticmethod(np.log)


class Max(MathOp):
    """Maximum (`np.max`)."""

    _callable = staticmethod(np.max)


class Min(MathOp):
    """Minimum (`np.min`)."""

    _callable = staticmethod(np.min)


class Norm(MathOp):
    """Vector or matrix norm (`np.linalg.norm`)."""

    _callable = staticmethod(np.linalg.norm)
