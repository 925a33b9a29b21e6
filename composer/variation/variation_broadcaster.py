"""Sharing one sampled value of a variation among several consumers."""

from __future__ import annotations

import collections
import weakref

from composer.variation import base


class VariationBroadcaster:
    """Wraps a variation so that several consumers see the same sequence of values.

    Each consumer gets its own proxy from `get_proxy()`. A proxy that has consumed every value
    sampled so far triggers a new sample of the wrapped variation, which is then queued for
    every proxy; so in each round in which every proxy is called once, all of them return the
    same value. The wrapped variation is evaluated with `initial_value` and `current_value`
    None, since consumers may differ in theirs.
    """

    def __init__(self, wrapped_variation):
        self._wrapped_variation = wrapped_variation
        self._proxies = weakref.WeakSet()

    def get_proxy(self) -> base.Variation:
        """Returns a new variation that yields this broadcaster's shared values."""
        proxy = _BroadcastProxy(self)
        self._proxies.add(proxy)
        return proxy

    def _next_value(self, proxy: _BroadcastProxy, random_state):
        if not proxy._pending:
            value = base.evaluate(self._wrapped_variation, None, None, random_state)
            for each in self._proxies:
                each._pending.append(value)
        return proxy._pending.popleft()


class _BroadcastProxy(base.Variation):
    def __init__(self, broadcaster: VariationBroadcaster):
        self._broadcaster = broadcaster
        self._pending = collections.deque()

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        return self._broadcaster._next_value(self, random_state)
