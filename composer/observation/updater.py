"""Samples enabled observables at physics sub-steps and assembles the agent's observations."""

import functools
import inspect
import math
import operator
from collections.abc import Callable, Mapping
from typing import NamedTuple

import numpy as np
from absl import logging
from dm_env import specs

from composer.observation import obs_buffer
from composer.utils import argument_checks

DEFAULT_BUFFER_SIZE = 1
DEFAULT_UPDATE_INTERVAL = 1
DEFAULT_DELAY = 0

_NEVER = math.inf

# Plans are cached per phase of the schedule; this bounds the cache when intervals have a
# very large least common multiple.
_MAX_CACHED_PLANS = 4096
# An observable's options as `Updater._options` lists them, after its name and identity.
_OPTIONS = operator.attrgetter(
    "update_interval", "delay", "buffer_size", "aggregator", "corruptor", "array_spec"
)


class _DueEntry(NamedTuple):
    """How `Updater.update` takes one sample of an observable: `insert(time, delay,
    sample())`; `name` is the observable's, for error messages."""

    insert: Callable
    sample: Callable
    delay: int
    name: str


class _ResetInputs(NamedTuple):
    """What the last `Updater.reset` was given, and the observables' options then."""

    physics: object
    data: object
    random_state: object
    options: list


class _SubStepPlan(NamedTuple):
    """What `Updater.update` does at one sub-step where observables are due.

    `fills` write samples straight into buffers (gathers and writers); `entries` sample the
    other due observables. `all_entries` holds every due observable's entry, in observable
    order: it replaces both while the physics is dirty, since direct sampling reads memory
    that only a `forward()` brings up to date.
    """

    fills: tuple[Callable, ...]
    entries: tuple[_DueEntry, ...]
    all_entries: tuple[_DueEntry, ...]


class _ControlStepPlan(NamedTuple):
    """The samples of one control step: the sub-steps (offsets from its start) after which
    observables are due, in increasing order, and each one's `_SubStepPlan`."""

    sample_steps: tuple[int, ...]
    sub_steps: tuple[_SubStepPlan, ...]


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
        "_sample_spec",
        "is_gathered",
        "writer",
    )

    def __init__(self, name, observable, physics, random_state, steps_per_control, strip, pad):
        self.name = name
        self.observable = observable
        shape, dtype = self._bind(physics, random_state)
        self.buffer_size = observable.buffer_size or DEFAULT_BUFFER_SIZE
        self.aggregator = observable.aggregator
        self._new_buffer(shape, dtype, strip, pad)
        self._offsets_by_phase = {}
        if self.is_stochastic:
            self._period = None
        else:
            self._period = math.lcm(self.update_interval, steps_per_control)

    def _bind(self, physics, random_state) -> tuple:
        """Binds the observable's callable and options; returns one sample's (shape, dtype)."""
        observable = self.observable
        self.observation_callable = observable.observation_callable(physics, random_state)
        self.update_interval, self._draw_interval = self._bind_option(
            observable.update_interval, DEFAULT_UPDATE_INTERVAL, random_state
        )
        self.delay, self._draw_delay = self._bind_option(
            observable.delay, DEFAULT_DELAY, random_state
        )
        spec = observable.array_spec
        if spec is None:
            # One sample gives the shape and dtype (the caller mutes physics errors).
            value = np.asarray(self.observation_callable())
            return value.shape, value.dtype
        return spec.shape, spec.dtype

    def _new_buffer(self, shape, dtype, strip, pad) -> None:
        """An empty buffer for samples of `shape` and `dtype`, and a new sampling schedule."""
        self.writer = None
        self.is_gathered = False
        if self.buffer_size == 1 and self._draw_delay is None and self.delay == 0:
            self.buffer = obs_buffer.LatestSampleBuffer(shape, dtype, strip)
        else:
            self.buffer = obs_buffer.Buffer(self.buffer_size, shape, dtype, pad, strip)
        self._sample_spec = (shape, np.dtype(dtype))
        self._schedule = []
        self._last_scheduled = 0

    def rebind(self, physics, random_state, strip, pad) -> bool:
        """Starts a new episode with the same options: makes the calls into the observable
        that construction makes, in its order, and empties the buffer.

        Returns whether the buffer is the same object, emptied: False when a sample's shape
        or dtype changed, the buffer then being new (its direct sampling and reader are to be
        set up again). A kept `LatestSampleBuffer` is not cleared: the reset's first sample
        overwrites it.
        """
        shape, dtype = self._bind(physics, random_state)
        if (shape, np.dtype(dtype)) != self._sample_spec:
            self._new_buffer(shape, dtype, strip, pad)
            return False
        self._schedule = []
        self._last_scheduled = 0
        if not self.keeps_one_sample:
            self.buffer.clear()
        return True

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

    @property
    def keeps_one_sample(self) -> bool:
        """Whether the buffer holds one undelayed sample, which can be written in place."""
        return isinstance(self.buffer, obs_buffer.LatestSampleBuffer)

    def direct_sampling_key(self) -> tuple:
        """What the direct sampling of this observable depends on, besides the physics."""
        interval = None if self.is_stochastic else self.update_interval
        observable = self.observable
        buffer = self.buffer
        return observable, interval, observable.corruptor is None, buffer.shape, buffer.dtype

    def due_entry(self, delay) -> _DueEntry:
        """What `Updater.update` needs to take one sample with `delay`."""
        return _DueEntry(self.buffer.insert, self.observation_callable, delay, self.name)

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
        """The observation's spec: the observable's own, renamed and buffered, if it has one.

        Without an aggregator, an observable's `array_spec` (of whatever `specs.Array`
        subclass) is kept, with this observation's name and buffered shape. With an
        aggregator the spec is that of the aggregated value, bounded only when the
        aggregator `preserves_bounds`.
        """
        bounds = None
        array_spec = self.observable.array_spec
        if array_spec is not None and self.aggregator is None:
            return array_spec.replace(name=self.name, shape=self.buffer.shape)
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


