"""The tasks' rewards respond to the states they describe, set up kinematically."""

import numpy as np
import pytest

import composer
from manipulation.props import Duplo2x4
from manipulation.tasks import registry


def _env(name, seed=0):
    env = composer.Environment(registry.build_task(name), time_limit=10.0, random_state=seed)
    env.reset()
    return env


def _seat(physics, upper, lower, height=Duplo2x4.HEIGHT):
    """Poses `upper` on its seat `height` above `lower` (same orientation)."""
    position = physics.bind(lower.root_body).xpos
    xmat = physics.bind(lower.root_body).xmat.reshape(3, 3)
    quaternion = physics.bind(lower.root_body).xquat
    upper.set_pose(physics, position=position + height * xmat[:, 2], quaternion=quaternion)
    physics.forward()


def test_reach_reward_is_one_at_the_target_and_near_zero_far_away():
    env = _env("reach_site_features")
    physics, task = env.physics, env.task
    pinch = physics.bind(task.hand.tool_center_point).xpos.copy()
    physics.bind(task.target).pos = pinch
    physics.forward()
    assert task.get_reward(physics) == 1.0
    physics.bind(task.target).pos = pinch + [0.0, 0.0, -0.3]
    physics.forward()
    assert task.get_reward(physics) < 0.01


def test_reach_duplo_reward_is_one_with_the_pinch_site_at_the_brick():
    env = _env("reach_duplo_features")
    physics, task = env.physics, env.task
    pinch = physics.bind(task.hand.tool_center_point).xpos.copy()
    assert task.get_reward(physics) < 0.5
    task.prop.set_pose(physics, position=pinch - [0.0, 0.0, Duplo2x4.HEIGHT / 2])
    physics.forward()
    assert task.get_reward(physics) == 1.0


def _brick_in_grip(physics, task):
    """Puts the brick between the finger pads, its width along the grip axis, and closes the
    fingers onto it."""
    pinch = physics.bind(task.hand.tool_center_point)
    grip_axis = pinch.xmat.reshape(3, 3)[:, 1]
    yaw = np.arctan2(grip_axis[1], grip_axis[0])
    quaternion = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    position = pinch.xpos - [0.0, 0.0, Duplo2x4.HEIGHT / 2]
    task.prop.set_pose(physics, position=position, quaternion=quaternion)
    physics.bind(task.hand.joints).qpos = 0.6
    physics.forward()


def test_lift_reward_is_one_for_a_brick_held_high_above_the_table():
    env = _env("lift_brick_features")
    _brick_in_grip(env.physics, env.task)
    assert env.task.get_reward(env.physics) == 1.0


def test_lift_reward_is_zero_for_a_brick_high_up_but_not_held():
    env = _env("lift_brick_features")
    physics, task = env.physics, env.task
    task.prop.set_pose(physics, position=[0.0, -0.15, 0.2])
    physics.forward()
    assert task.get_reward(physics) == 0.0


def test_lift_reward_is_zero_for_the_brick_on_the_table():
    env = _env("lift_brick_features")
    assert env.task.get_reward(env.physics) == 0.0


@pytest.mark.parametrize("name", ["place_brick_features", "place_cradle_features"])
def test_place_reward_is_one_for_the_brick_released_on_its_seat(name):
    env = _env(name)
    physics, task = env.physics, env.task
    assert task.get_reward(physics) < 0.5
    height = getattr(task.target, "SEAT_HEIGHT", Duplo2x4.HEIGHT)
    _seat(physics, task.prop, task.target, height)
    assert task.get_reward(physics) == 1.0


def test_stack_reward_counts_each_seated_pair_of_the_tower():
    env = _env("stack_3_bricks_features")
    physics, task = env.physics, env.task
    base, middle, top = task.bricks
    _seat(physics, middle, base)
    half = task.get_reward(physics)
    _seat(physics, top, middle)
    assert 0.5 <= half < 0.75
    assert task.get_reward(physics) == 1.0


def test_stack_reward_is_halved_while_the_hand_holds_the_seated_brick():
    env = _env("stack_2_bricks_features")
    physics, task = env.physics, env.task
    base, brick = task.bricks
    _seat(physics, brick, base)
    assert task.get_reward(physics) == 1.0
    # Move the base so that the seated brick's centre is at the pinch site, its width along
    # the grip axis, then close the fingers onto it.
    pinch = physics.bind(task.hand.tool_center_point)
    grip_axis = pinch.xmat.reshape(3, 3)[:, 1]
    yaw = np.arctan2(grip_axis[1], grip_axis[0])
    base.set_pose(
        physics,
        position=pinch.xpos - [0.0, 0.0, 1.5 * Duplo2x4.HEIGHT],
        quaternion=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)],
    )
    physics.forward()
    _seat(physics, brick, base)
    physics.bind(task.hand.joints).qpos = 0.6
    physics.forward()
    assert task.get_reward(physics) == 0.5


@pytest.mark.parametrize(
    "name", ["stack_3_bricks_random_order_features", "stack_2_of_3_bricks_random_order_features"]
)
def test_random_order_stacking_observes_and_rewards_the_drawn_order(name):
    env = _env(name)
    physics, task = env.physics, env.task
    order = env.reset().observation["desired_order"][0].astype(int)
    np.testing.assert_array_equal(order, task.desired_order)
    assert len(set(order)) == len(order)
    tower = [task.bricks[i] for i in order]
    for lower, upper in zip(tower[:-1], tower[1:]):
        _seat(physics, upper, lower)
    assert task.get_reward(physics) == 1.0


def test_random_order_changes_between_episodes():
    env = _env("stack_3_bricks_random_order_features")
    orders = {tuple(env.reset().observation["desired_order"][0]) for _ in range(10)}
    assert len(orders) > 1


@pytest.mark.parametrize(
    "name",
    ["reassemble_3_bricks_fixed_order_features", "reassemble_5_bricks_random_order_features"],
)
def test_reassemble_starts_as_a_tower_and_rewards_the_rebuilt_order(name):
    env = _env(name)
    physics, task = env.physics, env.task
    heights = sorted(physics.bind(brick.root_body).xpos[2] for brick in task.bricks)
    np.testing.assert_allclose(np.diff(heights), Duplo2x4.HEIGHT, atol=1e-3)
    assert task.get_reward(physics) < 1.0
    tower = [task.bricks[i] for i in task.desired_order]
    for lower, upper in zip(tower[:-1], tower[1:]):
        _seat(physics, upper, lower)
    assert task.get_reward(physics) == 1.0


def test_reassemble_fixed_order_asks_for_the_tower_upside_down():
    env = _env("reassemble_3_bricks_fixed_order_features")
    physics, task = env.physics, env.task
    bottom_up = sorted(range(3), key=lambda i: physics.bind(task.bricks[i].root_body).xpos[2])
    np.testing.assert_array_equal(task.desired_order, bottom_up[::-1])
    assert task.get_reward(physics) < 0.01


def test_starting_tower_stands_under_physics():
    env = _env("reassemble_5_bricks_random_order_features")
    physics, task = env.physics, env.task
    before = np.array([physics.bind(b.root_body).xpos.copy() for b in task.bricks])
    for _ in range(25):
        env.step(np.zeros(9))
    after = np.array([physics.bind(b.root_body).xpos for b in task.bricks])
    # The contacts between the bricks give a little (a fraction of a millimetre each).
    np.testing.assert_allclose(after[:, :2], before[:, :2], atol=1e-3)
    np.testing.assert_allclose(after[:, 2], before[:, 2], atol=3e-3)
