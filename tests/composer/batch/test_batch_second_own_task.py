"""A second own task, written from the docs alone (README, docs/own_task.md,
docs/batch_own_task.md, docs/concepts/batch.md), batched the way docs/batch_own_task.md
says: a door on a motorised hinge whose handle has to reach a target marker. The target
moves every episode by an `MJCFVariator` on a site's `pos`, the door starts at a random
angle by a physics write in `initialize_episode`; the `BatchTask` is only its reward. The
docs path stays true while this runs: 20 steps on Warp's CPU device, then the equivalence
check the page documents."""

import numpy as np
import pytest

import composer
import mjcf
from composer import batch, variation
from composer.observation import observable
from composer.variation import distributions

pytestmark = pytest.mark.warp
pytest.importorskip("warp", reason="needs MuJoCo Warp: pip install -e '.[warp]'")

TARGET_LOW, TARGET_HIGH = [-0.3, 0.2, 0.3], [0.3, 0.35, 0.3]
START_ANGLE = 0.5  # the door starts within +-0.5 rad of closed
NUM_ENVS = 4


class DoorArenaObservables(composer.Observables):
    @composer.observable
    def target_position(self):
        return observable.MJCFFeature("xpos", self._entity.target)


class DoorArena(composer.Arena):
    """A floor and the target marker the door's handle has to reach."""

    def _build(self, name="door_arena"):
        super()._build(name=name)
        worldbody = self.mjcf_model.worldbody
        worldbody.add("light", pos=[0, 0, 2], dir=[0, 0, -1])
        worldbody.add("geom", name="floor", type="plane", size=[1, 1, 0.05])
        self.target = worldbody.add(
            "site", name="target", type="sphere", size=[0.02], pos=[0.3, 0.3, 0.3]
        )

    def _build_observables(self):
        return DoorArenaObservables(self)


class DoorObservables(composer.Observables):
    @composer.observable
    def angle(self):
        return observable.MJCFFeature("qpos", [self._entity.hinge])

    @composer.observable
    def handle_position(self):
        return observable.MJCFFeature("xpos", self._entity.handle)


class Door(composer.Robot):
    """A 0.4 m wide leaf on a vertical hinge, driven by one motor; its handle at the edge."""

    def _build(self):
        self._model = mjcf.RootElement(model="door")
        leaf = self._model.worldbody.add("body", name="leaf", pos=[0, 0, 0.3])
        self.hinge = leaf.add(
            "joint", name="hinge", type="hinge", axis=[0, 0, 1], damping=0.5, range=[-2, 2]
        )
        leaf.add("geom", type="box", size=[0.2, 0.01, 0.25], pos=[0.2, 0, 0], mass=1)
        self.handle = leaf.add("site", name="handle", pos=[0.38, 0, 0], size=[0.01])
        self._actuators = [
            self._model.actuator.add(
                "motor", name="hinge", joint=self.hinge, ctrlrange=[-1, 1], gear=[2]
            )
        ]

    def _build_observables(self):
        return DoorObservables(self)

    @property
    def mjcf_model(self):
        return self._model

    @property
    def actuators(self):
        return self._actuators


class OpenDoor(composer.Task):
    """Bring the door's handle to the target; each step costs their distance."""

    def __init__(self, arena, door):
        self._arena, self.door = arena, door
        arena.attach(door)
        self._target_variator = variation.MJCFVariator()
        self._target_variator.bind_attributes(
            arena.target, pos=distributions.Uniform(TARGET_LOW, TARGET_HIGH)
        )
        arena.observables.target_position.enabled = True
        door.observables.angle.enabled = True
        door.observables.handle_position.enabled = True
        self.set_timesteps(control_timestep=0.04, physics_timestep=0.004)

    @property
    def root_entity(self):
        return self._arena

    def initialize_episode_mjcf(self, random_state):
        self._target_variator.apply_variations(random_state)

    def initialize_episode(self, physics, random_state):
        physics.bind(self.door.hinge).qpos = random_state.uniform(-START_ANGLE, START_ANGLE)

    def get_reward(self, physics):
        handle = physics.bind(self.door.handle).xpos
        target = physics.bind(self._arena.target).xpos
        return -float(np.linalg.norm(handle - target))


class BatchOpenDoor(batch.BatchTask):
    """OpenDoor's reward for every world; no discount or end of its own."""

    def after_compile(self, physics):
        self._handle = physics.bind(self.task.door.handle)
        self._target = physics.bind(self.task.root_entity.target)

    def get_reward(self, physics):
        offset = self._handle.xpos - self._target.xpos
        return -physics.xp.linalg.vector_norm(offset, axis=-1)


batch.register(OpenDoor, BatchOpenDoor)


def make_task():
    return OpenDoor(DoorArena(), Door())


def test_the_door_batches_as_written_and_its_worlds_draw_their_own_targets():
    env = batch.BatchEnvironment(
        make_task(),
        NUM_ENVS,
        device="warp-cpu",
        random_state=0,
        strip_singleton_obs_buffer_dim=True,
    )
    try:
        first = env.reset().observation
        targets, angles = first["target_position"], first["door/angle"][:, 0]
        assert targets.shape == (NUM_ENVS, 3)
        assert len({tuple(target) for target in targets}) == NUM_ENVS
        # float32 observations: within the range to float32's rounding.
        assert np.all(
            (targets >= np.subtract(TARGET_LOW, 1e-6)) & (targets <= np.add(TARGET_HIGH, 1e-6))
        )
        assert len(set(angles)) == NUM_ENVS and np.all(np.abs(angles) <= START_ANGLE)
        # The handle is 0.38 m from the hinge (at the origin, 0.3 m up), at the door's angle.
        handle = first["door/handle_position"]
        expected = 0.38 * np.stack([np.cos(angles), np.sin(angles)], axis=-1)
        np.testing.assert_allclose(handle[:, :2], expected, atol=1e-5)

        actions = np.random.RandomState(0).uniform(-1, 1, (20, NUM_ENVS, 1))
        for action in actions:
            timestep = env.step(action)
        assert timestep.reward.dtype == np.float32 and timestep.reward.shape == (NUM_ENVS,)
        observation = timestep.observation
        distance = np.linalg.norm(
            observation["door/handle_position"] - observation["target_position"], axis=-1
        )
        np.testing.assert_allclose(timestep.reward, -distance, atol=1e-6)
        np.testing.assert_array_equal(observation["target_position"], targets)
        assert np.all(np.abs(observation["door/angle"][:, 0] - angles) > 1e-3)
    finally:
        env.close()


def test_the_documented_equivalence_check_finds_the_batch_within_float32():
    from composer.batch import equivalence

    report = equivalence.compare(make_task, num_envs=2, control_steps=20, factors={"reward": 2.0})
    assert report.first is None, str(report)
    assert report.rounded_cpu_first is None
    assert "within the float32 bound" in str(report)
