"""Tests for composer.observation.updater.Updater, driven by a stand-in physics clock."""

import collections
import contextlib
import functools
import itertools
import logging

import numpy as np
import pytest
from dm_env import specs

from composer.observation import observable, updater


class _Clock:
    """Stand-in physics: the number of physics steps taken so far."""

    def __init__(self):
        self.time = 0

    def suppress_physics_errors(self):
        return contextlib.nullcontext()


def _value_at(time):
    return np.array([time, -2.0 * time])


def _enabled(obs):
    obs.enabled = True
    return obs


def _vector(**options):
    return _enabled(observable.Generic(lambda physics: _value_at(physics.time), **options))


def _scalar(**options):
    return _enabled(observable.Generic(lambda physics: float(physics.time), **options))


def _run(observables, steps_per_control, control_steps, chunked=False, seed=0, **kwargs):
    """Runs an updater; returns the observations after reset and each control step."""
    clock = _Clock()
    obs_updater = updater.Updater(observables, steps_per_control, **kwargs)
    obs_updater.reset(clock, np.random.RandomState(seed))
    observations = [obs_updater.get_observation()]
    for _ in range(control_steps):
        obs_updater.prepare_for_next_control_step()
        if chunked:
            done = 0
            for step in obs_updater.sample_steps + (steps_per_control,):
                if step > done:
                    clock.time += step - done
                    obs_updater.update(num_steps=step - done)
                    done = step
        else:
            for _ in range(steps_per_control):
                clock.time += 1
                obs_updater.update()
        observations.append(obs_updater.get_observation())
    return observations


class _RecordedDraws:
    """A random option (interval or delay) that remembers every value it drew, in order."""

    def __init__(self, low, high):
        self._low, self._high = low, high
        self.values = []

    def __call__(self, random_state):
        value = int(random_state.randint(self._low, self._high + 1))
        self.values.append(value)
        return value


def _reference(read_time, interval_of, delay_of, buffer_size, pad_initial, transform, aggregator):
    """What an observable shows at `read_time`: a from-scratch model of the semantics.

    Sample k is taken at the sum of the first k intervals and arrives `delay_of(k)` later;
    the observation holds the last `buffer_size` arrived samples in arrival order.
    """
    samples, timestamp, k = [], 0, 0
    while timestamp <= read_time:
        samples.append((timestamp + delay_of(k), timestamp, transform(_value_at(timestamp))))
        timestamp += interval_of(k)
        k += 1
    arrived = sorted((s for s in samples if s[0] <= read_time), key=lambda s: s[:2])
    values = [value for _, _, value in arrived][-buffer_size:]
    padding = samples[0][2] if pad_initial else np.zeros(2)
    stacked = np.array([padding] * (buffer_size - len(values)) + values)
    return stacked if aggregator is None else aggregator(stacked)


def _option_mix():
    """(name, options, interval_of, delay_of) covering the scheduling options."""
    interval_draws, delay_draws = _RecordedDraws(1, 4), _RecordedDraws(0, 6)
    both_interval, both_delay = _RecordedDraws(1, 3), _RecordedDraws(0, 8)
    single_draws = _RecordedDraws(1, 7)
    mix = [
        ("delayed_single", dict(delay=3), 1, 3),
        ("random_interval_single", dict(update_interval=single_draws), single_draws, 0),
        ("default", {}, 1, 0),
        ("buffer4", dict(buffer_size=4), 1, 0),
        ("every3", dict(update_interval=3, buffer_size=2), 3, 0),
        ("every7", dict(update_interval=7), 7, 0),
        ("delay2", dict(delay=2, buffer_size=3), 1, 2),
        ("long_delay", dict(update_interval=3, delay=7, buffer_size=2), 3, 7),
        ("mean", dict(buffer_size=5, delay=1, aggregator="mean"), 1, 1),
        ("reversed_sum", dict(buffer_size=3, aggregator=lambda x: x[::-1].cumsum(0)), 1, 0),
        ("corrupted", dict(corruptor=lambda v, random_state: 10 * v + 1, buffer_size=2), 1, 0),
        ("random_interval", dict(update_interval=interval_draws, buffer_size=2), interval_draws, 0),
        ("random_delay", dict(update_interval=2, delay=delay_draws, buffer_size=3), 2, delay_draws),
        (
            "random_both",
            dict(update_interval=both_interval, delay=both_delay, aggregator="max", buffer_size=4),
            both_interval,
            both_delay,
        ),
    ]
    return mix


