"""The manipulation tasks batched on MuJoCo Warp: `load(name, num_envs)`.

Registers the batched versions of the reach and lift tasks with `composer.batch` and readers
for the arm's observables. Rewards, observations and initial states are those of the CPU
tasks: the initial states come from the CPU task's own initializers (see
`composer.batch.BatchTask.initialize_episode`), the rewards are the same formulas on arrays.
Needs the extra `[warp]` to build an environment; importing this module does not import Warp.
"""

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
        super().after_compile(physics)
        self._pinch = physics.bind(self.task.hand.tool_center_point)
        self._target = physics.bind(self.task.target)

    def get_reward(self, physics) -> np.ndarray:
        distance = np.linalg.norm(self._pinch.xpos - self._target.xpos, axis=-1)
        return rewards.tolerance(
            distance.astype(np.float64),
            bounds=(0.0, tc.REACH_RADIUS),
            margin=tc.REACH_MARGIN,
            sigmoid="gaussian",
        )


class BatchLift(batch.BatchTask):
    """`Lift` for every world: the height of the prop's lowest corner, scaled to
    `lift_height`, while the hand touches the prop; 0 otherwise."""

    def after_compile(self, physics) -> None:
        super().after_compile(physics)
        task = self.task
        self._vertices = physics.bind(task.prop.vertices)
        # 1 for the hand's geoms, 2 for the prop's: a hand-prop contact multiplies to 2.
        codes = np.zeros(physics.mj_model.ngeom, dtype=np.int8)
        codes[base.entity_geom_mask(physics.host, task.prop)] = 2
        codes[base.entity_geom_mask(physics.host, task.hand)] = 1
        self._geom_codes = codes

    def _hand_touches(self, physics) -> np.ndarray:
        contacts = physics.contacts()
        pair_codes = self._geom_codes[contacts.geom]
        touching = pair_codes[:, 0] * pair_codes[:, 1] == 2
        touches = np.zeros(physics.num_envs, dtype=bool)
        touches[contacts.worldid[touching]] = True
        return touches

    def get_reward(self, physics) -> np.ndarray:
        height = self._vertices.xpos[:, :, 2].min(axis=1).astype(np.float64)
        lift_height = self.task.lift_height
        progress = rewards.tolerance(
            height,
            bounds=(lift_height, np.inf),
            margin=lift_height,
            sigmoid="linear",
            value_at_margin=0.0,
        )
        earns = (height > 0.0) & (progress > 0.0)
        if not earns.any():
            return np.zeros(physics.num_envs)
        return np.where(earns & self._hand_touches(physics), progress, 0.0)


batch.register(Reach, BatchReach)
batch.register(Lift, BatchLift)


@batch.batch_reader.register
def _joint_angles(observable: _JointAngleSinCos, physics):
    joints = physics.bind(list(observable._joints))
    return lambda: np.stack([np.sin(q := joints.qpos), np.cos(q)], axis=-1)


@batch.batch_reader.register
def _joint_torques(observable: _JointTorques, physics):
    sensors = physics.bind(list(observable._sensors))
    axes = np.asarray(physics.host.bind(list(observable._joints)).axis, dtype=np.float32)
    return lambda: np.einsum("wjk,jk->wj", sensors.sensordata.reshape(-1, *axes.shape), axes)


#: The environment names with a batched version.
BATCHED = ("reach_site_features", "lift_brick_features")


def load(environment_name: str, num_envs: int, *, seed=None, **kwargs) -> batch.BatchEnvironment:
    """Returns `num_envs` worlds of the manipulation task `environment_name`, batched.

    Args:
      environment_name: one of `BATCHED` ('reach_site_features', 'lift_brick_features').
      num_envs: the number of worlds.
      seed: an int, a `np.random.RandomState` or None; seeds each world's generator.
      **kwargs: passed to `composer.batch.BatchEnvironment` (`device`, `random_states`,
        `time_limit`: the CPU task's 10 s unless given, ...).

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
    return batch.BatchEnvironment(task, num_envs, random_state=seed, **kwargs)


def make_vector_env(
    environment_name: str, num_envs: int, device: str | None, autoreset_mode, **kwargs
):
    """`load(...)` as a `composer.batch.gym.WarpVectorEnv` (`gymnasium.make_vec`'s backend
    'warp'); imports gymnasium.

    Raises:
      ValueError: for an autoreset mode other than NEXT_STEP.
    """
    from gymnasium.vector import AutoresetMode

    from composer.batch.gym import WarpVectorEnv

    if AutoresetMode(autoreset_mode) is not AutoresetMode.NEXT_STEP:
        raise ValueError(
            f"autoreset_mode: backend 'warp' resets worlds at the next step (NEXT_STEP), got "
            f"{autoreset_mode!r}"
        )
    env = load(environment_name, num_envs, device="cpu" if device is None else device, **kwargs)
    return WarpVectorEnv(env)
