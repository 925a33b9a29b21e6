"""The batched physics view: bind and named give (num_envs, ...) arrays; writes go to the
selected worlds only; shared model fields refuse per-world writes."""

import numpy as np
import pytest

import composer
from composer.batch import BatchEnvironment
from manipulation import batch as manipulation_batch
from manipulation.tasks import observation_settings
from manipulation.tasks.reach import Reach

pytestmark = pytest.mark.warp

NUM_ENVS = 3


@pytest.fixture(scope="module")
def env():
    env = manipulation_batch.load("reach_site_features", NUM_ENVS, seed=5, device="warp-cpu")
    env.reset()
    return env


def test_bind_site_reads_one_row_per_world(env):
    pinch = env.task.task.hand.tool_center_point
    assert env.physics.bind(pinch).xpos.shape == (NUM_ENVS, 3)
    assert env.physics.bind(pinch).xmat.shape == (NUM_ENVS, 9)


def test_bind_joints_item_assignment_writes_only_the_selected_worlds(env):
    joints = list(env.task.task.arm.joints)
    addresses = env.physics.host.model.ptr.jnt_qposadr[env.physics.host.bind(joints).element_id]
    before = env.physics.data.qpos.copy()
    env.physics.bind(joints).qpos[[0, 2]] = [[0.1] * 6, [0.2] * 6]
    after = env.physics.data.qpos
    np.testing.assert_allclose(after[0, addresses], 0.1, rtol=1e-6)
    np.testing.assert_allclose(after[2, addresses], 0.2, rtol=1e-6)
    np.testing.assert_array_equal(after[1], before[1])
    others = np.setdiff1d(np.arange(after.shape[1]), addresses)
    np.testing.assert_array_equal(after[:, others], before[:, others])


def test_named_data_reads_and_writes_by_compiled_name(env):
    named = env.physics.named.data.qpos
    # A hinge owns one qpos row, so each world's value is (1,), as in mjcf.Physics.named.
    named["jaco_arm/joint_1"] = [[0.5], [0.6], [0.7]]
    np.testing.assert_allclose(named["jaco_arm/joint_1"], [[0.5], [0.6], [0.7]], rtol=1e-6)
    with pytest.raises(KeyError, match="no joint named 'nope'"):
        named["nope"]


def test_shared_model_field_refuses_a_per_world_write(env):
    geom = env.task.task.arena.mjcf_model.find_all("geom")[0]
    friction = env.physics.bind(geom).friction
    assert friction.shape == (NUM_ENVS, 3)
    with pytest.raises(ValueError, match=r"'geom_friction' is shared.*batched_model_fields"):
        friction[0] = [0.1, 0.1, 0.1]


def test_batched_model_field_takes_a_value_per_world():
    env = manipulation_batch.load(
        "reach_site_features", 2, seed=1, batched_model_fields=("geom_friction",)
    )
    geom = env.task.task.arena.mjcf_model.find_all("geom")[0]
    env.physics.bind(geom).friction[1] = [0.3, 0.02, 0.001]
    np.testing.assert_allclose(env.physics.bind(geom).friction[1], [0.3, 0.02, 0.001], rtol=1e-6)
    assert not np.allclose(env.physics.bind(geom).friction[0], [0.3, 0.02, 0.001])


def test_unknown_batched_model_field_is_refused_by_name():
    with pytest.raises(ValueError, match=r"batched_model_fields: \['geom_nothing'\]"):
        manipulation_batch.load("reach_site_features", 2, batched_model_fields=("geom_nothing",))


def test_action_of_the_wrong_shape_is_refused_with_the_expected_shape(env):
    with pytest.raises(ValueError, match=r"action: expected shape \(3, 9\).*got \(9,\)"):
        env.step(np.zeros(9))


def test_nan_action_names_the_world(env):
    action = np.zeros((NUM_ENVS, 9))
    action[1, 4] = np.nan
    with pytest.raises(ValueError, match=r"NaN or infinity in the actions of worlds \[1\]"):
        env.step(action)


def test_finite_action_beyond_float32_names_the_world(env):
    qpos = env.physics.data.qpos.copy()
    action = np.zeros((NUM_ENVS, 9))
    action[2, 0] = -1e39  # finite in float64, infinite in the device's float32
    with pytest.raises(ValueError, match=r"beyond float32's range .* worlds \[2\]"):
        env.step(action)
    np.testing.assert_array_equal(env.physics.data.qpos, qpos)


def test_episode_steps_beyond_int32_are_refused_by_name(env):
    steps = np.zeros(NUM_ENVS, np.int64)
    steps[1] = 2**31  # would wrap to a negative int32 count
    with pytest.raises(ValueError, match=r"episode_steps: expected counts from 0 to 2147483646"):
        env.episode_steps = steps
    steps[1] = -1
    with pytest.raises(ValueError, match=r"episode_steps: .*got -1"):
        env.episode_steps = steps


def test_observations_have_the_cpu_shapes_behind_the_world_axis(env):
    cpu = composer.Environment(Reach(observation_settings.FEATURES), random_state=0)
    expected = cpu.reset().observation
    observation = env.step(np.zeros((NUM_ENVS, 9))).observation
    assert sorted(observation) == sorted(expected)
    for key, value in expected.items():
        assert observation[key].shape == (NUM_ENVS, *value.shape), key


class _SubstepReach(Reach):
    def after_substep(self, physics, random_state) -> None:
        physics.data.qfrc_applied[0] = 0.0


def test_substep_hooks_are_refused_because_no_python_runs_between_substeps():
    with pytest.raises(NotImplementedError, match=r"_SubstepReach.after_substep: a batch steps"):
        BatchEnvironment(_SubstepReach(observation_settings.FEATURES), 2)


class _PushingReach(Reach):
    def before_step(self, physics, action, random_state) -> None:
        super().before_step(physics, action, random_state)
        physics.data.qfrc_applied[0] = 1.0


def test_a_cpu_before_step_needs_a_batched_one():
    with pytest.raises(
        NotImplementedError, match=r"_PushingReach.before_step does more.*BatchReach"
    ):
        BatchEnvironment(_PushingReach(observation_settings.FEATURES), 2)


def test_an_observable_with_a_corruptor_is_refused_by_key():
    task = Reach(observation_settings.FEATURES)
    task.hand.observables.pinch_site_pos.corruptor = lambda value, random_state: value
    with pytest.raises(ValueError, match=r"'jaco_arm/jaco_hand/pinch_site_pos': option corruptor"):
        BatchEnvironment(task, 2)