def _as_lookup(option):
    if isinstance(option, _RecordedDraws):
        return lambda k: option.values[k]
    return lambda k: option


@pytest.mark.parametrize("chunked", [False, True], ids=["every_substep", "sample_steps"])
@pytest.mark.parametrize("pad_initial", [False, True], ids=["zero_pad", "initial_pad"])
@pytest.mark.parametrize("steps_per_control", [1, 5])
def test_observations_match_reference_model(chunked, pad_initial, steps_per_control):
    mix = _option_mix()
    observables = collections.OrderedDict((name, _vector(**options)) for name, options, _, _ in mix)
    observations = _run(
        observables, steps_per_control, 12, chunked=chunked, pad_with_initial_value=pad_initial
    )
    for name, options, interval, delay in mix:
        corruptor = options.get("corruptor")
        transform = (lambda v: 10 * v + 1) if corruptor else (lambda v: v)
        aggregator = observables[name].aggregator
        for step, observation in enumerate(observations):
            expected = _reference(
                step * steps_per_control,
                _as_lookup(interval),
                _as_lookup(delay),
                options.get("buffer_size", 1),
                pad_initial,
                transform,
                aggregator,
            )
            np.testing.assert_array_equal(observation[name], expected, err_msg=f"{name} {step}")


def test_sample_steps_observations_equal_every_substep_observations():
    mix = _option_mix()
    naive = _run({n: _vector(**o) for n, o, _, _ in mix}, 20, 10, seed=3)
    mix = _option_mix()
    chunked = _run({n: _vector(**o) for n, o, _, _ in mix}, 20, 10, chunked=True, seed=3)
    for naive_obs, chunked_obs in zip(naive, chunked):
        for name in naive_obs:
            np.testing.assert_array_equal(naive_obs[name], chunked_obs[name])


def _sample_steps(observables, steps_per_control, control_steps=1):
    obs_updater = updater.Updater(observables, steps_per_control)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    found = []
    for _ in range(control_steps):
        obs_updater.prepare_for_next_control_step()
        found.append(obs_updater.sample_steps)
        done = 0
        for step in obs_updater.sample_steps + (steps_per_control,):
            if step > done:
                obs_updater.update(num_steps=step - done)
                done = step
    return found


def test_default_options_sample_only_after_the_last_substep():
    assert _sample_steps({"a": _vector(), "b": _scalar()}, 20) == [(20,)]


def test_buffer_of_three_samples_the_last_three_substeps():
    assert _sample_steps({"a": _vector(buffer_size=3)}, 20) == [(18, 19, 20)]


def test_update_interval_three_samples_the_visible_multiples_of_three():
    assert _sample_steps({"a": _vector(update_interval=3)}, 5, 3) == [(3,), (4,), (5,)]


def test_delay_moves_sampling_earlier_by_the_delay():
    assert _sample_steps({"a": _vector(delay=2)}, 20) == [(18,)]


def test_update_skipping_a_sample_step_raises():
    obs_updater = updater.Updater({"a": _vector(buffer_size=2)}, 10)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    obs_updater.prepare_for_next_control_step()
    with pytest.raises(RuntimeError, match="skipped sub-step 9"):
        obs_updater.update(num_steps=10)


def test_finish_control_step_samples_what_is_still_due_from_the_current_state():
    # A control step of 10 sub-steps cut short after 4: the buffer of 3 is due at 8, 9 and
    # 10, and all three samples read the state the physics was left in (time 4). The next
    # control step then starts on schedule, 10 sub-steps in.
    clock = _Clock()
    obs_updater = updater.Updater({"t": _scalar(buffer_size=3)}, 10)
    obs_updater.reset(clock, np.random.RandomState(0))
    obs_updater.prepare_for_next_control_step()
    clock.time = 4
    obs_updater.finish_control_step()
    assert list(obs_updater.get_observation()["t"]) == [4, 4, 4]
    obs_updater.prepare_for_next_control_step()
    assert obs_updater.sample_steps == (8, 9, 10)


def test_finish_control_step_with_nothing_due_still_counts_the_whole_step():
    clock = _Clock()
    obs_updater = updater.Updater({"t": _scalar(update_interval=3)}, 2)
    obs_updater.reset(clock, np.random.RandomState(0))
    obs_updater.prepare_for_next_control_step()
    assert obs_updater.sample_steps == ()
    clock.time = 1
    obs_updater.finish_control_step()
    assert list(obs_updater.get_observation()["t"]) == [0]
    obs_updater.prepare_for_next_control_step()
    # Sub-step 3 of the episode, the first of the coming control step, is due.
    assert obs_updater.sample_steps == (1,)