def _simulation_data(physics):
    """The MuJoCo data a physics wraps now (a reload replaces it), or None."""
    return getattr(getattr(physics, "data", None), "ptr", None)


def _live_source(enabled, physics):
    """(array, indices) of an observable whose value lives in `array[indices]`, or None.

    Only observables with a fixed update interval and a source that matches their buffer
    (a 1-D array of the buffer's dtype, indices of the sample's shape, in range) qualify.
    """
    if enabled.is_stochastic:
        return None
    source = enabled.observable.live_source(physics)
    if source is None:
        return None
    array, indices = source
    indices = np.asarray(indices)
    buffer = enabled.buffer
    sample_shape = buffer.sample_view.shape
    if not (
        isinstance(array, np.ndarray)
        and array.ndim == 1
        and array.dtype == buffer.dtype
        and indices.shape == sample_shape
        and indices.dtype.kind in "iu"
    ):
        return None
    if indices.size:
        lowest, highest = np.minimum.reduce(indices, None), np.maximum.reduce(indices, None)
        if lowest < 0 or highest >= array.size:
            return None
    return array, indices


class _Gather:
    """Observables sampled together by one `take` from an array into their buffers.

    Their values live in that array (see `Observable.live_source`) and they share an
    update interval, so they are due at the same sub-steps. `take()` copies all of their
    current values, in one call, into one block that holds their buffers' storage.
    `leader_position` is the position of one of them among the directly sampled ones.
    """

    __slots__ = ("take", "leader_position")

    def __init__(self, array: np.ndarray, members: list, buffers: list, strip: bool):
        block = np.empty(sum(indices.size for _, _, indices in members), array.dtype)
        start = 0
        for position, enabled, indices in members:
            end = start + indices.size
            storage = block[start:end].reshape(enabled.buffer.shape)
            buffers[position] = obs_buffer.LatestSampleBuffer(
                indices.shape, array.dtype, strip, storage
            )
            start = end
        indices = np.concatenate([indices.ravel() for _, _, indices in members])
        # mode='clip' writes straight into `block`; the indices are known to be in range.
        self.take = functools.partial(array.take, indices, 0, block, "clip")
        self.leader_position = members[0][0]


