"""Random distributions usable as variations; parameters may themselves be variations.

Without `single_sample`, a distribution called with an `initial_value` draws samples of that
value's shape; called without one, the sample shape is the broadcast shape of the parameters.
With `single_sample=True` one draw (of the parameters' shape) is made and broadcast to the
shape of `initial_value` where the two shapes are compatible.
"""

from __future__ import annotations

import abc

import numpy as np

from composer.variation import base


def _random_state(random_state):
    return np.random if random_state is None else random_state


def _contains_variation(structure) -> bool:
    if isinstance(structure, base.Variation):
        return True
    if isinstance(structure, (list, tuple)):
        return any(_contains_variation(item) for item in structure)
    if isinstance(structure, dict):
        return any(_contains_variation(value) for value in structure.values())
    return False


def _check_broadcastable(owner: str, **params) -> None:
    shapes = {name: np.shape(value) for name, value in params.items()}
    try:
        np.broadcast_shapes(*shapes.values())
    except ValueError:
        described = ", ".join(f"{name} of shape {shape}" for name, shape in shapes.items())
        raise ValueError(f"{owner}: parameters have incompatible shapes: {described}") from None


def _check_non_negative(owner: str, **params) -> None:
    for name, value in params.items():
        if np.any(np.asarray(value) < 0):
            raise ValueError(f"{owner}: {name} must be non-negative, got {value!r}")


def _describe(name: str, args, kwargs) -> str:
    params = [repr(arg) for arg in args]
    params += [f"{key}={value!r}" for key, value in kwargs.items()]
    return f"{name}({', '.join(params)})"