def test_finish_control_step_counts_from_where_the_step_was_cut():
    # Control steps of 2 sub-steps, sampled every 5th sub-step. The second control step
    # (sub-steps 3-4) is cut after sub-step 3; finishing it brings the count to 4, so the
    # third control step (sub-steps 5-6) samples at its first sub-step.
    clock = _Clock()
    obs_updater = updater.Updater({"t": _scalar(update_interval=5)}, 2)
    obs_updater.reset(clock, np.random.RandomState(0))
    obs_updater.prepare_for_next_control_step()
    obs_updater.update(num_steps=2)
    obs_updater.prepare_for_next_control_step()
    obs_updater.update()
    obs_updater.finish_control_step()
    obs_updater.prepare_for_next_control_step()
    assert obs_updater.sample_steps == (1,)


def test_update_interval_three_observes_every_third_step():
    observations = _run({"t": _scalar(update_interval=3, buffer_size=3)}, 2, 4)
    assert [list(o["t"]) for o in observations] == [
        [0, 0, 0],
        [0, 0, 0],
        [0, 0, 3],
        [0, 3, 6],
        [0, 3, 6],
    ]


def test_delay_pads_with_zeros_by_default():
    observations = _run({"t": _scalar(delay=3, buffer_size=2)}, 2, 3)
    assert [list(o["t"]) for o in observations] == [[0, 0], [0, 0], [0, 1], [2, 3]]


def test_delay_pads_with_the_first_value_when_requested():
    clock_start = 5.0
    obs = _enabled(observable.Generic(lambda p: p.time + clock_start, delay=3, buffer_size=2))
    observations = _run({"t": obs}, 2, 2, pad_with_initial_value=True)
    assert [list(o["t"]) for o in observations] == [[5, 5], [5, 5], [5, 6]]


@pytest.mark.parametrize(
    "name, expected",
    [("min", 1.0), ("max", 4.0), ("mean", 7.0 / 3.0), ("median", 2.0), ("sum", 7.0)],
)
def test_named_aggregator_reduces_the_buffer_axis(name, expected):
    values = [1.0, 4.0, 2.0]
    obs = _enabled(observable.Generic(lambda p: values[p.time], buffer_size=3, aggregator=name))
    observations = _run({"x": obs}, 2, 1)
    assert observations[-1]["x"] == pytest.approx(expected)


def test_callable_aggregator_receives_the_buffer():
    seen = []

    def last_minus_first(buffer):
        seen.append(buffer.shape)
        return buffer[-1] - buffer[0]

    observations = _run({"x": _vector(buffer_size=4, aggregator=last_minus_first)}, 3, 1)
    assert seen[-1] == (4, 2)
    np.testing.assert_array_equal(observations[-1]["x"], _value_at(3) - _value_at(0))


def test_corruptor_gets_the_reset_random_state_for_every_sample():
    random_state = np.random.RandomState(0)
    seen = []

    def corruptor(value, random_state):
        seen.append(random_state)
        return value + 1000.0

    obs = _scalar(corruptor=corruptor)
    obs_updater = updater.Updater({"x": obs}, 1)
    obs_updater.reset(_Clock(), random_state)
    obs_updater.prepare_for_next_control_step()
    obs_updater.update()
    assert obs_updater.get_observation()["x"][0] == 1000.0
    assert seen and all(state is random_state for state in seen)


def test_noise_corruptor_is_reproducible_with_a_seed():
    def noisy():
        return _scalar(corruptor=lambda v, random_state: v + random_state.normal(), buffer_size=3)

    first = _run({"x": noisy()}, 2, 3, seed=7)
    second = _run({"x": noisy()}, 2, 3, seed=7)
    other_seed = _run({"x": noisy()}, 2, 3, seed=8)
    np.testing.assert_array_equal(first[-1]["x"], second[-1]["x"])
    assert not np.array_equal(first[-1]["x"], other_seed[-1]["x"])
    assert not np.array_equal(first[-1]["x"], [2.0, 4.0, 6.0])


def test_stochastic_interval_reproducible_with_a_seed_and_varies_across_seeds():
    def timings(seed):
        draw = _RecordedDraws(1, 6)
        _run({"x": _scalar(update_interval=draw)}, 5, 6, seed=seed)
        return draw.values

    assert timings(1) == timings(1)
    assert timings(1) != timings(2)


