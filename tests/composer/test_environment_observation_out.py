"""composer.Environment.write_observations_to: observations written into the caller's arrays."""

import numpy as np
import pytest
from composer_scene import ReachTask

import composer


def _env(seed: int = 3, **kwargs) -> composer.Environment:
    return composer.Environment(ReachTask(), random_state=seed, **kwargs)


def _arrays_for(env: composer.Environment) -> dict[str, np.ndarray]:
    return {name: np.zeros(spec.shape, spec.dtype) for name, spec in env.observation_spec().items()}


def _snapshot(observation) -> dict[str, np.ndarray]:
    return {name: np.array(value) for name, value in observation.items()}


def test_reset_and_step_write_into_out_and_return_it_with_the_values_of_new_arrays():
    plain, writing = _env(), _env()
    out = _arrays_for(writing)
    arrays_before = {name: id(array) for name, array in out.items()}
    writing.write_observations_to(out)
    actions = np.random.RandomState(0).uniform(-1, 1, size=(30, 2))
    for episode in range(2):
        expected, got = plain.reset(), writing.reset()
        assert got.observation is out
        for name in expected.observation:
            np.testing.assert_array_equal(out[name], expected.observation[name])
        for action in actions[episode * 15 : (episode + 1) * 15]:
            expected, got = plain.step(action), writing.step(action)
            assert got.observation is out and got.reward == expected.reward
            for name in expected.observation:
                np.testing.assert_array_equal(out[name], expected.observation[name])
    assert {name: id(array) for name, array in out.items()} == arrays_before


def test_a_step_overwrites_what_the_last_one_wrote():
    env = _env()
    env.write_observations_to(_arrays_for(env))
    first = _snapshot(env.reset().observation)
    second = env.step(np.array([1.0, -1.0])).observation
    assert not np.array_equal(first["arm/joint_positions"], second["arm/joint_positions"])


def test_none_goes_back_to_new_arrays_at_every_call():
    env = _env()
    out = _arrays_for(env)
    env.write_observations_to(out)
    env.reset()
    env.write_observations_to(None)
    first = env.step(np.zeros(2)).observation
    second = env.step(np.zeros(2)).observation
    assert first is not out and second is not out
    assert first["arm/joint_positions"] is not second["arm/joint_positions"]


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda out: out.pop("box/position"), "expected a dict with the keys"),
        (lambda out: out.update(extra=np.zeros(3)), "expected a dict with the keys"),
        (
            lambda out: out.update({"arm/tip_position": np.zeros(4)}),
            # The observation keeps its buffer axis (strip_singleton_obs_buffer_dim=False).
            "'arm/tip_position': expected a writeable float64 array of shape (1, 3), got a "
            "float64 array of shape (4,)",
        ),
        (
            lambda out: out.update({"arm/tip_position": np.zeros((1, 3), np.float32)}),
            "got a float32 array of shape (1, 3)",
        ),
        (
            lambda out: out["arm/tip_position"].setflags(write=False),
            "got a read-only float64 array",
        ),
    ],
)
def test_arrays_that_do_not_match_the_observation_spec_are_refused_by_key(change, message):
    env = _env()
    out = _arrays_for(env)
    change(out)
    with pytest.raises(ValueError, match="write_observations_to: ") as error:
        env.write_observations_to(out)
    assert message in str(error.value)
    timestep = env.reset()
    assert timestep.observation is not out  # nothing was taken


def test_a_reset_that_changes_the_observation_spec_goes_back_to_new_arrays():
    env = _env()
    out = _arrays_for(env)
    env.write_observations_to(out)
    assert env.reset().observation is out
    env.task.arm.observables.joint_velocities.enabled = True
    observation = env.reset().observation
    assert observation is not out
    assert "arm/joint_velocities" in observation and "arm/joint_velocities" not in out
