"""The lift reward rises linearly with the prop's height: 0 on the table, 1 at LIFT_HEIGHT."""

import pytest

import composer
from manipulation.tasks import registry, task_constants


@pytest.fixture(scope="module")
def lifted():
    """A lift task whose hand always counts as touching the brick, and a function putting the
    brick's underside at a given height above the table."""
    env = composer.Environment(registry.build_task("lift_brick_features"), random_state=0)
    env.reset()
    task, physics = env.task, env.physics
    task._hand_touches = lambda: True

    def reward_at(height, env=env):  # the environment owns the physics: keep it alive
        task.prop.set_pose(physics, position=[0.0, -0.15, height], quaternion=[1, 0, 0, 0])
        physics.forward()
        return task.get_reward(physics)

    return reward_at


@pytest.mark.parametrize("fraction", [0.25, 0.5, 0.75])
def test_lift_reward_is_the_fraction_of_the_lift_height_reached(lifted, fraction):
    assert lifted(fraction * task_constants.LIFT_HEIGHT) == pytest.approx(fraction)


@pytest.mark.parametrize("fraction", [1.0, 1.5, 3.0])
def test_lift_reward_is_one_at_and_above_the_lift_height(lifted, fraction):
    assert lifted(fraction * task_constants.LIFT_HEIGHT) == 1.0


def test_lift_reward_is_zero_on_the_table(lifted):
    assert lifted(0.0) == 0.0