class Distribution(base.Variation):
    """Base class for variations drawn from a parametrised NumPy distribution.

    Subclasses implement `_callable(random_state)`, returning the sampler to call as
    `sampler(*args, size=size, **kwargs)` with the evaluated constructor arguments, and may
    override `_validate(*args, **kwargs)` to reject bad parameters. Constant parameters are
    validated at construction; parameters that contain variations at each evaluation.
    """

    def __init__(self, *args, single_sample: bool = False, **kwargs):
        self._single_sample = single_sample
        self._args = args
        self._kwargs = kwargs
        self._has_variable_parameters = _contains_variation((args, kwargs))
        if not self._has_variable_parameters:
            self._validate(*args, **kwargs)

    def __getattr__(self, name):
        # Keyword parameters read as attributes (`Uniform(0, 1).high`), as in dm_control.
        if not name.startswith("_"):
            kwargs = self.__dict__.get("_kwargs", {})
            if name in kwargs:
                return kwargs[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def _validate(self, *args, **kwargs) -> None:
        """Raises ValueError for invalid parameter values; accepts everything by default."""

    @abc.abstractmethod
    def _callable(self, random_state):
        """Returns the NumPy sampling function of `random_state` for this distribution."""

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        if self._has_variable_parameters:
            args = base.evaluate(self._args, initial_value, current_value, random_state)
            kwargs = base.evaluate(self._kwargs, initial_value, current_value, random_state)
            self._validate(*args, **kwargs)
        else:
            # Constant parameters evaluate to themselves: skip the traversal (this runs
            # once per sample when the distribution corrupts an observable).
            args, kwargs = self._args, self._kwargs
        if initial_value is None:
            target_shape = None
        else:
            # `np.shape(initial_value)`, without its dispatch: a corruptor's distribution
            # draws once per sample, for arrays that are often ndarray subclasses.
            try:
                target_shape = initial_value.shape
            except AttributeError:
                target_shape = np.asarray(initial_value).shape
        single_sample = self._single_sample
        size = None if single_sample else target_shape
        sampler = self._callable(np.random if random_state is None else random_state)
        try:
            sample = sampler(*args, size=size, **kwargs)
        except ValueError as error:
            raise ValueError(
                f"{_describe(type(self).__name__, args, kwargs)}: cannot draw samples of shape "
                f"{size}: {error}"
            ) from error
        if single_sample and target_shape is not None and np.shape(sample) != target_shape:
            try:
                if np.broadcast_shapes(np.shape(sample), target_shape) == target_shape:
                    return np.broadcast_to(sample, target_shape).copy()
            except ValueError:
                pass  # shapes do not broadcast: return the draw as it is, like dm_control
        return sample

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return (
            self._single_sample == other._single_sample
            and base.same_value(self._args, other._args)
            and base.same_value(self._kwargs, other._kwargs)
        )

    __hash__ = None

    def __repr__(self):
        return (
            f"{type(self).__name__}(args={self._args!r}, kwargs={self._kwargs!r}, "
            f"single_sample={self._single_sample!r})"
        )


class Uniform(Distribution):
    """Uniform samples in `[low, high)`."""

    def __init__(self, low=0.0, high=1.0, single_sample: bool = False):
        super().__init__(low=low, high=high, single_sample=single_sample)

    def _validate(self, low, high):
        _check_broadcastable("Uniform", low=low, high=high)
        if np.any(np.asarray(low) > np.asarray(high)):
            raise ValueError(f"Uniform: low must not exceed high, got low={low!r}, high={high!r}")

    def _callable(self, random_state):
        return random_state.uniform


class UniformInteger(Distribution):
    """Uniform integers in `[low, high)`, or in `[0, low)` when `high` is None."""

    def __init__(self, low, high=None, single_sample: bool = False):
        super().__init__(low, high=high, single_sample=single_sample)

    def _validate(self, low, high):
        if high is None:
            if np.any(np.asarray(low) <= 0):
                raise ValueError(
                    f"UniformInteger: low must be positive when high is None, got {low!r}"
                )
            return
        _check_broadcastable("UniformInteger", low=low, high=high)
        if np.any(np.asarray(low) >= np.asarray(high)):
            raise ValueError(
                f"UniformInteger: low must be smaller than high, got low={low!r}, high={high!r}"
            )

    def _callable(self, random_state):
        return getattr(random_state, "randint", None) or random_state.integers


class UniformChoice(Distribution):
    """Uniformly chosen elements of the 1-D sequence `choices`."""

    def __init__(self, choices, single_sample: bool = False):
        super().__init__(choices, single_sample=single_sample)

    def _validate(self, choices):
        if np.ndim(choices) != 1 or len(choices) == 0:
            raise ValueError(
                f"UniformChoice: choices must be a non-empty 1-D sequence, got {choices!r}"
            )

    def _callable(self, random_state):
        return random_state.choice


class Normal(Distribution):
    """Gaussian samples with mean `loc` and standard deviation `scale`."""

    def __init__(self, loc=0.0, scale=1.0, single_sample: bool = False):
        super().__init__(loc=loc, scale=scale, single_sample=single_sample)

    def _validate(self, loc, scale):
        _check_broadcastable("Normal", loc=loc, scale=scale)
        _check_non_negative("Normal", scale=scale)

    def _callable(self, random_state):
        return random_state.normal


class LogNormal(Distribution):
    """Samples whose logarithm is Gaussian with mean `mean` and standard deviation `sigma`."""

    def __init__(self, mean=0.0, sigma=1.0, single_sample: bool = False):
        super().__init__(mean=mean, sigma=sigma, single_sample=single_sample)

    def _validate(self, mean, sigma):
        _check_broadcastable("LogNormal", mean=mean, sigma=sigma)
        _check_non_negative("LogNormal", sigma=sigma)

    def _callable(self, random_state):
        return random_state.lognormal


class Exponential(Distribution):
    """Exponential samples with mean `scale`."""

    def __init__(self, scale=1.0, single_sample: bool = False):
        super().__init__(scale=scale, single_sample=single_sample)

    def _validate(self, scale):
        _check_non_negative("Exponential", scale=scale)

    def _callable(self, random_state):
        return random_state.exponential


class Poisson(Distribution):
    """Poisson samples with rate `lam`."""

    def __init__(self, lam=1.0, single_sample: bool = False):
        super().__init__(lam=lam, single_sample=single_sample)

    def _validate(self, lam):
        _check_non_negative("Poisson", lam=lam)

    def _callable(self, random_state):
        return random_state.poisson


class Bernoulli(Distribution):
    """Samples that are 1 with probability `prob` and 0 otherwise."""

    def __init__(self, prob=0.5, single_sample: bool = False):
        super().__init__(prob, single_sample=single_sample)

    def _validate(self, prob):
        if np.any((np.asarray(prob) < 0) | (np.asarray(prob) > 1)):
            raise ValueError(f"Bernoulli: prob must lie in [0, 1], got {prob!r}")

    def _callable(self, random_state):
        def sample(prob, size=None):
            return random_state.binomial(1, prob, size)

        return sample


class UniformPointOnSphere(base.Variation):
    """Uniformly distributed unit 3-vectors.

    Called with an `initial_value` (and `single_sample=False`), returns an array of shape
    `np.shape(initial_value) + (3,)`; otherwise a single (3,) vector.
    """

    def __init__(self, single_sample: bool = False):
        self._single_sample = single_sample

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        if self._single_sample or initial_value is None:
            size = (3,)
        else:
            size = np.shape(initial_value) + (3,)
        points = _random_state(random_state).normal(size=size)
        return points / np.linalg.norm(points, axis=-1, keepdims=True)

    def __eq__(self, other):
        if not isinstance(other, UniformPointOnSphere):
            return NotImplemented
        return self._single_sample == other._single_sample

    __hash__ = None

    def __repr__(self):
        return f"UniformPointOnSphere(single_sample={self._single_sample!r})"


#: Message templates for BiasedRandomWalk's argument checks (dm_control's tests read them).
_NEGATIVE_STDEV = "BiasedRandomWalk: stdev must be non-negative, got {!r}"
_NEGATIVE_TIMESCALE = "BiasedRandomWalk: timescale must be non-negative, got {!r}"


class BiasedRandomWalk(base.Variation):
    """Zero-mean Ornstein-Uhlenbeck noise: each call advances the process by one step.

    `x <- retain * x + N(0, stdev * sqrt(1 - retain**2))` with `retain = exp(-1 / timescale)`,
    so the stationary standard deviation is `stdev` and correlation decays by a factor e
    every `timescale` calls. `timescale=0` gives uncorrelated Gaussian noise.
    """

    def __init__(self, stdev: float = 0.1, timescale: float = 10.0):
        if stdev < 0:
            raise ValueError(_NEGATIVE_STDEV.format(stdev))
        if timescale < 0:
            raise ValueError(_NEGATIVE_TIMESCALE.format(timescale))
        self._retain = 0.0 if timescale == 0 else float(np.exp(-1.0 / timescale))
        self._scale = stdev * np.sqrt(1.0 - self._retain**2)
        self._value = 0.0

    def __call__(self, initial_value=None, current_value=None, random_state=None):
        noise = _random_state(random_state).normal(loc=0.0, scale=self._scale)
        self._value = self._retain * self._value + noise
        return self._value
