"""Observable kinds: generic callables, named MuJoCo features, MJCF-bound features, cameras."""

from composer.observation.observable.base import (
    AGGREGATORS,
    Generic,
    MujocoCamera,
    MujocoFeature,
    Observable,
)
from composer.observation.observable.mjcf import MJCFCamera, MJCFFeature

__all__ = [
    "AGGREGATORS",
    "Generic",
    "MJCFCamera",
    "MJCFFeature",
    "MujocoCamera",
    "MujocoFeature",
    "Observable",
]
