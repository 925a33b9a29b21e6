"""Tests for composer.variation.distributions."""

import numpy as np
import pytest

from composer.variation import deterministic, distributions


def _draws(dist, seed, count=5, **kwargs):
    random_state = np.random.RandomState(seed)
    return [dist(random_state=random_state, **kwargs) for _ in range(count)]


@pytest.mark.parametrize(
    "dist",
    [
        distributions.Uniform(-1.0, 1.0),
        distributions.UniformInteger(0, 100),
        distributions.UniformChoice(["a", "b", "c", "d"]),
        distributions.Normal(0.0, 1.0),
        distributions.LogNormal(0.0, 1.0),
        distributions.Exponential(2.0),
        distributions.Poisson(3.0),
        distributions.Bernoulli(0.5),
        distributions.UniformPointOnSphere(),
    ],
    ids=lambda dist: type(dist).__name__,
)
def test_same_seed_reproduces_samples_and_other_seed_differs(dist):
    first = _draws(dist, seed=3, count=20)
    again = _draws(dist, seed=3, count=20)
    other = _draws(dist, seed=4, count=20)
    np.testing.assert_array_equal(np.array(first), np.array(again))
    assert not np.array_equal(np.array(first), np.array(other))


def test_sample_shape_follows_broadcast_parameters():
    sample = distributions.Uniform(low=[0.0, 1.0, 2.0], high=3.0)(
        random_state=np.random.RandomState(0)
    )
    assert sample.shape == (3,)
    assert np.all(sample >= [0.0, 1.0, 2.0]) and np.all(sample < 3.0)


def test_sample_shape_follows_initial_value():
    sample = distributions.Normal()(initial_value=np.zeros((2, 3)))
    assert sample.shape == (2, 3)


def test_single_sample_draws_one_value_and_broadcasts_it():
    sample = distributions.Uniform(single_sample=True)(
        initial_value=np.zeros(4), random_state=np.random.RandomState(0)
    )
    assert sample.shape == (4,)
    assert np.all(sample == sample[0])


def test_without_single_sample_elements_are_independent():
    sample = distributions.Uniform()(
        initial_value=np.zeros(4), random_state=np.random.RandomState(0)
    )
    assert len(set(sample.tolist())) == 4


def test_uniform_samples_lie_in_the_interval():
    samples = distributions.Uniform(2.0, 3.0)(
        initial_value=np.zeros(1000), random_state=np.random.RandomState(0)
    )
    assert samples.min() >= 2.0 and samples.max() < 3.0


def test_uniform_integer_without_high_samples_from_zero_to_low():
    samples = distributions.UniformInteger(3)(initial_value=np.zeros(300))
    assert set(samples.tolist()) == {0, 1, 2}


def test_uniform_choice_returns_only_given_choices():
    samples = distributions.UniformChoice([2, 5, 7])(initial_value=np.zeros(200))
    assert set(samples.tolist()) == {2, 5, 7}


def test_normal_matches_its_moments():
    samples = distributions.Normal(loc=1.5, scale=0.5)(
        initial_value=np.zeros(20000), random_state=np.random.RandomState(0)
    )
    assert samples.mean() == pytest.approx(1.5, abs=0.02)
    assert samples.std() == pytest.approx(0.5, abs=0.02)


def test_bernoulli_returns_zeros_and_ones_with_given_rate():
    samples = distributions.Bernoulli(0.25)(
        initial_value=np.zeros(20000), random_state=np.random.RandomState(0)
    )
    assert set(samples.tolist()) == {0, 1}
    assert samples.mean() == pytest.approx(0.25, abs=0.02)


def test_point_on_sphere_has_unit_norm_and_initial_value_batch_shape():
    points = distributions.UniformPointOnSphere()(initial_value=np.zeros(50))
    assert points.shape == (50, 3)
    np.testing.assert_allclose(np.linalg.norm(points, axis=-1), 1.0)


def test_parameters_may_be_variations():
    dist = distributions.Uniform(
        low=deterministic.Sequence([0.0, 10.0]), high=deterministic.Sequence([1.0, 11.0])
    )
    random_state = np.random.RandomState(0)
    assert 0.0 <= dist(random_state=random_state) < 1.0
    assert 10.0 <= dist(random_state=random_state) < 11.0


def test_variable_parameters_are_validated_when_evaluated():
    dist = distributions.Normal(scale=deterministic.Constant(-1.0))
    with pytest.raises(ValueError, match="Normal: scale must be non-negative"):
        dist()


