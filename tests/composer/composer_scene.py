"""A small scene shared by the composer tests: a floor arena, a two-joint arm and a free box."""

import numpy as np

import composer
import mjcf
from composer.observation import observable


class Floor(composer.Arena):
    """An arena with a ground plane."""

    def _build(self, name="floor"):
        super()._build(name=name)
        self.mjcf_model.worldbody.add("geom", name="ground", type="plane", size=[2, 2, 0.1])


class ArmObservables(composer.Observables):
    @composer.observable
    def joint_positions(self):
        return observable.MJCFFeature("qpos", self._entity.joints)

    @composer.observable
    def joint_velocities(self):
        return observable.MJCFFeature("qvel", self._entity.joints)

    @composer.observable
    def tip_position(self):
        return observable.MJCFFeature("xpos", self._entity.tip)


class Arm(composer.Robot):
    """Two hinge joints in a chain, each driven by a motor limited to [-1, 1]."""

    def _build(self, name="arm"):
        self._model = mjcf.RootElement(model=name)
        upper = self._model.worldbody.add("body", name="upper", pos=[0, 0, 0.5])
        shoulder = upper.add("joint", name="shoulder", type="hinge", axis=[0, 1, 0], damping=0.1)
        upper.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.03])
        lower = upper.add("body", name="lower", pos=[0.3, 0, 0])
        elbow = lower.add("joint", name="elbow", type="hinge", axis=[0, 1, 0], damping=0.1)
        lower.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.025])
        self.tip = lower.add("site", name="tip", pos=[0.3, 0, 0])
        self.joints = [shoulder, elbow]
        self._actuators = [
            self._model.actuator.add(
                "motor", name=f"{joint.name}_motor", joint=joint, ctrlrange=[-1, 1], gear=[5]
            )
            for joint in self.joints
        ]

    def _build_observables(self):
        return ArmObservables(self)

    @property
    def mjcf_model(self):
        return self._model

    @property
    def actuators(self):
        return self._actuators


class BoxObservables(composer.Observables, composer.FreePropObservableMixin):
    pass


class Box(composer.Entity):
    """A 5 cm cube."""

    def _build(self, name="box", half_size=0.05):
        self._model = mjcf.RootElement(model=name)
        self.geom = self._model.worldbody.add(
            "geom", name="geom", type="box", size=[half_size] * 3, mass=0.2
        )

    def _build_observables(self):
        return BoxObservables(self)

    @property
    def mjcf_model(self):
        return self._model


class ReachTask(composer.Task):
    """Reward: minus the distance from the arm's tip to the box. 10 physics steps per action."""

    def __init__(self, discount=1.0):
        self.arena = Floor()
        self.arm = Arm()
        self.box = Box()
        self.arena.attach(self.arm)
        self.arena.add_free_entity(self.box)
        self.discount = discount
        self.arm.observables.joint_positions.enabled = True
        self.arm.observables.tip_position.enabled = True
        self.box.observables.position.enabled = True
        self.set_timesteps(control_timestep=0.02, physics_timestep=0.002)

    @property
    def root_entity(self):
        return self.arena

    def initialize_episode(self, physics, random_state):
        position = [random_state.uniform(0.2, 0.5), random_state.uniform(-0.2, 0.2), 0.05]
        self.box.set_pose(physics, position=position, quaternion=[1, 0, 0, 0])
        physics.bind(self.arm.joints).qpos = random_state.uniform(-0.5, 0.5, size=2)

    def get_reward(self, physics):
        tip = physics.bind(self.arm.tip).xpos
        box = physics.bind(self.box.root_body).xpos
        return -float(np.linalg.norm(tip - box))

    def get_discount(self, physics):
        return self.discount


class Diverges(ReachTask):
    """Makes the box's mass NaN before the control step numbered `diverge_at` of an episode."""

    def __init__(self, diverge_at):
        super().__init__()
        self.diverge_at = diverge_at
        self.steps = 0

    def initialize_episode(self, physics, random_state):
        super().initialize_episode(physics, random_state)
        self.steps = 0

    def before_step(self, physics, action, random_state):
        super().before_step(physics, action, random_state)
        self.steps += 1
        if self.steps == self.diverge_at:
            physics.bind(self.box.root_body).mass = np.nan


def play_episodes(env, episodes: int, steps: int, seed: int = 7) -> list:
    """The first observation of each of `episodes` episodes of `env`, then (reward,
    observation) of each of its `steps` steps under seeded random actions (two controls,
    as `ReachTask`'s arm has)."""
    actions = np.random.RandomState(seed).uniform(-1, 1, size=(steps, 2))
    values = []
    for _ in range(episodes):
        values.append(env.reset().observation)
        for action in actions:
            timestep = env.step(action)
            values.append((timestep.reward, timestep.observation))
    return values


def assert_same_episodes(first: list, second: list) -> None:
    """Asserts that two `play_episodes` results are bit-identical: the same rewards, and the
    same observation names with arrays of the same shape, dtype and bytes."""
    assert len(first) == len(second)
    for mine, theirs in zip(first, second):
        if isinstance(mine, tuple):
            assert mine[0] == theirs[0]
            mine, theirs = mine[1], theirs[1]
        assert list(mine) == list(theirs)
        for name in mine:
            a, b = np.asarray(mine[name]), np.asarray(theirs[name])
            assert (a.shape, a.dtype, a.tobytes()) == (b.shape, b.dtype, b.tobytes()), name
