"""Episodes start from random but valid states, reproducibly for a given seed."""

import numpy as np
import pytest

import manipulation

_PINCH = "jaco_arm/jaco_hand/pinch_site_pos"


def _first_observations(name, seed, episodes):
    env = manipulation.load(name, seed=seed)
    return [env.reset().observation for _ in range(episodes)]


def test_pinch_site_starts_pointing_down_inside_the_workspace():
    for observation in _first_observations("reach_site_features", seed=3, episodes=10):
        pinch = observation[_PINCH][0]
        assert np.all(pinch >= [-0.1, -0.1, 0.2] - np.array(1e-3))
        assert np.all(pinch <= [0.1, 0.1, 0.4] + np.array(1e-3))
        # The pinch site's z axis (third column of its rotation matrix) points down.
        rmat = observation["jaco_arm/jaco_hand/pinch_site_rmat"][0].reshape(3, 3)
        assert rmat[2, 2] == pytest.approx(-1.0, abs=1e-3)


def test_initial_pose_and_target_vary_between_episodes():
    observations = _first_observations("reach_site_features", seed=0, episodes=5)
    pinches = np.array([o[_PINCH][0] for o in observations])
    targets = np.array([o["target_position"][0] for o in observations])
    assert np.ptp(pinches, axis=0).min() > 0.01
    assert np.ptp(targets, axis=0).min() > 0.01


def test_bricks_start_on_the_table_inside_the_prop_area_without_overlapping():
    for observation in _first_observations("stack_3_bricks_features", seed=1, episodes=5):
        positions = np.array(
            [
                observation[f"{name}/position"][0]
                for name in ("duplo2x4", "duplo2x4_2", "duplo2x4_4")
            ]
        )
        assert np.all(np.abs(positions[:, :2]) <= 0.1 + 1e-9)
        np.testing.assert_allclose(positions[:, 2], 0.0, atol=1e-3)
        distances = np.linalg.norm(positions[:, None, :2] - positions[None, :, :2], axis=-1)
        # Two bricks closer than their width (3.18 cm) would overlap.
        assert distances[np.triu_indices(3, 1)].min() > 0.0318


@pytest.mark.parametrize("name", ["reach_site_features", "place_brick_features"])
def test_same_seed_gives_the_same_episodes(name):
    first = _first_observations(name, seed=7, episodes=2)
    second = _first_observations(name, seed=7, episodes=2)
    for a, b in zip(first, second):
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])


def test_different_seeds_give_different_episodes():
    first = _first_observations("lift_brick_features", seed=1, episodes=1)[0]
    second = _first_observations("lift_brick_features", seed=2, episodes=1)[0]
    assert not np.array_equal(first["duplo2x4/position"], second["duplo2x4/position"])
    assert not np.array_equal(first[_PINCH], second[_PINCH])


def test_pedestal_starts_inside_its_bounds_clear_of_the_brick():
    for observation in _first_observations("place_cradle_features", seed=2, episodes=5):
        top = observation["pedestal/position"][0]
        assert np.all(top >= [-0.1, -0.1, 0.05] - np.array(1e-9))
        assert np.all(top <= [0.1, 0.1, 0.15] + np.array(1e-9))
        brick = observation["duplo2x4/position"][0]
        # The column's radius (7 cm) plus the brick's half width keep them apart.
        assert np.linalg.norm(brick[:2] - top[:2]) > 0.07 + 0.0159
