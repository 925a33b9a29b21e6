"""composer.Initializer: `__call__(physics, random_state)` is the contract, as in dm_control."""

import numpy as np
import pytest

import composer
import mjcf


class _RaiseBall(composer.Initializer):
    """Implements only `__call__`, as dm_control's initializers do."""

    def __init__(self, ball_joint, height):
        self._joint = ball_joint
        self._height = height

    def __call__(self, physics, random_state):
        physics.bind(self._joint).qpos[2] = self._height + random_state.uniform(0.0, 0.01)


class _BallTask(composer.Task):
    def __init__(self):
        self._arena = composer.Arena()
        ball = self._arena.mjcf_model.worldbody.add("body", name="ball")
        self.joint = ball.add("freejoint", name="ball_joint")
        ball.add("geom", type="sphere", size=[0.05])
        self.initializer = _RaiseBall(self.joint, height=2.0)

    @property
    def root_entity(self):
        return self._arena

    def initialize_episode(self, physics, random_state):
        self.initializer(physics, random_state)

    def get_reward(self, physics):
        return 0.0


def test_initializer_defining_only_call_sets_the_state_at_every_reset():
    env = composer.Environment(_BallTask(), random_state=0)
    for _ in range(2):
        env.reset()
        height = env.physics.bind(env.task.joint).qpos[2]
        assert 2.0 <= height <= 2.01


def test_initialize_episode_is_the_same_call():
    task = _BallTask()
    physics = mjcf.Physics.from_mjcf_model(task.root_entity.mjcf_model)
    task.initializer.initialize_episode(physics, np.random.RandomState(0))
    assert 2.0 <= physics.bind(task.joint).qpos[2] <= 2.01


def test_initializer_without_call_cannot_be_instantiated():
    class OnlyInitializeEpisode(composer.Initializer):
        def initialize_episode(self, physics, random_state):
            pass

    with pytest.raises(TypeError, match="__call__"):
        OnlyInitializeEpisode()
