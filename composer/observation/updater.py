"""Samples enabled observables at physics sub-steps and assembles the agent's observations."""

import functools
import inspect
import math
import operator
from collections.abc import Callable

import numpy as np
from absl import logging
from dm_env import specs

from composer.observation import obs_buffer

DEFAULT_BUFFER_SIZE = 1
DEFAULT_UPDATE_INTERVAL = 1
DEFAULT_DELAY = 0

_NEVER = math.inf

# Plans are cached per phase of the schedule; this bounds the cache when intervals have a
# very large least common multiple.
_MAX_CACHED_PLANS = 4096


def _accepts_random_state(function: Callable) -> bool:
    try:
        parameters = inspect.signature(function).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(
        p.name == "random_state" or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters
    )


def _drawer(option: Callable, random_state) -> Callable[[], object]:
    """Returns a zero-argument function drawing a value of a callable option."""
    if _accepts_random_state(option):
        return functools.partial(option, random_state=random_state)
    return option


def _as_count(name: str, option: str, value, minimum: int) -> int:
    """Returns `value` as an int >= minimum, or raises a ValueError naming the observable."""
    try:
        count = operator.index(value)
    except TypeError:
        count = None
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            count = int(value)
    if count is None or count < minimum:
        raise ValueError(
            f"observable {name!r}: option {option!r} produced {value!r}; expected an integer "
            f">= {minimum}"
        )
    return count


