"""A user's own CPU task, batched unchanged: push_puck's goal site, moved every episode by an
`MJCFVariator` on its `pos`, is drawn per world, as a CPU environment seeded alike draws it.
"""

import numpy as np
import pytest
from push_puck import HALF_SIDE, BatchPushPuck, PushPuck

import composer
from composer import batch, variation
from composer.variation import distributions, rotations

pytestmark = pytest.mark.warp
pytest.importorskip("warp", reason="needs MuJoCo Warp: pip install -e '.[warp]'")

SEEDS = (21, 22, 23, 24)
RESETS = 2
CONTROL_STEPS = 4


@pytest.fixture
def batch_env():
    """A fresh batch: its worlds' generators as seeded, like fresh CPU environments."""
    env = batch.BatchEnvironment(PushPuck(), len(SEEDS), random_states=SEEDS, device="warp-cpu")
    yield env
    env.close()


def test_the_batched_task_is_the_users_batch_task_with_no_rewrite(batch_env):
    assert type(batch_env.task) is BatchPushPuck
    assert "site_pos" in batch_env.physics.batched_model_fields


def test_each_world_draws_its_cpu_environments_goal_at_every_reset(batch_env):
    cpu_envs = [composer.Environment(PushPuck(), random_state=seed) for seed in SEEDS]
    goals = []
    for _ in range(RESETS):
        observation = batch_env.reset().observation
        for world, env in enumerate(cpu_envs):
            expected = env.reset().observation
            for key in ("goal_position", "puck_position", "pusher_position"):
                # The device holds float32: the CPU's values rounded, bit for bit.
                np.testing.assert_array_equal(
                    observation[key][world], np.float32(expected[key]), err_msg=f"{world} {key}"
                )
        goals.append(observation["goal_position"][:, 0, :2].copy())
    goals = np.array(goals)  # (resets, worlds, 2)
    assert len(np.unique(goals[..., 0])) == goals[..., 0].size  # every world its own goal
    assert np.all(np.abs(goals) <= HALF_SIDE)


def test_worlds_step_and_reward_as_their_cpu_environments(batch_env):
    cpu_envs = [composer.Environment(PushPuck(), random_state=seed) for seed in SEEDS]
    batch_env.reset()
    for env in cpu_envs:
        env.reset()
    actions = np.random.default_rng(3).uniform(-1, 1, (CONTROL_STEPS, len(SEEDS), 2))
    for action in actions:
        step = batch_env.step(action)
        for world, env in enumerate(cpu_envs):
            expected = env.step(action[world])
            # float32 state over a few steps, before any impact: well within a millimetre.
            np.testing.assert_allclose(
                step.observation["pusher_position"][world],
                expected.observation["pusher_position"],
                atol=1e-4,
            )
            assert abs(float(step.reward[world]) - expected.reward) < 1e-3


class _WalledPushPuck(PushPuck):
    """push_puck with a wall, a body welded to the world, placed and turned every episode by
    an `MJCFVariator` on the body's `pos` and `quat`."""

    def __init__(self):
        super().__init__()
        self.wall = self.root_entity.mjcf_model.worldbody.add("body", name="wall", pos=[0.5, 0, 0])
        self.wall.add("geom", name="wall", type="box", size=[0.02, 0.3, 0.05], pos=[0, 0, 0.05])
        self._wall_variator = variation.MJCFVariator()
        self._wall_variator.bind_attributes(
            self.wall,
            pos=distributions.Uniform([0.4, -0.1, 0], [0.6, 0.1, 0]),
            quat=rotations.UniformQuaternion(),
        )

    def initialize_episode_mjcf(self, random_state) -> None:
        super().initialize_episode_mjcf(random_state)
        self._wall_variator.apply_variations(random_state)


def test_a_welded_body_moved_by_an_mjcf_variator_is_placed_per_world_as_on_the_cpu():
    env = batch.BatchEnvironment(
        _WalledPushPuck(), len(SEEDS), random_states=SEEDS, device="warp-cpu"
    )
    cpu_envs = [composer.Environment(_WalledPushPuck(), random_state=seed) for seed in SEEDS]
    assert {"body_pos", "body_quat"} <= set(env.physics.batched_model_fields)
    for _ in range(RESETS):
        env.reset()
        wall = env.physics.bind(env.task.task.wall.find("geom", "wall"))
        xpos, xmat = np.array(wall.xpos), np.array(wall.xmat)
        for world, cpu in enumerate(cpu_envs):
            cpu.reset()
            expected = cpu.physics.bind(cpu.task.wall.find("geom", "wall"))
            # float32 on the device: the CPU's pose to rounding.
            np.testing.assert_allclose(xpos[world], expected.xpos, atol=1e-6, err_msg=world)
            np.testing.assert_allclose(xmat[world], expected.xmat, atol=1e-6, err_msg=world)
        assert len(np.unique(xpos[:, 0])) == len(SEEDS)
    env.close()
