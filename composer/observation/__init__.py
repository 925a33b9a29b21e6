"""Observables and the machinery that samples, delays, buffers and aggregates them."""

from composer.observation import observable
from composer.observation.obs_buffer import Buffer
from composer.observation.updater import (
    DEFAULT_BUFFER_SIZE,
    DEFAULT_DELAY,
    DEFAULT_UPDATE_INTERVAL,
    Updater,
)

__all__ = [
    "DEFAULT_BUFFER_SIZE",
    "DEFAULT_DELAY",
    "DEFAULT_UPDATE_INTERVAL",
    "Buffer",
    "Updater",
    "observable",
]
