"""OutputBuffer: a vector step's outputs copied at once, and recycled only when unheld."""

import gc

import gymnasium
import numpy as np
import pytest
from gymnasium.vector.utils import create_empty_array

from composer.gym.output_buffer import OutputBuffer

_NESTED = gymnasium.spaces.Dict(
    {
        "position": gymnasium.spaces.Box(-1.0, 1.0, (2, 3), dtype=np.float32),
        "parts": gymnasium.spaces.Tuple(
            (gymnasium.spaces.Discrete(4), gymnasium.spaces.MultiBinary(5))
        ),
        "speed": gymnasium.spaces.Box(0.0, 1.0, (), dtype=np.float64),
    }
)
_FLAT = gymnasium.spaces.Dict(
    {
        "a": gymnasium.spaces.Box(-1.0, 1.0, (3,), dtype=np.float64),
        "b": gymnasium.spaces.Box(-1.0, 1.0, (1, 2), dtype=np.float32),
    }
)


def _leaves(batch):
    if isinstance(batch, dict):
        return [leaf for part in batch.values() for leaf in _leaves(part)]
    if isinstance(batch, tuple):
        return [leaf for part in batch for leaf in _leaves(part)]
    return [batch]


def _fill(buffer, value):
    """Writes `value` (cast) into every live array."""
    for array in [*_leaves(buffer.live.observations), *buffer.live[1:]]:
        array[...] = value


@pytest.mark.parametrize("space", [_NESTED, _FLAT], ids=["nested", "flat"])
def test_arrays_have_the_batched_spaces_shapes_and_dtypes_and_are_contiguous(space):
    buffer = OutputBuffer(space, 3)
    expected = create_empty_array(space, 3)
    for outputs in (buffer.live, buffer.copy()):
        assert type(outputs.observations) is type(expected)
        got, wanted = _leaves(outputs.observations), _leaves(expected)
        assert [(a.shape, a.dtype) for a in got] == [(a.shape, a.dtype) for a in wanted]
        assert all(a.flags.c_contiguous and a.flags.writeable for a in got)
        assert (outputs.rewards.shape, outputs.rewards.dtype) == ((3,), np.float64)
        assert (outputs.terminations.dtype, outputs.truncations.dtype) == (np.bool_, np.bool_)


def test_a_copy_holds_the_values_at_the_time_it_was_made():
    buffer = OutputBuffer(_NESTED, 2)
    _fill(buffer, 1)
    first = buffer.copy()
    _fill(buffer, 0)
    assert all(np.all(np.asarray(a) == 1) for a in _leaves(first.observations))
    assert first.rewards.tolist() == [1.0, 1.0]


@pytest.mark.parametrize(
    "hold",
    [
        lambda out: out.observations,  # the dict
        lambda out: out.observations["parts"][1],  # one leaf
        lambda out: out.observations["position"][0, 1],  # a view into a leaf
        lambda out: out.rewards[1:],  # a view of the rewards
        lambda out: out.terminations,
    ],
    ids=["dict", "leaf", "view-of-leaf", "view-of-rewards", "terminations"],
)
def test_what_a_caller_holds_is_never_written_again(hold):
    buffer = OutputBuffer(_NESTED, 2)
    _fill(buffer, 1)
    held = hold(buffer.copy())
    gc.collect()
    before = np.array(held if not isinstance(held, dict) else _leaves(held)[0]).tolist()
    for value in (0, 1, 0, 1, 0):
        _fill(buffer, value)
        buffer.copy()  # dropped at once: recycled, but never into what is held
    after = np.array(held if not isinstance(held, dict) else _leaves(held)[0]).tolist()
    assert after == before
    if isinstance(held, dict):
        assert all(np.all(np.asarray(a) == 1) for a in _leaves(held))


def test_a_copy_nobody_holds_is_recycled_with_the_new_values():
    buffer = OutputBuffer(_FLAT, 2)
    _fill(buffer, 1)
    rewards_id = id(buffer.copy().rewards)
    _fill(buffer, 2)
    again = buffer.copy()
    assert id(again.rewards) == rewards_id  # the same arrays, written again
    assert again.rewards.tolist() == [2.0, 2.0]
    assert again.observations["b"].tolist() == [[[2.0, 2.0]], [[2.0, 2.0]]]


def test_the_previous_steps_outputs_survive_the_step_that_replaces_them():
    # obs, ... = env.step(policy(obs)): the last outputs are held while the next are made.
    buffer = OutputBuffer(_FLAT, 1)
    outputs = None
    for step in range(6):
        _fill(buffer, step)
        previous, outputs = outputs, buffer.copy()
        if previous is not None:
            assert previous.rewards.tolist() == [step - 1.0]
            assert previous.observations["a"].tolist() == [[step - 1.0] * 3]
        del previous


def test_copy_observations_is_a_new_copy_each_time():
    buffer = OutputBuffer(_FLAT, 2)
    _fill(buffer, 3)
    first = buffer.copy_observations()
    _fill(buffer, 4)
    second = buffer.copy_observations()
    assert first["a"].tolist() == [[3.0] * 3] * 2
    assert second["a"].tolist() == [[4.0] * 3] * 2


def test_observations_that_are_not_arrays_of_numbers_are_copied_leaf_by_leaf():
    space = gymnasium.spaces.OneOf([gymnasium.spaces.Discrete(2), gymnasium.spaces.Box(0, 1, (2,))])
    buffer = OutputBuffer(space, 2)
    assert buffer.live.observations == create_empty_array(space, 2)
    buffer.live.rewards[...] = 5.0
    assert buffer.copy().rewards.tolist() == [5.0, 5.0]