class _EnabledObservable:
    """An enabled observable bound to one episode's physics: its options, buffer and plan."""

    __slots__ = (
        "name",
        "observable",
        "observation_callable",
        "buffer",
        "aggregator",
        "buffer_size",
        "update_interval",
        "delay",
        "_draw_interval",
        "_draw_delay",
        "_schedule",
        "_last_scheduled",
        "_offsets_by_phase",
        "_period",
    )

    def __init__(self, name, observable, physics, random_state, steps_per_control, strip, pad):
        self.name = name
        self.observable = observable
        self.observation_callable = observable.observation_callable(physics, random_state)
        self.update_interval, self._draw_interval = self._bind_option(
            observable.update_interval, DEFAULT_UPDATE_INTERVAL, random_state
        )
        self.delay, self._draw_delay = self._bind_option(
            observable.delay, DEFAULT_DELAY, random_state
        )
        self.buffer_size = observable.buffer_size or DEFAULT_BUFFER_SIZE
        self.aggregator = observable.aggregator
        spec = observable.array_spec
        if spec is None:
            # One sample gives the shape and dtype (the caller mutes physics errors).
            value = np.asarray(self.observation_callable())
            shape, dtype = value.shape, value.dtype
        else:
            shape, dtype = spec.shape, spec.dtype
        if self.buffer_size == 1 and self._draw_delay is None and self.delay == 0:
            self.buffer = obs_buffer.LatestSampleBuffer(shape, dtype, strip)
        else:
            self.buffer = obs_buffer.Buffer(self.buffer_size, shape, dtype, pad, strip)
        self._schedule = []
        self._last_scheduled = 0
        self._offsets_by_phase = {}
        if self.is_stochastic:
            self._period = None
        else:
            self._period = math.lcm(self.update_interval, steps_per_control)

    @staticmethod
    def _bind_option(value, default, random_state):
        """Returns (fixed value or None, zero-argument drawer or None)."""
        if not value:
            return default, None
        if callable(value):
            return None, _drawer(value, random_state)
        return value, None

    @property
    def is_stochastic(self) -> bool:
        return self._draw_interval is not None or self._draw_delay is not None

    def next_delay(self) -> int:
        if self._draw_delay is None:
            return self.delay
        return _as_count(self.name, "delay", self._draw_delay(), 0)

    def _next_interval(self) -> int:
        if self._draw_interval is None:
            return self.update_interval
        return _as_count(self.name, "update_interval", self._draw_interval(), 1)

    def sample(self, timestamp, delay) -> None:
        value = self.observation_callable()
        try:
            self.buffer.insert(timestamp, delay, value)
        except obs_buffer.IncompatibleSampleError as exc:
            raise ValueError(f"observable {self.name!r}: {exc}") from None

    def due_entry(self, delay) -> tuple:
        """What `Updater.update` needs to take one sample: (insert, sample, delay, name)."""
        return self.buffer.insert, self.observation_callable, delay, self.name

    def plan(self, start: int, steps: int):
        """Returns ((offset, delay), ...) of the samples due in sub-steps start+1..start+steps
        that some read at a multiple of `steps` will return."""
        if self._period is None:
            return self._stochastic_plan(start, steps)
        phase = start % self._period
        planned = self._offsets_by_phase.get(phase)
        if planned is None:
            planned = self._fixed_plan(start, steps)
            if len(self._offsets_by_phase) < _MAX_CACHED_PLANS:
                self._offsets_by_phase[phase] = planned
        return planned

    def _fixed_plan(self, start, steps):
        # With a fixed delay samples arrive in timestamp order, so the ones arriving after a
        # sample by its first read are exactly the scheduled ones with timestamps up to that
        # read minus the delay.
        interval, delay = self.update_interval, self.delay
        planned = []
        for timestamp in range(start + interval - start % interval, start + steps + 1, interval):
            first_read = -(-(timestamp + delay) // steps) * steps
            arriving_later = (first_read - delay) // interval - timestamp // interval
            if arriving_later < self.buffer_size:
                planned.append((timestamp - start, delay))
        return tuple(planned)

    def _stochastic_plan(self, start, steps):
        schedule = self._schedule
        while schedule and schedule[0][0] <= start:
            schedule.pop(0)
        # Options are drawn two control steps ahead (interval, then delay, for each sample)
        # so that a sample's fate is decided knowing the samples that could displace it.
        horizon = start + 2 * steps
        while self._last_scheduled < horizon:
            self._last_scheduled += self._next_interval()
            schedule.append((self._last_scheduled, self.next_delay()))
        self.buffer.drop_unobserved_upcoming_items(schedule, steps)
        end = start + steps
        return tuple((t - start, d) for t, d in schedule if t <= end)

    def read_function(self) -> Callable[[int], np.ndarray]:
        read, aggregator = self.buffer.read, self.aggregator
        if aggregator is None:
            return read
        return lambda current_time: aggregator(read(current_time))

    def spec(self) -> specs.Array:
        bounds = None
        array_spec = self.observable.array_spec
        if isinstance(array_spec, specs.BoundedArray):
            bounds = (array_spec.minimum, array_spec.maximum)
        if self.aggregator is None:
            shape, dtype = self.buffer.shape, self.buffer.dtype
        else:
            aggregated = np.asarray(
                self.aggregator(np.zeros(self.buffer.shape, dtype=self.buffer.dtype))
            )
            shape, dtype = aggregated.shape, aggregated.dtype
            if bounds is not None and not getattr(self.aggregator, "preserves_bounds", False):
                logging.warning(
                    "Observable %r: dropping the bounds of its spec because its aggregator "
                    "has no true `preserves_bounds` attribute.",
                    self.name,
                )
                bounds = None
        if bounds is None:
            return specs.Array(shape=shape, dtype=dtype, name=self.name)
        return specs.BoundedArray(shape, dtype, bounds[0], bounds[1], name=self.name)


def _is_nested(observables) -> bool:
    if isinstance(observables, (list, tuple)):
        if all(isinstance(item, dict) for item in observables):
            return True
    elif isinstance(observables, dict):
        return False
    raise ValueError(
        f"Updater: observables must be a dict of observables or a list/tuple of such dicts, "
        f"got {type(observables).__name__}"
    )


class Updater:
    """Samples the enabled observables during a control step and builds observations.

    Use per episode: `reset(physics, random_state)`, then per control step
    `prepare_for_next_control_step()`, `update()` after each physics sub-step, and
    `get_observation()`. Observations are read at integer multiples of
    `physics_steps_per_control_step` (that is, after each control step).

    `observables` is a dict name -> Observable, or a list/tuple of such dicts; specs and
    observations come back in the same structure (same dict type, same key order), holding
    only the observables that were enabled at `reset`.

    Speed: after `prepare_for_next_control_step()`, `sample_steps` lists the sub-steps
    (1..physics_steps_per_control_step) after which some observable must be sampled; with
    default options that is only the last one. A caller may step the physics several times
    and then call `update(num_steps=k)`, provided no skipped sub-step is in `sample_steps`;
    observations are identical to calling `update()` after every sub-step.
    """

    def __init__(
        self,
        observables,
        physics_steps_per_control_step: int = 1,
        strip_singleton_buffer_dim: bool = False,
        pad_with_initial_value: bool = False,
    ):
        self._is_nested = _is_nested(observables)
        self._observables = observables
        self._steps = _as_count(
            "<updater>", "physics_steps_per_control_step", physics_steps_per_control_step, 1
        )
        self._strip_singleton_buffer_dim = strip_singleton_buffer_dim
        self._pad_with_initial_value = pad_with_initial_value
        self._enabled_structure = None
        self._enabled_list = ()
        self._readers = ()
        self._plan_period = None
        self._step_counter = 0
        self._reset_plan()

    def _reset_plan(self):
        self._plan_start = 0
        self._sample_steps = ()
        self._due = ()
        self._due_index = 0
        self._next_due = _NEVER
        self._plans_by_phase = {}

    @property
    def sample_steps(self) -> tuple:
        """Sub-steps of the coming control step after which `update` must be called."""
        return self._sample_steps

    def reset(self, physics, random_state) -> None:
        """Binds the enabled observables to `physics` and takes the first sample of each."""

        def enable(observables):
            enabled = type(observables)()
            for name, observable in observables.items():
                if observable.enabled:
                    enabled[name] = _EnabledObservable(
                        name,
                        observable,
                        physics,
                        random_state,
                        self._steps,
                        self._strip_singleton_buffer_dim,
                        self._pad_with_initial_value,
                    )
            return enabled

        # Observables without an array_spec are sampled once for their shape and dtype; the
        # physics state may not be valid before the episode's first step, so divergence
        # errors are muted meanwhile.
        with physics.suppress_physics_errors():
            if self._is_nested:
                structure = type(self._observables)(enable(d) for d in self._observables)
                dicts = list(structure)
            else:
                structure = enable(self._observables)
                dicts = [structure]
        self._enabled_structure = structure
        self._enabled_list = [enabled for d in dicts for enabled in d.values()]
        self._readers = [
            (type(d), list(d), [enabled.read_function() for enabled in d.values()]) for d in dicts
        ]
        if any(enabled.is_stochastic for enabled in self._enabled_list):
            self._plan_period = None
        else:
            self._plan_period = math.lcm(
                self._steps, *(enabled.update_interval for enabled in self._enabled_list)
            )
        self._step_counter = 0
        self._reset_plan()
        for enabled in self._enabled_list:
            enabled.sample(0, enabled.next_delay())

    def _check_reset(self):
        if self._enabled_structure is None:
            raise RuntimeError("Updater: call reset(physics, random_state) first")

    def observation_spec(self):
        """Specs of the observations, in the structure of `observables`.

        A spec has the leading buffer axis unless stripped (buffer size 1 and
        `strip_singleton_buffer_dim`); an aggregator's output shape replaces it. Bounds of a
        `BoundedArray` spec survive only aggregators with `preserves_bounds = True`.
        """
        self._check_reset()
        out = [
            type(d)((name, enabled.spec()) for name, enabled in d.items())
            for d in (self._enabled_structure if self._is_nested else [self._enabled_structure])
        ]
        return type(self._enabled_structure)(out) if self._is_nested else out[0]

    def prepare_for_next_control_step(self) -> None:
        """Plans which sub-steps of the coming control step sample which observables."""
        self._check_reset()
        start = self._step_counter
        if self._plan_period is not None:
            phase = start % self._plan_period
            plan = self._plans_by_phase.get(phase)
            if plan is None:
                plan = self._build_plan(start)
                if len(self._plans_by_phase) < _MAX_CACHED_PLANS:
                    self._plans_by_phase[phase] = plan
        else:
            plan = self._build_plan(start)
        self._plan_start = start
        self._sample_steps, self._due = plan
        self._due_index = 0
        self._next_due = self._sample_steps[0] if self._sample_steps else _NEVER

    def _build_plan(self, start):
        due = {}
        for enabled in self._enabled_list:
            for offset, delay in enabled.plan(start, self._steps):
                due.setdefault(offset, []).append(enabled.due_entry(delay))
        sample_steps = tuple(sorted(due))
        return sample_steps, tuple(tuple(due[offset]) for offset in sample_steps)

    def update(self, num_steps: int = 1) -> None:
        """Records that `num_steps` physics steps have passed and samples what is now due."""
        if self._enabled_structure is None:
            self._check_reset()
        counter = self._step_counter + num_steps
        self._step_counter = counter
        offset = counter - self._plan_start
        if offset < self._next_due:
            return
        if offset > self._next_due:
            raise RuntimeError(
                f"Updater.update(num_steps={num_steps}) skipped sub-step {self._next_due} of "
                f"this control step, at which observables are due (sample_steps "
                f"{self._sample_steps})"
            )
        index = self._due_index
        try:
            for insert, sample, delay, name in self._due[index]:  # noqa: B007 (see except)
                insert(counter, delay, sample())
        except obs_buffer.IncompatibleSampleError as exc:
            raise ValueError(f"observable {name!r}: {exc}") from None
        index += 1
        self._due_index = index
        self._next_due = self._sample_steps[index] if index < len(self._sample_steps) else _NEVER

    def get_observation(self):
        """Returns new arrays the caller owns, in the structure of `observables`."""
        self._check_reset()
        now = self._step_counter
        if not self._is_nested:
            dict_type, names, reads = self._readers[0]
            return dict_type(zip(names, [read(now) for read in reads]))
        return type(self._enabled_structure)(
            dict_type(zip(names, [read(now) for read in reads]))
            for dict_type, names, reads in self._readers
        )