def test_option_callable_without_random_state_is_called_without_arguments():
    observations = _run({"t": _scalar(update_interval=lambda: 2, buffer_size=2)}, 3, 2)
    assert [list(o["t"]) for o in observations] == [[0, 0], [0, 2], [4, 6]]


def _interval_two_given_a_random_state(**kwargs):
    return 2 if isinstance(kwargs.get("random_state"), np.random.RandomState) else 99


@pytest.mark.parametrize(
    "interval",
    [
        lambda scale=2: scale,
        _interval_two_given_a_random_state,
        functools.partial(next, itertools.repeat(2)),
    ],
    ids=["other_parameter", "keyword_arguments", "builtin_without_signature"],
)
def test_option_callable_gets_the_random_state_exactly_when_it_can_take_it(interval):
    # A parameter named random_state or **kwargs gets it; anything else, and a builtin
    # whose signature cannot be read, is called without arguments.
    observations = _run({"t": _scalar(update_interval=interval, buffer_size=2)}, 3, 2)
    assert [list(o["t"]) for o in observations] == [[0, 0], [0, 2], [4, 6]]


def test_random_options_are_drawn_two_control_steps_ahead():
    # Which draw of a shared random state goes to which observable depends on how far
    # ahead the schedule is drawn: up to two control steps past the current step.
    interval_draws, delay_draws = [], []

    def interval():
        interval_draws.append(5)
        return 5

    def delay():
        delay_draws.append(0)
        return 0

    obs_updater = updater.Updater({"t": _scalar(update_interval=interval, delay=delay)}, 5)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    obs_updater.prepare_for_next_control_step()
    # Samples at 5 and 10 reach the horizon of 10 sub-steps; none is drawn for 15. The
    # first sample, at reset, drew a delay of its own.
    assert len(interval_draws) == 2
    assert len(delay_draws) == 1 + 2


def test_random_interval_samples_only_what_a_read_returns():
    # Every sub-step is scheduled, but one sample per control step is ever observed.
    calls = []

    def read(physics):
        calls.append(physics.time)
        return float(physics.time)

    obs = _enabled(observable.Generic(read, update_interval=lambda: 1))
    observations = _run({"t": obs}, 5, 3)
    assert [list(o["t"]) for o in observations] == [[0], [5], [10], [15]]
    assert [time for time in calls if time > 0] == [5, 10, 15]


def test_stochastic_interval_below_one_is_an_error_naming_observable_and_option():
    obs_updater = updater.Updater({"arm/pos": _scalar(update_interval=lambda: 0)}, 2)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    with pytest.raises(ValueError, match=r"'arm/pos'.*'update_interval'"):
        obs_updater.prepare_for_next_control_step()


def test_stochastic_negative_delay_is_an_error_naming_observable_and_option():
    obs_updater = updater.Updater({"arm/pos": _scalar(delay=lambda: -1)}, 2)
    with pytest.raises(ValueError, match=r"'arm/pos'.*'delay'"):
        obs_updater.reset(_Clock(), np.random.RandomState(0))


def test_sample_of_changed_shape_is_an_error_naming_observable():
    sizes = iter([3, 3, 4])
    obs = _enabled(observable.Generic(lambda p: np.zeros(next(sizes))))
    obs_updater = updater.Updater({"arm/joints": obs}, 1)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    obs_updater.prepare_for_next_control_step()
    with pytest.raises(ValueError, match=r"'arm/joints'.*shape \(4,\)"):
        obs_updater.update()


def test_first_sample_of_another_shape_than_the_probe_is_an_error_naming_observable():
    # Reset reads the value once for its shape and once as the episode's first sample.
    sizes = iter([3, 4])
    obs = _enabled(observable.Generic(lambda p: np.zeros(next(sizes))))
    obs_updater = updater.Updater({"arm/joints": obs}, 1)
    with pytest.raises(ValueError) as raised:
        obs_updater.reset(_Clock(), np.random.RandomState(0))
    assert str(raised.value) == (
        "observable 'arm/joints': sample has shape (4,), expected (3,) (dtype float64)"
    )


def test_update_interval_none_means_every_step():
    observations = _run({"t": _scalar(update_interval=None)}, 2, 2)
    assert [o["t"].tolist() for o in observations] == [[0.0], [2.0], [4.0]]