class _DirectSampling:
    """How the observables that keep one undelayed sample are sampled straight into their
    buffers: gathers of live sources (one per source array and update interval) and
    writers (see `Observable.observation_writer`).

    Built for a physics and the observables' current options; `reset` reuses it while
    those stay the same, with the same buffers (each episode's first sample refills them).
    """

    def __init__(self, physics, eligible: list, strip: bool):
        self.physics = physics
        self.data = _simulation_data(physics)
        self.keys = [enabled.direct_sampling_key() for enabled in eligible]
        self.buffers = [enabled.buffer for enabled in eligible]
        self.writers = [None] * len(eligible)
        groups = {}
        for position, enabled in enumerate(eligible):
            source = _live_source(enabled, physics)
            if source is not None:
                array, indices = source
                key = array.__array_interface__["data"][0], array.dtype.str, array.size
                group = groups.setdefault((key, enabled.update_interval), (array, []))
                group[1].append((position, enabled, indices))
        self.gathers = [
            _Gather(array, members, self.buffers, strip) for array, members in groups.values()
        ]
        self.gathered = {position for _, members in groups.values() for position, _, _ in members}
        for position, enabled in enumerate(eligible):
            if position not in self.gathered:
                buffer = self.buffers[position]
                writer = enabled.observable.observation_writer(physics, buffer.sample_view)
                self.writers[position] = writer

    def matches(self, physics, eligible: list) -> bool:
        if physics is not self.physics or _simulation_data(physics) is not self.data:
            return False
        if len(eligible) != len(self.keys):
            return False
        for enabled, (observable, *options) in zip(eligible, self.keys):
            key = enabled.direct_sampling_key()
            if key[0] is not observable or list(key[1:]) != options:
                return False
        return True

    def apply(self, eligible: list) -> list:
        """Gives `eligible` their buffers and writers; returns the gathers' (take, leader)."""
        for position, enabled in enumerate(eligible):
            enabled.buffer = self.buffers[position]
            enabled.writer = self.writers[position]
            enabled.is_gathered = position in self.gathered
        return [(gather.take, eligible[gather.leader_position]) for gather in self.gathers]


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
    observations are identical to calling `update()` after every sub-step. Observables that
    keep one undelayed sample are sampled straight into their buffers, unless the physics
    `is_dirty`: those with a live source (see `Observable.live_source`) by one gather per
    MuJoCo array they read, those with a writer (`Observable.observation_writer`) by it.
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
        self._gathers = ()
        self._direct_sampling = None
        self._physics = None
        self._last_reset = None
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
        """Binds the enabled observables to `physics` and takes the first sample of each.

        When the physics, the random state and every observable's options are those of the
        last reset, the observables bound then are bound again (the same calls into them,
        in the same order) and keep their buffers' storage and direct sampling, emptied.
        """
        options = self._options()
        if self._same_inputs(physics, random_state, options):
            rebound = True
            with physics.suppress_physics_errors():
                for enabled in self._enabled_list:
                    rebound &= enabled.rebind(
                        physics,
                        random_state,
                        self._strip_singleton_buffer_dim,
                        self._pad_with_initial_value,
                    )
            if rebound:
                # The same buffers, emptied: the readers of the last reset read them.
                self._start_episode()
                return
            structure = self._enabled_structure
        else:
            structure = self._enable(physics, random_state)
        self._finish_reset(physics, random_state, structure, options)

    def _same_inputs(self, physics, random_state, options) -> bool:
        """Whether the last reset had this physics (and data), random state and options."""
        last = self._last_reset
        return (
            last is not None
            and physics is last.physics
            and _simulation_data(physics) is last.data
            and random_state is last.random_state
            and options == last.options
        )

    def _enabled_dicts(self) -> list:
        structure = self._enabled_structure
        return list(structure) if self._is_nested else [structure]

    def _enable(self, physics, random_state):
        """The structure of the observables, the enabled ones bound to `physics`."""

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
                return type(self._observables)(enable(d) for d in self._observables)
            return enable(self._observables)

    def _finish_reset(self, physics, random_state, structure, options) -> None:
        """Sets up sampling for the bound `structure` and takes the first samples."""
        self._enabled_structure = structure
        dicts = self._enabled_dicts()
        self._enabled_list = [enabled for d in dicts for enabled in d.values()]
        # Direct sampling reads memory that is only up to date while the physics has no
        # pending forward(), which a physics without `is_dirty` cannot tell.
        self._gathers = []
        if hasattr(physics, "is_dirty"):
            eligible = [enabled for enabled in self._enabled_list if enabled.keeps_one_sample]
            layout = self._direct_sampling
            if layout is None or not layout.matches(physics, eligible):
                layout = _DirectSampling(physics, eligible, self._strip_singleton_buffer_dim)
                self._direct_sampling = layout
            self._gathers = layout.apply(eligible)
        self._physics = physics
        self._last_reset = _ResetInputs(physics, _simulation_data(physics), random_state, options)
        self._readers = [self._reader(d) for d in dicts]
        if any(enabled.is_stochastic for enabled in self._enabled_list):
            self._plan_period = None
        else:
            self._plan_period = math.lcm(
                self._steps, *(enabled.update_interval for enabled in self._enabled_list)
            )
        self._start_episode()

    def _start_episode(self) -> None:
        """Restarts the step count and the plan, and takes each observable's first sample."""
        self._step_counter = 0
        self._reset_plan()
        for enabled in self._enabled_list:
            enabled.sample(0, enabled.next_delay())

    def reset_draws(self, physics, random_state) -> None:
        """Makes the calls into the observables that `reset(physics, random_state)` makes, in
        its order (so the same draws from `random_state`), keeping what the last `reset` built.

        For a reset that another `reset` follows before anything steps or reads an
        observation: `composer.Environment` resets the updater after every model update, as
        dm_control resets the one it builds at every compile, and again once the episode
        is initialised. Each enabled observable's `observation_callable(physics,
        random_state)` is built, called once for its shape when it has no `array_spec`, and
        then, observable after observable, its delay is drawn (when a callable) and it is
        called once more: the reset's calls, with the same values read. Nothing is bound or
        buffered, so the specs stay those of the last `reset`. A full `reset` is done
        instead when there was none yet, or the physics, the random state or any
        observable's options (enabled, update interval, delay, buffer size, aggregator,
        corruptor, spec) differ from the last one's, since the specs may then differ.
        """
        options = self._options()
        if not self._same_inputs(physics, random_state, options):
            self.reset(physics, random_state)
            return
        calls = []
        with physics.suppress_physics_errors():
            for name, observable, _, delay, _, _, _, array_spec in options:
                sample = observable.observation_callable(physics, random_state)
                _, draw_delay = _EnabledObservable._bind_option(delay, DEFAULT_DELAY, random_state)
                if array_spec is None:
                    np.asarray(sample())
                calls.append((name, sample, draw_delay))
        for name, sample, draw_delay in calls:
            if draw_delay is not None:
                _as_count(name, "delay", draw_delay(), 0)
            sample()

    def _options(self) -> list:
        """The name, identity and options of each enabled observable, in order: with the
        physics and the random state, what the structure `reset` builds depends on, besides
        sampled shapes."""
        return [
            (name, observable) + _OPTIONS(observable)
            for d in (self._observables if self._is_nested else [self._observables])
            for name, observable in d.items()
            if observable.enabled
        ]

    @staticmethod
    def _reader(enabled_dict) -> tuple:
        """(dict type, names, read functions or None, storages or None) for one dict: the
        storages of size-1 undelayed buffers are copied directly when all of them are such."""
        enabled = list(enabled_dict.values())
        if all(
            isinstance(e.buffer, obs_buffer.LatestSampleBuffer) and e.aggregator is None
            for e in enabled
        ):
            return type(enabled_dict), list(enabled_dict), None, [e.buffer.storage for e in enabled]
        return type(enabled_dict), list(enabled_dict), [e.read_function() for e in enabled], None

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
        if self._enabled_structure is None:
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
        self._sample_steps, self._due = plan.sample_steps, plan.sub_steps
        self._due_index = 0
        self._next_due = self._sample_steps[0] if self._sample_steps else _NEVER

    def _build_plan(self, start) -> _ControlStepPlan:
        """Plans the control step starting `start` sub-steps into the episode."""
        due = {}
        for enabled in self._enabled_list:
            for offset, delay in enabled.plan(start, self._steps):
                due.setdefault(offset, []).append((enabled, enabled.due_entry(delay)))
        sample_steps = tuple(sorted(due))
        plan = []
        for offset in sample_steps:
            due_now = {id(enabled) for enabled, _ in due[offset]}
            fills = [take for take, leader in self._gathers if id(leader) in due_now]
            fills += [e.writer for e, _ in due[offset] if e.writer is not None]
            entries = tuple(
                entry
                for enabled, entry in due[offset]
                if not enabled.is_gathered and enabled.writer is None
            )
            all_entries = tuple(entry for _, entry in due[offset])
            plan.append(_SubStepPlan(tuple(fills), entries, all_entries))
        return _ControlStepPlan(sample_steps, tuple(plan))

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
        fills, entries, all_entries = self._due[index]
        if fills:
            if self._physics.is_dirty:
                # Bindings run forward() on the first read of a derived quantity: sample
                # through them, in order, as without fills.
                entries, fills = all_entries, ()
            for fill in fills:
                fill()
        try:
            for insert, sample, delay, name in entries:  # noqa: B007 (see except)
                insert(counter, delay, sample())
        except obs_buffer.IncompatibleSampleError as exc:
            raise ValueError(f"observable {name!r}: {exc}") from None
        index += 1
        self._due_index = index
        self._next_due = self._sample_steps[index] if index < len(self._sample_steps) else _NEVER

    def finish_control_step(self) -> None:
        """Counts the rest of the planned control step as passed, sampling everything still
        due in it from the current physics state.

        For a control step cut short, e.g. by a `PhysicsError`: the observation then shows
        the state the physics was left in, as after a complete step.
        """
        if self._enabled_structure is None:
            self._check_reset()
        while self._next_due is not _NEVER:
            self.update(self._next_due - (self._step_counter - self._plan_start))
        remaining = self._steps - (self._step_counter - self._plan_start)
        if remaining > 0:
            self.update(remaining)

    def get_observation(self, out=None):
        """Returns the current observations, in the structure of `observables`.

        Args:
          out: None for new arrays the caller owns; or arrays to write them into, which
            `output_problem` accepts (not checked here, on every call).

        Returns:
          New arrays, or `out` holding the observations.
        """
        if self._enabled_structure is None:
            self._check_reset()
        if out is not None:
            if not self._is_nested:
                self._write_dict(out, *self._readers[0])
            else:
                for part, reader in zip(out, self._readers):
                    self._write_dict(part, *reader)
            return out
        if not self._is_nested:
            return self._observation_dict(*self._readers[0])
        return type(self._enabled_structure)(
            self._observation_dict(*reader) for reader in self._readers
        )

    def _observation_dict(self, dict_type, names, reads, storages):
        # Item by item: an OrderedDict fills faster this way than from an iterable of pairs.
        observation = dict_type()
        if reads is None:
            for name, storage in zip(names, storages):
                observation[name] = storage.copy()
        else:
            now = self._step_counter
            for name, read in zip(names, reads):
                observation[name] = read(now)
        return observation

    def _write_dict(self, out, dict_type, names, reads, storages):
        if reads is None:
            for name, storage in zip(names, storages):
                out[name][...] = storage
        else:
            now = self._step_counter
            for name, read in zip(names, reads):
                out[name][...] = read(now)

    def output_problem(self, out) -> str | None:
        """Why `get_observation(out)` cannot write into `out`, or None when it can.

        `out` must hold, in the structure of `observation_spec()` (the same keys, in any
        order), a writeable NumPy array of each spec's shape and dtype.
        """
        spec = self.observation_spec()
        if self._is_nested:
            if not isinstance(out, (list, tuple)) or len(out) != len(spec):
                return f"expected a sequence of {len(spec)} dicts of arrays, got {out!r:.80}"
            pairs = list(zip(spec, out))
        else:
            pairs = [(spec, out)]
        for spec_dict, arrays in pairs:
            if not isinstance(arrays, Mapping) or set(arrays) != set(spec_dict):
                keys = sorted(arrays) if isinstance(arrays, Mapping) else arrays
                return f"expected a dict with the keys {sorted(spec_dict)}, got {keys!r:.200}"
            for name, array_spec in spec_dict.items():
                problem = argument_checks.writeable_array_problem(
                    arrays[name], array_spec.shape, array_spec.dtype
                )
                if problem is not None:
                    return f"{name!r}: {problem}"
        return None
