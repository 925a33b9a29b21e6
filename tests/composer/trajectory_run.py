"""Runs a seeded task and prints a SHA-256 digest of everything the agent saw.

Usage: ``python trajectory_run.py TASK SEED`` with TASK 'varied_reach' (a scene whose MJCF
and compiled physics are randomised every episode) or 'lift_brick' (a manipulation task).
Three episodes of 30 steps with actions drawn from numpy's RandomState(SEED); the digest
covers every observation's bytes, reward and discount, and the final physics state.
"""

import hashlib
import sys

import numpy as np
from composer_scene import ReachTask

import composer
from composer.variation import MJCFVariator, PhysicsVariator, distributions

EPISODES = 3
STEPS = 30


class VariedReach(ReachTask):
    """ReachTask whose box is resized and recoloured in the MJCF, and whose friction and arm
    damping are varied in the compiled physics, every episode."""

    def __init__(self):
        super().__init__()
        self.mjcf_variator = MJCFVariator()
        self.physics_variator = PhysicsVariator()
        self.mjcf_variator.bind_attributes(
            self.box.geom,
            size=distributions.Uniform([0.03] * 3, [0.07] * 3),
            rgba=distributions.Uniform([0, 0, 0, 1], [1, 1, 1, 1]),
        )
        self.physics_variator.bind_attributes(
            self.box.geom, friction=distributions.Uniform([0.5, 0.001, 0.0001], [1.5, 0.01, 0.001])
        )
        for joint in self.arm.joints:
            self.physics_variator.bind_attributes(joint, damping=distributions.Uniform(0.05, 0.5))

    def initialize_episode_mjcf(self, random_state):
        self.mjcf_variator.apply_variations(random_state)

    def initialize_episode(self, physics, random_state):
        self.physics_variator.apply_variations(physics, random_state)
        super().initialize_episode(physics, random_state)


def _task(name: str):
    if name == "varied_reach":
        return VariedReach()
    from manipulation.tasks import registry

    return registry.build_task("lift_brick_features")


def digest(name: str, seed: int) -> str:
    env = composer.Environment(_task(name), random_state=seed, time_limit=10.0)
    actions = np.random.RandomState(seed)
    spec = env.action_spec()
    hasher = hashlib.sha256()

    def record(timestep):
        for key, value in timestep.observation.items():
            hasher.update(key.encode())
            hasher.update(np.ascontiguousarray(value).tobytes())
        hasher.update(np.array([timestep.reward or 0.0, timestep.discount or 0.0]).tobytes())

    for _ in range(EPISODES):
        record(env.reset())
        for _ in range(STEPS):
            action = actions.uniform(spec.minimum, spec.maximum, size=spec.shape)
            record(env.step(action.astype(spec.dtype)))
        hasher.update(env.physics.get_state().tobytes())
    return hasher.hexdigest()


if __name__ == "__main__":
    print(digest(sys.argv[1], int(sys.argv[2])))