def test_strip_singleton_buffer_dim_removes_the_axis_of_size_one_buffers():
    observables = {"one": _vector(), "two": _vector(buffer_size=2), "late": _vector(delay=2)}
    obs_updater = updater.Updater(observables, 1, strip_singleton_buffer_dim=True)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    spec = obs_updater.observation_spec()
    assert spec["one"].shape == (2,)
    assert spec["two"].shape == (2, 2)
    assert spec["late"].shape == (2,)
    assert obs_updater.get_observation()["one"].shape == (2,)
    assert obs_updater.get_observation()["late"].shape == (2,)


def test_delayed_observations_are_zero_padded_by_default():
    late = _enabled(observable.Generic(lambda physics: physics.time + 5.0, delay=3))
    obs_updater = updater.Updater({"late": late})
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    assert obs_updater.get_observation()["late"].tolist() == [0.0]
    assert obs_updater.sample_steps == ()


@pytest.mark.parametrize(
    ("observables", "steps", "message"),
    [
        (
            [{"a": None}, 3],
            1,
            "Updater: observables must be a dict of observables or a list/tuple of such "
            "dicts, got list",
        ),
        (
            {},
            0,
            "observable '<updater>': option 'physics_steps_per_control_step' produced 0; "
            "expected an integer >= 1",
        ),
    ],
    ids=["list_of_non_dicts", "zero_steps"],
)
def test_bad_updater_arguments_are_named_in_full(observables, steps, message):
    with pytest.raises(ValueError) as raised:
        updater.Updater(observables, steps)
    assert str(raised.value) == message


@pytest.mark.parametrize(("value", "shown"), [(2.5, "2.5"), ("3", "'3'")])
def test_random_interval_that_is_not_an_integer_is_an_error_naming_it(value, shown):
    obs_updater = updater.Updater({"arm/pos": _scalar(update_interval=lambda: value)}, 2)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    with pytest.raises(ValueError) as raised:
        obs_updater.prepare_for_next_control_step()
    assert str(raised.value) == (
        f"observable 'arm/pos': option 'update_interval' produced {shown}; expected an integer >= 1"
    )


def test_spec_keeps_the_buffer_axis_by_default():
    obs_updater = updater.Updater({"one": _vector()}, 1)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    assert obs_updater.observation_spec()["one"].shape == (1, 2)


@pytest.mark.parametrize(
    "obs",
    [
        lambda: _vector(buffer_size=3),
        lambda: _scalar(),
        lambda: _enabled(observable.Generic(lambda p: np.int32(p.time))),
        lambda: _enabled(observable.Generic(lambda p: np.eye(3, dtype=np.float32))),
        lambda: _vector(buffer_size=4, aggregator="mean"),
        lambda: _enabled(observable.Generic(lambda p: np.arange(3), aggregator="median")),
    ],
    ids=["vector_buffer", "scalar", "int32", "matrix_float32", "mean", "median_of_ints"],
)
@pytest.mark.parametrize("strip", [False, True])
def test_observations_conform_to_spec(obs, strip):
    obs_updater = updater.Updater({"x": obs()}, 3, strip_singleton_buffer_dim=strip)
    clock = _Clock()
    obs_updater.reset(clock, np.random.RandomState(0))
    spec = obs_updater.observation_spec()["x"]
    for _ in range(2):
        obs_updater.prepare_for_next_control_step()
        for _ in range(3):
            clock.time += 1
            obs_updater.update()
        spec.validate(obs_updater.get_observation()["x"])


def test_bounded_spec_survives_bound_preserving_aggregator_only():
    class Bounded(observable.Generic):
        @property
        def array_spec(self):
            return specs.BoundedArray((), np.float64, -1.0, 1.0)

    observables = {
        "mean": _enabled(Bounded(lambda p: 0.5, buffer_size=2, aggregator="mean")),
        "sum": _enabled(Bounded(lambda p: 0.5, buffer_size=2, aggregator="sum")),
    }
    obs_updater = updater.Updater(observables, 1)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    spec = obs_updater.observation_spec()
    assert spec["mean"] == specs.BoundedArray((), np.float64, -1.0, 1.0, name="mean")
    assert type(spec["sum"]) is specs.Array
    assert spec["sum"] == specs.Array((), np.float64, name="sum")


class _BoundedPair(observable.Generic):
    """A float32 pair in [-1, 2] x [0, 3]."""

    @property
    def array_spec(self):
        return specs.BoundedArray((2,), np.float32, [-1.0, 0.0], [2.0, 3.0])


