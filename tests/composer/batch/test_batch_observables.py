"""Batched readers built from an observable's public `selection`: each world's value is the
bound field of that world, indexed as the selection says."""

import numpy as np
import pytest

from composer.batch import batch_reader
from composer.batch.gather import FieldGather, ObservationGather
from composer.batch.observables import selection_reader
from composer.observation import observable
from manipulation import batch as manipulation_batch

pytestmark = pytest.mark.warp

NUM_ENVS = 3


@pytest.fixture(scope="module")
def env():
    env = manipulation_batch.load("lift_brick_features", NUM_ENVS, seed=2)
    env.reset()
    env.step(np.zeros((NUM_ENVS, *env.action_spec().shape)))
    yield env
    env.close()


class _Height(observable.Observable):
    """A user's own observable type: the height of a site, described by a selection."""

    def __init__(self, site):
        self._site = site
        super().__init__(1, None, None, None, None)

    @property
    def selection(self) -> observable.MJCFSelection:
        return observable.MJCFSelection(self._site, "xpos", (2,))

    def _callable(self, physics):
        return self.selection.reader(physics)


@batch_reader.register
def _height(obs: _Height, physics):
    return selection_reader(obs.selection, physics)


def test_a_registered_twin_reads_each_worlds_height_of_the_site(env):
    pinch = env.task.task.hand.tool_center_point
    heights = np.asarray(batch_reader(_Height(pinch), env.physics)())
    assert heights.shape == (NUM_ENVS,)
    np.testing.assert_array_equal(heights, np.asarray(env.physics.bind(pinch).xpos)[:, 2])
    # The worlds start from different arm poses, so the pinch site is at different heights.
    assert len(set(heights.tolist())) == NUM_ENVS


def test_a_prop_velocity_reads_the_translational_half_of_each_worlds_cvel(env):
    prop = env.task.task.prop
    read = batch_reader(prop.observables.linear_velocity, env.physics)
    cvel = np.asarray(env.physics.bind(prop.root_body).cvel)
    np.testing.assert_array_equal(np.asarray(read()), cvel[:, 3:6])


def test_an_indexed_feature_reads_the_same_entries_in_every_world(env):
    joints = list(env.task.task.arm.joints)
    feature = observable.MJCFFeature("qpos", joints)[::-1][1:3]
    qpos = np.asarray(env.physics.bind(joints).qpos)
    np.testing.assert_array_equal(np.asarray(batch_reader(feature, env.physics)()), qpos[:, [4, 3]])


def test_kernel_gathered_observations_of_earlier_steps_stay_as_they_were(monkeypatch):
    pytest.importorskip("torch", reason="torch is optional: pip install torch==2.13.0")
    from composer.batch import gather

    # Task code in torch: the observations come from the Warp gather kernel, into blocks
    # cut from chunks; chunks of two reads make the run cross chunks.
    monkeypatch.setattr(gather.ObservationGather, "CHUNK_BYTES", 1)
    env = manipulation_batch.load("reach_site_features", 2, seed=1, array_type="torch")
    rng = np.random.RandomState(0)
    spec = env.action_spec()
    kept, copies = [], []
    for _ in range(5):
        action = rng.uniform(spec.minimum, spec.maximum, (2, *spec.shape)).astype(np.float32)
        observation = env.step(action).observation
        kept.append(observation)
        copies.append({key: value.clone() for key, value in observation.items()})
    env.close()
    for observation, copy in zip(kept, copies):
        for key, value in copy.items():
            np.testing.assert_array_equal(observation[key].numpy(), value.numpy(), err_msg=key)
    # The steps moved the arm: a reused block would have shown a later step's angles.
    assert not np.array_equal(
        kept[1]["jaco_arm/joints_pos"].numpy(), kept[4]["jaco_arm/joints_pos"].numpy()
    )


def _gathered(env, readers):
    gather = ObservationGather(env.physics, readers)
    if env.physics.arrays.library != "numpy":
        pytest.skip(f"the NumPy reads need the NumPy namespace, not {env.physics.arrays.library}")
    return {key: np.asarray(value, np.float64) for key, value in gather.read().items()}


def test_weighted_sums_of_entries_read_as_the_sums_of_each_worlds_values(env):
    physics = env.physics
    qpos = np.asarray(physics.field("data", "qpos").view, np.float64)
    weights = np.array([[1.0, -2.0, 0.5], [3.0, 0.25, -1.0]])
    sums = FieldGather(physics, physics.field("data", "qpos"), [[0, 1, 2], [3, 4, 2]], weights)
    # The same entry twice in one sum, and two sums sharing entries.
    repeated = FieldGather(
        physics, physics.field("data", "qpos"), [[1, 1], [0, 1]], [[0.5, 0.5], [2.0, -1.0]]
    )
    got = _gathered(env, {"sums": sums, "repeated": repeated})
    expected = np.stack([qpos[:, [0, 1, 2]] @ weights[0], qpos[:, [3, 4, 2]] @ weights[1]], axis=1)
    np.testing.assert_allclose(got["sums"], expected, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(
        got["repeated"], np.stack([qpos[:, 1], 2 * qpos[:, 0] - qpos[:, 1]], 1), atol=1e-6
    )


def test_sines_and_cosines_of_entries_in_any_order_read_each_worlds_angles(env):
    physics = env.physics
    qpos = np.asarray(physics.field("data", "qpos").view, np.float64)
    entries = [[5], [2], [5], [2], [7]]
    ops = ["sin", "cos", "cos", "identity", "sin"]
    got = _gathered(
        env,
        {"angles": FieldGather(physics, physics.field("data", "qpos"), entries, ops=ops)},
    )["angles"]
    expected = np.stack(
        [
            np.sin(qpos[:, 5]),
            np.cos(qpos[:, 2]),
            np.cos(qpos[:, 5]),
            qpos[:, 2],
            np.sin(qpos[:, 7]),
        ],
        axis=1,
    )
    assert len({tuple(row) for row in np.round(expected, 6)}) == NUM_ENVS  # worlds differ
    np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-6)
