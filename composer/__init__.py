"""Composer: build reinforcement-learning environments from reusable MJCF entities.

The names exported here, and the subpackages `observation`, `variation`, `initializers` and
`utils`, are dm_control's `dm_control.composer` API: the same names, signatures and
behaviour, so that code written for dm_control runs on this package (through
`composer.dm_control_compat`, which also serves this package as `dm_control.composer`).
`viewer.launch` takes the arguments of dm_control's `dm_control.viewer.launch`.

This project's own additions, which dm_control does not have:

- `composer.gym`: Gymnasium environments, vector envs (threads or Ray) and `VideoRecorder`;
- `composer.batch`: batched environments on MuJoCo Warp;
- `composer.video`: episode videos (`record_video`);
- `composer.dm_control_compat`: the import redirect that serves this project as `dm_control`.
"""

# First: it picks MuJoCo's OpenGL backend before mujoco is imported.
import mujoco_physics  # noqa: F401

# As on dm_control (whose observation updater imports it), `composer.variation` is there
# after `import composer` alone.
from composer import variation
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
    "variation",
]