def _spec_of(obs, name="pair"):
    obs_updater = updater.Updater({name: _enabled(obs)}, 1)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    return obs_updater.observation_spec()[name]


def test_bound_preserving_aggregator_keeps_bounds_dtype_and_name():
    obs = _BoundedPair(lambda p: np.zeros(2, np.float32), buffer_size=3, aggregator="max")
    spec = _spec_of(obs)
    assert spec == specs.BoundedArray((2,), np.float32, [-1.0, 0.0], [2.0, 3.0])
    assert (spec.dtype, spec.name) == (np.float32, "pair")


def test_plain_callable_aggregator_drops_the_bounds_with_a_warning(caplog):
    obs = _BoundedPair(lambda p: np.zeros(2, np.float32), buffer_size=3, aggregator=np.sum)
    with caplog.at_level(logging.WARNING):
        spec = _spec_of(obs)
    assert type(spec) is specs.Array
    # np.sum over a float32 buffer keeps float32 and sums the whole buffer.
    assert spec == specs.Array((), np.float32, name="pair")
    assert [r.getMessage() for r in caplog.records] == [
        "Observable 'pair': dropping the bounds of its spec because its aggregator has no "
        "true `preserves_bounds` attribute."
    ]


def test_aggregated_spec_of_an_unspecified_observable_has_the_aggregated_dtype_and_name():
    obs = _enabled(
        observable.Generic(lambda p: np.zeros(3, np.float32), buffer_size=2, aggregator="min")
    )
    spec = _spec_of(obs, "low")
    assert spec == specs.Array((3,), np.float32)
    assert (spec.dtype, spec.name) == (np.float32, "low")


def test_observable_spec_subclass_is_kept_with_buffered_shape_and_name():
    class PixelSpec(specs.BoundedArray):
        pass

    class Pixels(observable.Generic):
        @property
        def array_spec(self):
            return PixelSpec((2,), np.uint8, 0, 255)

    obs_updater = updater.Updater(
        {"pixels": _enabled(Pixels(lambda p: np.array([1, 2], np.uint8), buffer_size=3))}, 1
    )
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    spec = obs_updater.observation_spec()["pixels"]
    assert type(spec) is PixelSpec
    assert (spec.shape, spec.dtype, spec.name) == ((3, 2), np.uint8, "pixels")
    assert (spec.minimum, spec.maximum) == (0, 255)


def test_returned_observations_are_not_changed_by_later_steps():
    observables = {"a": _vector(), "b": _vector(buffer_size=3), "c": _vector(delay=1)}
    clock = _Clock()
    obs_updater = updater.Updater(observables, 2)
    obs_updater.reset(clock, np.random.RandomState(0))
    obs_updater.prepare_for_next_control_step()
    for _ in range(2):
        clock.time += 1
        obs_updater.update()
    held = obs_updater.get_observation()
    snapshot = {name: value.copy() for name, value in held.items()}
    for _ in range(3):
        obs_updater.prepare_for_next_control_step()
        for _ in range(2):
            clock.time += 1
            obs_updater.update()
        obs_updater.get_observation()
    for name in held:
        np.testing.assert_array_equal(held[name], snapshot[name])


def test_mutating_a_returned_observation_does_not_change_the_next_one():
    obs_updater = updater.Updater({"a": _vector(update_interval=10)}, 1)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    obs_updater.get_observation()["a"][:] = 99.0
    np.testing.assert_array_equal(obs_updater.get_observation()["a"], [[0.0, 0.0]])


def test_observation_keys_follow_input_order_and_skip_disabled():
    disabled = observable.Generic(lambda p: 1.0)
    observables = collections.OrderedDict(
        [("z", _scalar()), ("off", disabled), ("a", _scalar()), ("m", _scalar())]
    )
    obs_updater = updater.Updater(observables, 1)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    observation = obs_updater.get_observation()
    assert isinstance(observation, collections.OrderedDict)
    assert list(observation) == ["z", "a", "m"]
    assert list(obs_updater.observation_spec()) == ["z", "a", "m"]


def test_disabled_observable_is_never_called():
    calls = []
    disabled = observable.Generic(lambda p: calls.append(p) or 1.0)
    _run({"on": _scalar(), "off": disabled}, 2, 2)
    assert calls == []


def test_list_of_dicts_gives_observations_in_the_same_structure():
    observables = (collections.OrderedDict(a=_scalar()), collections.OrderedDict(b=_vector()))
    observations = _run(observables, 2, 1)
    assert isinstance(observations[-1], tuple)
    assert [list(d) for d in observations[-1]] == [["a"], ["b"]]


