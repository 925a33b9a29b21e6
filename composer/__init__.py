"""Composer: build reinforcement-learning environments from reusable MJCF entities."""

from composer.arena import Arena
from composer.constants import SENSOR_SITES_GROUP
from composer.define import cached_property, observable
from composer.entity import Entity, FreePropObservableMixin, ModelWrapperEntity, Observables
from composer.environment import (
    HOOK_NAMES,
    Environment,
    EpisodeInitializationError,
    ObservationPadding,
)
from composer.initializer import Initializer
from composer.robot import Robot
from composer.task import NullTask, Task
from mjcf import PhysicsError

__all__ = [
    "HOOK_NAMES",
    "Arena",
    "Entity",
    "Environment",
    "EpisodeInitializationError",
    "FreePropObservableMixin",
    "Initializer",
    "ModelWrapperEntity",
    "NullTask",
    "ObservationPadding",
    "Observables",
    "PhysicsError",
    "Robot",
    "SENSOR_SITES_GROUP",
    "Task",
    "cached_property",
    "observable",
]
