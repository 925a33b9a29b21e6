"""A Composer task built from scratch: a two-link arm pushes a box towards a target on a table.

Everything here is user code: an arena with a floor, a robot with motors and observables,
a free prop using the standard free-prop observables, and a task that enables the
observables the agent sees and rewards the box getting close to the target. It runs one
episode with random actions and prints how it went.

Usage: python examples/custom_task.py [--time_limit SECONDS] [--seed N]
"""

import argparse
import time

import numpy as np

import composer
import mjcf
from composer.observation import observable


class TableArena(composer.Arena):
    """An arena with a checkered floor and a target marker at `target_position`."""

    def _build(self, name="table"):
        super()._build(name=name)
        assets = self.mjcf_model.asset
        texture = assets.add(
            "texture", name="grid", type="2d", builtin="checker", width=64, height=64
        )
        material = assets.add("material", name="grid", texture=texture, texrepeat=[8, 8])
        worldbody = self.mjcf_model.worldbody
        worldbody.add("light", pos=[0, 0, 3], dir=[0, 0, -1])
        worldbody.add("geom", name="floor", type="plane", size=[1.5, 1.5, 0.1], material=material)
        self.target = worldbody.add(
            "site", name="target", type="sphere", size=[0.03], rgba=[0, 1, 0, 0.5]
        )


class ArmObservables(composer.Observables):
    """What the arm senses about itself."""

    @composer.observable
    def joint_positions(self):
        return observable.MJCFFeature("qpos", self._entity.joints)

    @composer.observable
    def joint_velocities(self):
        return observable.MJCFFeature("qvel", self._entity.joints)

    @composer.observable
    def fingertip_position(self):
        return observable.MJCFFeature("xpos", self._entity.fingertip)


class PlanarArm(composer.Robot):
    """A two-link arm on a vertical base, turning about the vertical axis, with two motors."""

    def _build(self, name="arm", link_length=0.3):
        self._model = mjcf.RootElement(model=name)
        base = self._model.worldbody.add("body", name="base", pos=[0, 0, 0.04])
        shoulder = base.add("joint", name="shoulder", type="hinge", axis=[0, 0, 1], damping=0.5)
        base.add("geom", type="capsule", fromto=[0, 0, 0, link_length, 0, 0], size=[0.03])
        forearm = base.add("body", name="forearm", pos=[link_length, 0, 0])
        elbow = forearm.add("joint", name="elbow", type="hinge", axis=[0, 0, 1], damping=0.5)
        forearm.add("geom", type="capsule", fromto=[0, 0, 0, link_length, 0, 0], size=[0.025])
        self.fingertip = forearm.add("site", name="fingertip", pos=[link_length, 0, 0])
        self.joints = (shoulder, elbow)
        self._actuators = tuple(
            self._model.actuator.add(
                "motor", name=joint.name, joint=joint, gear=[2.0], ctrlrange=[-1, 1]
            )
            for joint in self.joints
        )

    def _build_observables(self):
        return ArmObservables(self)

    @property
    def mjcf_model(self):
        return self._model

    @property
    def actuators(self):
        return self._actuators


class BoxObservables(composer.Observables, composer.FreePropObservableMixin):
    """Position, orientation and velocities of a free box."""


class Box(composer.Entity):
    """A light box that slides on the floor."""

    def _build(self, name="box", half_size=0.04):
        self._model = mjcf.RootElement(model=name)
        self.geom = self._model.worldbody.add(
            "geom", type="box", size=[half_size] * 3, mass=0.1, rgba=[0.8, 0.3, 0.2, 1]
        )
        self.half_size = half_size

    def _build_observables(self):
        return BoxObservables(self)

    @property
    def mjcf_model(self):
        return self._model


class PushBox(composer.Task):
    """Reward in (0, 1]: exp(-distance from the box to the target / 0.1)."""

    def __init__(self):
        self._arena = TableArena()
        self._arm = PlanarArm()
        self._box = Box()
        self._arena.attach(self._arm)
        self._arena.add_free_entity(self._box)
        for entity in (self._arm, self._box):
            entity.observables.enable_all()
        self.set_timesteps(control_timestep=0.04, physics_timestep=0.002)

    @property
    def root_entity(self):
        return self._arena

    @property
    def task_observables(self):
        target = observable.MJCFFeature("xpos", self._arena.target)
        target.enabled = True
        return {"target_position": target}

    def initialize_episode(self, physics, random_state):
        radius, angle = random_state.uniform(0.3, 0.5), random_state.uniform(-np.pi, np.pi)
        box_position = [radius * np.cos(angle), radius * np.sin(angle), self._box.half_size]
        self._box.set_pose(physics, position=box_position, quaternion=[1, 0, 0, 0])
        physics.bind(self._arena.target).pos = [*random_state.uniform(-0.4, 0.4, size=2), 0.01]
        physics.bind(self._arm.joints).qpos = random_state.uniform(-np.pi, np.pi, size=2)

    def get_reward(self, physics):
        box = physics.bind(self._box.root_body).xpos[:2]
        target = physics.bind(self._arena.target).xpos[:2]
        return float(np.exp(-np.linalg.norm(box - target) / 0.1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--time_limit", type=float, default=10.0, help="episode length (s)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    env = composer.Environment(PushBox(), time_limit=args.time_limit, random_state=args.seed)
    action_spec = env.action_spec()
    print(f"actions: {action_spec.shape} ({action_spec.name.replace(chr(9), ', ')})")
    for name, spec in env.observation_spec().items():
        print(f"observation {name}: shape {spec.shape}")

    policy = np.random.RandomState(args.seed)
    start = time.perf_counter()
    timestep = env.reset()
    steps, episode_return = 0, 0.0
    while not timestep.last():
        action = policy.uniform(action_spec.minimum, action_spec.maximum)
        timestep = env.step(action)
        steps += 1
        episode_return += timestep.reward
    elapsed = time.perf_counter() - start
    print(
        f"episode: {steps} steps, return {episode_return:.3f}, "
        f"{elapsed:.2f} s wall ({elapsed / steps * 1e3:.3f} ms per step)"
    )


if __name__ == "__main__":
    main()