def test_list_of_dicts_gives_specs_in_the_same_structure():
    observables = [collections.OrderedDict(a=_scalar()), dict(b=_vector())]
    obs_updater = updater.Updater(observables, 1)
    obs_updater.reset(_Clock(), np.random.RandomState(0))
    spec = obs_updater.observation_spec()
    assert type(spec) is list
    assert [type(d) for d in spec] == [collections.OrderedDict, dict]
    assert [(name, s.shape) for d in spec for name, s in d.items()] == [("a", (1,)), ("b", (1, 2))]


def test_observables_that_are_not_dicts_are_rejected():
    with pytest.raises(ValueError, match="dict"):
        updater.Updater([_scalar()], 1)


@pytest.mark.parametrize(
    "call",
    [
        lambda u: u.get_observation(),
        lambda u: u.observation_spec(),
        lambda u: u.prepare_for_next_control_step(),
        lambda u: u.update(),
        lambda u: u.finish_control_step(),
    ],
    ids=["get_observation", "observation_spec", "prepare", "update", "finish"],
)
def test_use_before_reset_raises(call):
    with pytest.raises(RuntimeError) as raised:
        call(updater.Updater({"a": _scalar()}, 1))
    assert str(raised.value) == "Updater: call reset(physics, random_state) first"


def test_reset_restarts_the_schedule_and_buffers():
    clock = _Clock()
    obs_updater = updater.Updater({"t": _scalar(update_interval=3, buffer_size=2)}, 2)
    for _ in range(2):
        clock.time = 0
        obs_updater.reset(clock, np.random.RandomState(0))
        for _ in range(2):
            obs_updater.prepare_for_next_control_step()
            for _ in range(2):
                clock.time += 1
                obs_updater.update()
        assert list(obs_updater.get_observation()["t"]) == [0.0, 3.0]


def test_interval_options_that_are_floats_with_integer_values_are_accepted():
    observations = _run({"t": _scalar(update_interval=lambda: 2.0)}, 2, 1)
    assert list(observations[-1]["t"]) == [2.0]


def test_default_constants_match_documented_defaults():
    assert (updater.DEFAULT_BUFFER_SIZE, updater.DEFAULT_UPDATE_INTERVAL) == (1, 1)
    assert updater.DEFAULT_DELAY == 0


def test_many_control_steps_with_coprime_intervals_stay_exact():
    observables = {"a": _scalar(update_interval=7, buffer_size=2), "b": _scalar(update_interval=4)}
    observations = _run(observables, 5, 30, chunked=True)
    for step, observation in enumerate(observations):
        now = step * 5
        last_a = now - now % 7
        expected_a = [max(last_a - 7, 0) if last_a >= 7 else 0.0, last_a]
        assert list(observation["a"]) == expected_a, step
        assert observation["b"][0] == now - now % 4, step


def test_cycle_of_interval_values_is_followed_in_order():
    cycle = itertools.cycle([1, 2, 3])
    obs = _scalar(update_interval=lambda: next(cycle), buffer_size=4)
    observations = _run({"t": obs}, 6, 1)
    assert list(observations[-1]["t"]) == [0.0, 1.0, 3.0, 6.0]


def test_an_observables_array_spec_sets_the_observation_dtype():
    class Float32Spec(observable.Generic):
        @property
        def array_spec(self):
            return specs.Array((1,), np.float32)

    obs = _enabled(Float32Spec(lambda physics: np.array([physics.time + 0.1])))
    observations = _run({"t": obs}, 2, 1)
    assert [o["t"].dtype for o in observations] == [np.float32, np.float32]
    assert observations[-1]["t"].tolist() == [[np.float32(2.1)]]


def _counted_observables(calls):
    """Observables that draw at every sample (a noise corruptor, a random delay), one of them
    without a spec, counting the calls made to their raw reads in `calls`."""

    def read(name, physics):
        calls.append(name)
        return _value_at(physics.time)

    delay_draws = _RecordedDraws(0, 3)
    noisy = _enabled(
        observable.Generic(
            functools.partial(read, "noisy"),
            corruptor=lambda v, random_state: v + random_state.normal(size=np.shape(v)),
        )
    )
    delayed = _enabled(
        observable.Generic(functools.partial(read, "delayed"), delay=delay_draws, buffer_size=2)
    )
    return {"noisy": noisy, "delayed": delayed}, delay_draws