def test_biased_random_walk_has_stationary_stdev_and_correlation():
    walk = distributions.BiasedRandomWalk(stdev=0.5, timescale=5.0)
    random_state = np.random.RandomState(0)
    values = np.array([walk(random_state=random_state) for _ in range(40000)])[1000:]
    assert values.std() == pytest.approx(0.5, rel=0.1)
    lag_one = np.corrcoef(values[:-1], values[1:])[0, 1]
    assert lag_one == pytest.approx(np.exp(-1.0 / 5.0), abs=0.03)


def test_biased_random_walk_with_zero_timescale_is_uncorrelated():
    walk = distributions.BiasedRandomWalk(stdev=1.0, timescale=0.0)
    random_state = np.random.RandomState(0)
    values = np.array([walk(random_state=random_state) for _ in range(20000)])
    assert abs(np.corrcoef(values[:-1], values[1:])[0, 1]) < 0.03


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda: distributions.Uniform([0.0, 0.0], [1.0, 1.0, 1.0]),
            "incompatible shapes: low of shape \\(2,\\), high of shape \\(3,\\)",
        ),
        (lambda: distributions.Uniform(1.0, 0.0), "low must not exceed high"),
        (lambda: distributions.UniformInteger(5, 5), "low must be smaller than high"),
        (lambda: distributions.UniformInteger(0), "low must be positive when high is None"),
        (lambda: distributions.UniformChoice([]), "choices must be a non-empty 1-D sequence"),
        (lambda: distributions.Normal(0.0, -0.1), "Normal: scale must be non-negative"),
        (
            lambda: distributions.Normal([0.0, 0.0], [1.0, 1.0, 1.0]),
            "Normal: parameters have incompatible shapes",
        ),
        (lambda: distributions.LogNormal(0.0, -1.0), "LogNormal: sigma must be non-negative"),
        (lambda: distributions.Exponential(-2.0), "Exponential: scale must be non-negative"),
        (lambda: distributions.Poisson(-1.0), "Poisson: lam must be non-negative"),
        (lambda: distributions.Bernoulli(1.5), "Bernoulli: prob must lie in \\[0, 1\\]"),
        (lambda: distributions.BiasedRandomWalk(stdev=-1.0), "stdev must be non-negative"),
        (lambda: distributions.BiasedRandomWalk(timescale=-1.0), "timescale must be non-negative"),
    ],
)
def test_bad_parameters_are_rejected_at_construction(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_parameters_incompatible_with_initial_value_shape_are_reported():
    with pytest.raises(
        ValueError, match=r"Uniform\(low=\[0, 0\], high=1\): cannot draw samples of shape \(3,\)"
    ):
        distributions.Uniform([0, 0], 1)(initial_value=np.zeros(3))


def test_keyword_parameters_read_as_attributes():
    uniform = distributions.Uniform(low=0.3, high=2.0)
    assert uniform.low == 0.3
    assert uniform.high == 2.0
    assert distributions.Normal(loc=1.0, scale=0.5).scale == 0.5


def test_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="'Uniform' object has no attribute 'mean'"):
        _ = distributions.Uniform().mean


def test_distributions_with_equal_parameters_compare_equal():
    assert distributions.Uniform([0, 1], [2, 3]) == distributions.Uniform([0, 1], [2, 3])
    assert distributions.Normal(np.zeros(2), 1.0) == distributions.Normal(np.zeros(2), 1.0)
    assert distributions.UniformPointOnSphere() == distributions.UniformPointOnSphere()


def test_distributions_differing_in_type_parameters_or_single_sample_differ():
    assert distributions.Normal(0.0, 1.0) != distributions.LogNormal(0.0, 1.0)
    assert distributions.Normal(0.0, 1.0) != distributions.Normal(0.0, 2.0)
    assert distributions.Normal(0.0, 1.0) != distributions.Normal(0.0, 1.0, single_sample=True)
    assert distributions.UniformPointOnSphere() != distributions.UniformPointOnSphere(
        single_sample=True
    )


def test_biased_random_walks_are_equal_only_to_themselves():
    walk = distributions.BiasedRandomWalk()
    assert walk == walk
    assert walk != distributions.BiasedRandomWalk()


def test_distribution_repr_lists_args_kwargs_and_single_sample():
    assert repr(distributions.Exponential(scale=3)) == (
        "Exponential(args=(), kwargs={'scale': 3}, single_sample=False)"
    )
