"""A user's own task, batched: a pusher on two slide joints pushes a puck to a goal site.

Written as a plain CPU `composer.Task` first, the way a user who never batched would: the
goal site is placed every episode by an `MJCFVariator` on its `pos` (an
`initialize_episode_mjcf` change), the puck by a `PropPlacer` and the pusher by a joint
draw (`initialize_episode`). `BatchPushPuck` batches it with array code only (the reward);
the batch runs the CPU task's own hooks for every world's initial state and variation.

Used by tests/composer/batch/test_batch_push_puck.py and by the docs.
"""

import numpy as np

import composer
import mjcf
from composer import batch, initializers, variation
from composer.observation import observable
from composer.variation import distributions

#: The square the goal and the puck are drawn in, half its side (metres).
HALF_SIDE = 0.3
#: Where the pusher starts along each slide joint, at most (metres).
PUSHER_RANGE = 0.1
#: How close the puck must be to the goal for a reward of 1 (metres).
GOAL_RADIUS = 0.05


class _Floor(composer.Arena):
    def _build(self) -> None:
        super()._build(name="push_puck")
        self.mjcf_model.worldbody.add("geom", name="floor", type="plane", size=[1, 1, 0.1])
        self.goal = self.mjcf_model.worldbody.add(
            "site", name="goal", pos=[0, 0, 0.001], size=[GOAL_RADIUS], rgba=[0, 1, 0, 0.5]
        )


class _Pusher(composer.Entity):
    """A sphere on two horizontal slide joints, each driven by a motor."""

    def _build(self) -> None:
        self._model = mjcf.RootElement(model="pusher")
        body = self._model.worldbody.add("body", name="body", pos=[-0.4, 0, 0.03])
        self.joints = [
            body.add("joint", name=axis, type="slide", axis=direction, damping=5.0)
            for axis, direction in (("x", [1, 0, 0]), ("y", [0, 1, 0]))
        ]
        body.add("geom", name="ball", type="sphere", size=[0.03], mass=0.5)
        for joint in self.joints:
            self._model.actuator.add(
                "motor", name=joint.name, joint=joint, gear=[10], ctrlrange=[-1, 1]
            )

    @property
    def mjcf_model(self):
        return self._model


class _Puck(composer.Entity):
    """A free cylinder."""

    def _build(self) -> None:
        self._model = mjcf.RootElement(model="puck")
        self._model.worldbody.add(
            "geom", name="disc", type="cylinder", size=[0.04, 0.015], mass=0.2
        )

    @property
    def mjcf_model(self):
        return self._model


class PushPuck(composer.Task):
    """Push the puck to the goal: reward 1 within `GOAL_RADIUS`, falling off beyond."""

    def __init__(self):
        self._arena = _Floor()
        self.pusher = _Pusher()
        self.puck = _Puck()
        self._arena.attach(self.pusher)
        self._arena.add_free_entity(self.puck)
        self.goal = self._arena.goal
        self._goal_variator = variation.MJCFVariator()
        self._goal_variator.bind_attributes(
            self.goal,
            pos=distributions.Uniform(
                [-HALF_SIDE, -HALF_SIDE, 0.001], [HALF_SIDE, HALF_SIDE, 0.001]
            ),
        )
        self._puck_placer = initializers.PropPlacer(
            [self.puck],
            position=distributions.Uniform(
                [-HALF_SIDE, -HALF_SIDE, 0.016], [HALF_SIDE, HALF_SIDE, 0.016]
            ),
        )
        self._observables = {
            "goal_position": observable.MJCFFeature("xpos", self.goal),
            "puck_position": observable.MJCFFeature(
                "xpos", self.puck.mjcf_model.find("geom", "disc")
            ),
            "pusher_position": observable.MJCFFeature("qpos", self.pusher.joints),
        }
        for value in self._observables.values():
            value.enabled = True

    @property
    def root_entity(self):
        return self._arena

    @property
    def task_observables(self):
        return self._observables

    def initialize_episode_mjcf(self, random_state) -> None:
        self._goal_variator.apply_variations(random_state)

    def initialize_episode(self, physics, random_state) -> None:
        physics.bind(self.pusher.joints).qpos = random_state.uniform(
            -PUSHER_RANGE, PUSHER_RANGE, size=2
        )
        self._puck_placer(physics, random_state)

    def get_reward(self, physics) -> float:
        puck = physics.bind(self.puck.mjcf_model.find("geom", "disc")).xpos
        distance = np.linalg.norm(puck[:2] - physics.bind(self.goal).xpos[:2])
        return float(1.0 if distance <= GOAL_RADIUS else GOAL_RADIUS / distance)


class BatchPushPuck(batch.BatchTask):
    """`PushPuck`'s reward for every world, as array code."""

    def after_compile(self, physics) -> None:
        self._puck = physics.bind(self.task.puck.mjcf_model.find("geom", "disc"))
        self._goal = physics.bind(self.task.goal)

    def get_reward(self, physics):
        xp = physics.xp
        distance = xp.linalg.vector_norm(self._puck.xpos[:, :2] - self._goal.xpos[:, :2], axis=-1)
        return xp.where(distance <= GOAL_RADIUS, xp.ones_like(distance), GOAL_RADIUS / distance)


batch.register(PushPuck, BatchPushPuck)
