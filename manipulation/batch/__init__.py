"""The manipulation tasks batched on MuJoCo Warp: `load(name, num_envs)`.

Registers the batched versions of the reach and lift tasks with `composer.batch` and readers
for the arm's observables. Rewards, observations and initial states are those of the CPU
tasks: the initial states come from the CPU task's own initializers (see
`composer.batch.BatchTask.initialize_episode`), the rewards are the same formulas on arrays.
Needs the extra `[warp]` to build an environment; importing this module does not import Warp.
"""

import functools

import numpy as np

from composer import batch
from composer.utils import rewards
from manipulation.arms.jaco_arm import _JointAngleSinCos, _JointTorques
from manipulation.tasks import base, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.lift import Lift
from manipulation.tasks.reach import Reach

__all__ = ["BATCHED", "BatchLift", "BatchReach", "load", "make_vector_env"]


class BatchReach(batch.BatchTask):
    """`Reach` for every world: 1 within `REACH_RADIUS` of the target, Gaussian beyond.

    The target site's position is a model parameter set at every reset, so `site_pos` is a
    per-world model field.
    """

    batched_model_fields = ("site_pos",)

    def after_compile(self, physics) -> None:
        self._pinch = physics.bind(self.task.hand.tool_center_point)
        self._target = physics.bind(self.task.target)

    def get_reward(self, physics):
        xp = physics.xp
        distance = xp.linalg.vector_norm(self._pinch.xpos - self._target.xpos, axis=-1)
        return rewards.tolerance(
            distance, bounds=(0.0, tc.REACH_RADIUS), margin=tc.REACH_MARGIN, sigmoid="gaussian"
        )


class BatchLift(batch.BatchTask):
    """`Lift` for every world: the height of the prop's lowest corner, scaled to
    `lift_height`, while the hand touches the prop; 0 otherwise."""

    def after_compile(self, physics) -> None:
        task = self.task
        self._vertices = physics.bind(task.prop.vertices)
        self._touches = physics.contact_watch(
            base.entity_geom_mask(physics.host, task.hand),
            base.entity_geom_mask(physics.host, task.prop),
        )

    def get_reward(self, physics):
        xp = physics.xp
        height = xp.min(self._vertices.xpos[:, :, 2], axis=1)
        lift_height = self.task.lift_height
        progress = rewards.tolerance(
            height,
            bounds=(lift_height, float("inf")),
            margin=lift_height,
            sigmoid="linear",
            value_at_margin=0.0,
        )
        earns = (height > 0.0) & (progress > 0.0) & self._touches()
        return xp.where(earns, progress, xp.zeros_like(progress))


batch.register(Reach, BatchReach)
batch.register(Lift, BatchLift)


@batch.batch_reader.register
def _joint_angles(observable: _JointAngleSinCos, physics):
    joints = physics.bind(list(observable._joints))
    xp = physics.xp
    return lambda: xp.stack([xp.sin(q := joints.qpos), xp.cos(q)], axis=-1)


@batch.batch_reader.register
def _joint_torques(observable: _JointTorques, physics):
    sensors = physics.bind(list(observable._sensors))
    axes = np.asarray(physics.host.bind(list(observable._joints)).axis, dtype=np.float32)
    device_axes = physics.arrays.asarray(axes)
    xp = physics.xp
    return lambda: xp.sum(xp.reshape(sensors.sensordata, (-1, *axes.shape)) * device_axes, axis=-1)


#: The environment names with a batched version.
BATCHED = ("reach_site_features", "lift_brick_features")


def load(environment_name: str, num_envs: int, *, seed=None, **kwargs) -> batch.BatchEnvironment:
    """Returns `num_envs` worlds of the manipulation task `environment_name`, batched.

    Args:
      environment_name: one of `BATCHED`.
      num_envs: the number of worlds.
      seed: an int, a `np.random.RandomState` or None; seeds each world's generator.
      **kwargs: passed to `composer.batch.BatchEnvironment` (`device`, `random_states`,
        `array_type`, `autoreset_mode`, `state_workers`, `time_limit`: the CPU task's
        10 s unless given, ...). Initial-state producers build their tasks by name.

    Raises:
      ValueError: if the name is not one of `BATCHED`.
    """
    if environment_name not in BATCHED:
        raise ValueError(
            f"environment_name: expected one of {list(BATCHED)} (the batched tasks), got "
            f"{environment_name!r}"
        )
    task = registry.build_task(environment_name)
    kwargs.setdefault("time_limit", tc.TIME_LIMIT)
    kwargs.setdefault("task_factory", functools.partial(registry.build_task, environment_name))
    return batch.BatchEnvironment(task, num_envs, random_state=seed, **kwargs)


def make_vector_env(
    environment_name: str, num_envs: int, device: str | None, autoreset_mode, **kwargs
):
    """`load(...)` as a `composer.batch.gym.WarpVectorEnv` (`gymnasium.make_vec`'s backend
    'warp', with Gymnasium's NEXT_STEP or SAME_STEP autoreset); imports gymnasium.

    Raises:
      ValueError: for Gymnasium's DISABLED autoreset mode.
    """
    from composer.batch.gym import WarpVectorEnv, autoreset_mode_name

    mode = autoreset_mode_name(autoreset_mode)
    env = load(environment_name, num_envs, device=device, autoreset_mode=mode, **kwargs)
    return WarpVectorEnv(env)
