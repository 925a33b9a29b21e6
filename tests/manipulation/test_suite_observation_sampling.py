"""Suite observations sampled directly (gathered or written in place) equal the observables'
own values, read through their observation callables at the same state."""

import numpy as np
import pytest

import manipulation


@pytest.mark.parametrize("name", ["reach_site_features", "stack_2_bricks_moveable_base_features"])
def test_step_observations_equal_the_observables_read_directly(name):
    env = manipulation.load(name, seed=3)
    env.reset()
    spec = env.action_spec()
    random_state = np.random.RandomState(4)
    for _ in range(5):
        timestep = env.step(random_state.uniform(spec.minimum, spec.maximum))
    observables = env.task.observables
    for key, observed in timestep.observation.items():
        expected = np.asarray(observables[key](env.physics))
        np.testing.assert_array_equal(observed[0], expected, err_msg=key)


def test_arm_joints_torque_and_prop_pose_are_read_where_they_live():
    env = manipulation.load("lift_brick_features", seed=0)
    observables = env.task.observables
    for key in ["jaco_arm/joints_torque", "duplo2x4/position", "duplo2x4/angular_velocity"]:
        assert observables[key].live_source(env.physics) is not None, key


def test_arm_joints_pos_is_written_in_place_like_its_callable_computes_it():
    env = manipulation.load("reach_site_features", seed=0)
    env.reset()
    joints_pos = env.task.observables["jaco_arm/joints_pos"]
    out = np.empty((6, 2))
    write = joints_pos.observation_writer(env.physics, out)
    write()
    np.testing.assert_array_equal(out, joints_pos(env.physics))