@pytest.mark.parametrize("second", ["reset", "reset_draws"])
def test_reset_draws_then_reset_draws_and_reads_as_two_resets(second):
    def episode(second_reset):
        calls = []
        observables, delay_draws = _counted_observables(calls)
        clock, random_state = _Clock(), np.random.RandomState(3)
        obs_updater = updater.Updater(observables, 2)
        obs_updater.reset(clock, random_state)
        clock.time = 5
        getattr(obs_updater, second_reset)(clock, random_state)
        clock.time = 7
        obs_updater.reset(clock, random_state)
        obs_updater.prepare_for_next_control_step()
        for _ in range(2):
            clock.time += 1
            obs_updater.update()
        return calls, delay_draws.values, random_state.randint(1 << 30), obs_updater

    calls, delays, next_draw, obs_updater = episode(second)
    reference_calls, reference_delays, reference_next, reference = episode("reset")
    assert calls == reference_calls
    assert delays == reference_delays and len(delays) >= 3
    assert next_draw == reference_next
    observation, expected = obs_updater.get_observation(), reference.get_observation()
    for name in expected:
        np.testing.assert_array_equal(observation[name], expected[name])


def test_reset_draws_after_an_option_change_resets_the_specs_too():
    obs = _vector()
    obs_updater = updater.Updater({"x": obs}, 1)
    clock, random_state = _Clock(), np.random.RandomState(0)
    obs_updater.reset(clock, random_state)
    assert obs_updater.observation_spec()["x"].shape == (1, 2)
    obs.buffer_size = 3
    obs_updater.reset_draws(clock, random_state)
    assert obs_updater.observation_spec()["x"].shape == (3, 2)


def test_reset_draws_after_an_observable_is_enabled_resets_the_specs_too():
    later = observable.Generic(lambda physics: float(physics.time))
    obs_updater = updater.Updater({"x": _vector(), "later": later}, 1)
    clock, random_state = _Clock(), np.random.RandomState(0)
    obs_updater.reset(clock, random_state)
    assert list(obs_updater.observation_spec()) == ["x"]
    later.enabled = True
    obs_updater.reset_draws(clock, random_state)
    assert list(obs_updater.observation_spec()) == ["x", "later"]


def test_second_reset_with_the_same_inputs_starts_afresh_as_a_new_updater():
    def observables():
        noisy_and_delayed, _ = _counted_observables([])
        return {**noisy_and_delayed, "buffered": _scalar(buffer_size=3, update_interval=2)}

    def control_step(obs_updater, clock):
        obs_updater.prepare_for_next_control_step()
        for _ in range(2):
            clock.time += 1
            obs_updater.update()
        return obs_updater.get_observation()

    clock, random_state = _Clock(), np.random.RandomState(5)
    obs_updater = updater.Updater(observables(), 2)
    obs_updater.reset(clock, random_state)
    for _ in range(2):
        control_step(obs_updater, clock)
    clock.time = 10
    state = random_state.get_state()
    obs_updater.reset(clock, random_state)
    # A new updater for the same observables, from the same clock and random state.
    fresh_clock, fresh_random_state = _Clock(), np.random.RandomState()
    fresh_clock.time = 10
    fresh_random_state.set_state(state)
    fresh = updater.Updater(observables(), 2)
    fresh.reset(fresh_clock, fresh_random_state)
    assert list(obs_updater.get_observation()["buffered"]) == [0.0, 0.0, 10.0]
    for _ in range(3):
        observation = control_step(obs_updater, clock)
        expected = control_step(fresh, fresh_clock)
        assert observation.keys() == expected.keys()
        for name in expected:
            np.testing.assert_array_equal(observation[name], expected[name])
    assert random_state.randint(1 << 30) == fresh_random_state.randint(1 << 30)


def test_second_reset_with_the_same_inputs_follows_a_changed_sample_shape():
    size = [2]
    obs_updater = updater.Updater(
        {"x": _enabled(observable.Generic(lambda p: np.ones(size[0])))}, 1
    )
    clock, random_state = _Clock(), np.random.RandomState(0)
    obs_updater.reset(clock, random_state)
    assert obs_updater.observation_spec()["x"].shape == (1, 2)
    size[0] = 4
    obs_updater.reset(clock, random_state)
    assert obs_updater.observation_spec()["x"].shape == (1, 4)
    assert obs_updater.get_observation()["x"].tolist() == [[1.0] * 4]
