"""Observable kinds (generic callables, named MuJoCo features, MJCF-bound features, cameras)
and the selection record that describes what an MJCF-bound feature reads."""

from composer.observation.observable.base import (
    AGGREGATORS,
    Generic,
    MujocoCamera,
    MujocoFeature,
    Observable,
)
from composer.observation.observable.mjcf import MJCFCamera, MJCFFeature
from composer.observation.observable.selection import MJCFSelection

__all__ = [
    "AGGREGATORS",
    "Generic",
    "MJCFCamera",
    "MJCFFeature",
    "MJCFSelection",
    "MujocoCamera",
    "MujocoFeature",
    "Observable",
]
