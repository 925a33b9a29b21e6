"""Draws the docs' diagrams from real runs: `python -m tools.docs.figures OUT` writes two SVGs.

The files are OUT/lifecycle.svg and OUT/observables_timeline.svg.

The lifecycle diagram is the order in which a real `composer.Environment` calls a traced
task's and entity's hooks; the timeline is what a real observation updater delivered. Both
are recorded when the docs are built, so the pictures cannot drift from the code.
"""

import dataclasses
import html
import pathlib
import sys

import numpy as np

import composer
from composer.observation import observable

_PHYSICS_STEP = "physics step (mj_step)"
_OBSERVATION = "observables sampled"


class _TracedEntity(composer.Entity):
    """An entity (a free box) whose hooks append their names to a shared log."""

    def _build(self, log: list, physics_time: list):
        self._log = log
        self._physics_time = physics_time
        self._model = composer.Arena().mjcf_model
        self._model.model = "entity"
        self._model.worldbody.add("geom", type="box", size=[0.05] * 3)

    @property
    def mjcf_model(self):
        return self._model

    def _record(self, name: str, physics=None) -> None:
        _record(self._log, self._physics_time, f"entity.{name}", physics)

    def initialize_episode_mjcf(self, random_state):
        self._record("initialize_episode_mjcf")

    def after_compile(self, physics, random_state):
        self._record("after_compile", physics)

    def initialize_episode(self, physics, random_state):
        self._record("initialize_episode", physics)

    def before_step(self, physics, random_state):
        self._record("before_step", physics)

    def before_substep(self, physics, random_state):
        self._record("before_substep", physics)

    def after_substep(self, physics, random_state):
        self._record("after_substep", physics)

    def after_step(self, physics, random_state):
        self._record("after_step", physics)


def _record(log: list, physics_time: list, name: str, physics) -> None:
    """Appends `name`, preceded by a physics step whenever simulated time advanced."""
    if physics is not None:
        time = float(physics.data.time)
        if physics_time and time > physics_time[-1]:
            log.append(_PHYSICS_STEP)
        physics_time.append(time)
    log.append(name)


class _TracedTask(composer.Task):
    """A task with one entity whose every hook, reward and observable call is logged."""

    def __init__(self):
        self.log: list[str] = []
        self._time: list[float] = []
        self._arena = composer.Arena()
        self._entity = _TracedEntity(self.log, self._time)
        self._arena.add_free_entity(self._entity)
        self.set_timesteps(control_timestep=0.004, physics_timestep=0.002)
        sampled = observable.Generic(self._sample)
        sampled.enabled = True
        self._observables = {"time": sampled}

    def _sample(self, physics):
        _record(self.log, self._time, _OBSERVATION, physics)
        return np.array([physics.data.time])

    def _record(self, name: str, physics=None) -> None:
        _record(self.log, self._time, f"task.{name}", physics)

    @property
    def root_entity(self):
        return self._arena

    @property
    def task_observables(self):
        return self._observables

    def initialize_episode_mjcf(self, random_state):
        self._record("initialize_episode_mjcf")

    def after_compile(self, physics, random_state):
        self._record("after_compile", physics)

    def initialize_episode(self, physics, random_state):
        self._record("initialize_episode", physics)

    def before_step(self, physics, action, random_state):
        self._record("before_step", physics)

    def before_substep(self, physics, action, random_state):
        self._record("before_substep", physics)

    def after_substep(self, physics, random_state):
        self._record("after_substep", physics)

    def after_step(self, physics, random_state):
        self._record("after_step", physics)

    def get_reward(self, physics):
        self._record("get_reward", physics)
        return 0.0

    def get_discount(self, physics):
        self._record("get_discount", physics)
        return 1.0

    def should_terminate_episode(self, physics):
        self._record("should_terminate_episode", physics)
        return False


@dataclasses.dataclass(frozen=True)
class HookTrace:
    """The calls one `reset()` and one `step()` made, in order (two physics sub-steps)."""

    reset: tuple[str, ...]
    step: tuple[str, ...]
    n_sub_steps: int


def hook_trace() -> HookTrace:
    """Runs a traced task through a reset and two steps and returns the second step's calls.

    The second step is shown because the first one follows the reset directly; both make
    the same calls.
    """
    task = _TracedTask()
    env = composer.Environment(task, random_state=0)
    task.log.clear()
    env.reset()
    reset = _without_repeats(task.log)
    env.step(np.zeros(0))
    task.log.clear()
    env.step(np.zeros(0))
    return HookTrace(
        reset=reset,
        step=_without_repeats(task.log),
        n_sub_steps=task.physics_steps_per_control_step,
    )


def _without_repeats(calls: list[str]) -> tuple[str, ...]:
    """The calls with immediate repeats of the same call merged (a reset samples twice)."""
    return tuple(call for i, call in enumerate(calls) if i == 0 or calls[i - 1] != call)


_COLOURS = {
    "task": "#dbe4ff",
    "entity": "#d3f9d8",
    "physics": "#e9ecef",
    "observables": "#fff3bf",
}


def _colour(call: str) -> str:
    return _COLOURS.get(call.split(".")[0].split(" ")[0], "#f8f9fa")


def _text(
    x: float, y: float, text: str, *, size: int = 13, anchor: str = "middle", weight="normal"
):
    return (
        f'<text x="{x}" y="{y}" font-size="{size}" text-anchor="{anchor}" '
        f'font-weight="{weight}" font-family="monospace">{html.escape(text)}</text>'
    )


def _substep_span(calls: tuple[str, ...]) -> tuple[int, int]:
    """The indices [first, last] of the first sub-step's calls (from before_ to after_substep)."""
    first = next(i for i, call in enumerate(calls) if call.endswith("before_substep"))
    after = [i for i, call in enumerate(calls) if call.endswith("after_substep")]
    last = after[len(after) // 2 - 1] if len(after) > 1 else after[-1]
    # A sample right after the sub-step belongs to it.
    while last + 1 < len(calls) and calls[last + 1] == _OBSERVATION:
        last += 1
    return first, last


def lifecycle_svg(trace: HookTrace) -> str:
    """Returns an SVG of the reset and step call sequences side by side.

    The step column shows one sub-step's calls once, framed and marked as repeated
    `n_sub_steps` times.
    """
    first, last = _substep_span(trace.step)
    substep_length = last - first + 1
    step = trace.step[: last + 1] + trace.step[first + substep_length * trace.n_sub_steps :]
    box_w, box_h, gap, top = 250, 26, 12, 50
    columns = (("env.reset()", trace.reset, None), ("env.step(action)", step, (first, last)))
    rows = max(len(trace.reset), len(step))
    width, height = 2 * box_w + 190, top + rows * (box_h + gap) + 50
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}">',
        '<defs><marker id="arrow" markerWidth="8" markerHeight="8" refX="4" refY="4" '
        'orient="auto"><path d="M0,0 L8,4 L0,8 z" fill="#495057"/></marker></defs>',
        f'<rect width="{width}" height="{height}" fill="white"/>',
    ]
    for column, (title, calls, frame) in enumerate(columns):
        x = 20 + column * (box_w + 50)
        parts.append(_text(x + box_w / 2, 28, title, size=16, weight="bold"))
        for i, call in enumerate(calls):
            y = top + i * (box_h + gap)
            parts.append(
                f'<rect x="{x}" y="{y}" width="{box_w}" height="{box_h}" rx="6" '
                f'fill="{_colour(call)}" stroke="#495057"/>'
            )
            parts.append(_text(x + box_w / 2, y + 17, call))
            if i + 1 < len(calls):
                parts.append(
                    f'<line x1="{x + box_w / 2}" y1="{y + box_h}" x2="{x + box_w / 2}" '
                    f'y2="{y + box_h + gap - 2}" stroke="#495057" marker-end="url(#arrow)"/>'
                )
        if frame is not None:
            y0 = top + frame[0] * (box_h + gap) - 6
            y1 = top + frame[1] * (box_h + gap) + box_h + 6
            parts.append(
                f'<rect x="{x - 14}" y="{y0}" width="{box_w + 28}" height="{y1 - y0}" rx="8" '
                'fill="none" stroke="#e8590c" stroke-width="2" stroke-dasharray="6 4"/>'
            )
            parts.append(
                _text(x + box_w + 18, (y0 + y1) / 2, "× n_sub_steps", anchor="start", size=12)
            )
    legend_y = height - 24
    for i, (kind, colour) in enumerate(_COLOURS.items()):
        lx = 20 + i * 120
        parts.append(
            f'<rect x="{lx}" y="{legend_y - 13}" width="18" height="18" fill="{colour}" '
            'stroke="#495057"/>'
        )
        parts.append(_text(lx + 26, legend_y + 1, kind, anchor="start", size=12))
    parts.append("</svg>")
    return "\n".join(parts)


@dataclasses.dataclass(frozen=True)
class TimelineRow:
    """One observable configuration and what the agent saw after each control step.

    `samples` are the sub-step indices the observable was sampled at during the run;
    `observations[k]` is the observation after control step k (k = 0 is the reset), as
    the sub-step index each entry was sampled at (or their aggregate). `buffer_size` and
    `delay` are the observable's options.
    """

    label: str
    samples: tuple[int, ...]
    observations: tuple[tuple[float, ...], ...]
    buffer_size: int
    delay: int
    aggregator: str | None


_SUB_STEPS = 5
_CONTROL_STEPS = 3
TIMELINE_CONFIGURATIONS = {
    "default (interval 1, buffer 1)": {},
    "update_interval=2, buffer_size=3": {"update_interval": 2, "buffer_size": 3},
    "update_interval=2, buffer_size=3, delay=3": {
        "update_interval": 2,
        "buffer_size": 3,
        "delay": 3,
    },
    "buffer_size=5, aggregator='mean'": {"buffer_size": 5, "aggregator": "mean"},
}


class _SubStepTask(composer.Task):
    """A task whose one observable reads the index of the current physics sub-step."""

    def __init__(self, options: dict):
        self._arena = composer.Arena()
        self.set_timesteps(control_timestep=0.002 * _SUB_STEPS, physics_timestep=0.002)
        self.samples: list[int] = []
        sub_step = observable.Generic(self._sub_step, **options)
        sub_step.enabled = True
        self._observables = {"sub_step": sub_step}

    def _sub_step(self, physics):
        index = round(physics.data.time / 0.002)
        self.samples.append(index)
        return np.array([index], float)

    @property
    def root_entity(self):
        return self._arena

    @property
    def task_observables(self):
        return self._observables

    def get_reward(self, physics):
        return 0.0


def observation_timeline() -> list[TimelineRow]:
    """Runs each of `TIMELINE_CONFIGURATIONS` for three control steps of five sub-steps."""
    rows = []
    for label, options in TIMELINE_CONFIGURATIONS.items():
        task = _SubStepTask(options)
        env = composer.Environment(task, random_state=0)
        observations = [env.reset().observation["sub_step"]]
        observations += [env.step(np.zeros(0)).observation["sub_step"] for _ in range(3)]
        rows.append(
            TimelineRow(
                label=label,
                samples=tuple(sorted(set(task.samples))),
                observations=tuple(tuple(np.ravel(o).tolist()) for o in observations),
                buffer_size=options.get("buffer_size", 1),
                delay=options.get("delay", 0),
                aggregator=options.get("aggregator"),
            )
        )
    return rows


def timeline_svg(rows: list[TimelineRow]) -> str:
    """Returns an SVG: per configuration, the sub-steps sampled and those the agent sees.

    Sub-steps run left to right; control-step boundaries are vertical lines. A filled
    dot is a sub-step that was sampled; a ringed one is in the observation returned at the
    end of control step 2 (sub-step 10).
    """
    total = _SUB_STEPS * _CONTROL_STEPS
    left, step_w, row_h, top = 320, 22, 62, 60
    width, height = left + total * step_w + 20, top + len(rows) * row_h + 70
    shown_step = 2
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}">',
        f'<rect width="{width}" height="{height}" fill="white"/>',
        _text(left - 10, 24, "physics sub-step →", anchor="end", size=12),
    ]
    for k in range(total + 1):
        x = left + k * step_w
        parts.append(_text(x, 24, str(k), size=11))
        if k % _SUB_STEPS == 0:
            parts.append(
                f'<line x1="{x}" y1="32" x2="{x}" y2="{height - 60}" stroke="#868e96" '
                'stroke-dasharray="4 3"/>'
            )
            label = "reset" if k == 0 else f"step {k // _SUB_STEPS}"
            parts.append(_text(x, height - 42, label, size=11))
    for r, row in enumerate(rows):
        y = top + r * row_h + 16
        parts.append(_text(10, y + 5, row.label, anchor="start", size=12))
        seen = row.observations[shown_step]
        aggregated = row.aggregator is not None
        # What the aggregate reduced: the newest `buffer_size` samples that had arrived.
        arrived = [s for s in row.samples if s + row.delay <= shown_step * _SUB_STEPS]
        in_buffer = set(arrived[-row.buffer_size :]) if aggregated else set(seen)
        parts.append(
            _text(
                left - 24,
                y + 24,
                f"obs after step {shown_step}: "
                + ", ".join(f"{v:g}" for v in seen)
                + (f" ({row.aggregator} of the ringed)" if aggregated else ""),
                anchor="end",
                size=11,
            )
        )
        for k in range(total + 1):
            x = left + k * step_w
            sampled = k in row.samples
            parts.append(
                f'<circle cx="{x}" cy="{y}" r="6" fill="{"#1c7ed6" if sampled else "white"}" '
                'stroke="#1c7ed6"/>'
            )
            if sampled and k in in_buffer:
                parts.append(
                    f'<circle cx="{x}" cy="{y}" r="10" fill="none" stroke="#e8590c" '
                    'stroke-width="2.5"/>'
                )
    legend_y = height - 14
    parts += [
        f'<circle cx="16" cy="{legend_y - 4}" r="6" fill="#1c7ed6" stroke="#1c7ed6"/>',
        _text(28, legend_y, "sampled", anchor="start", size=12),
        f'<circle cx="116" cy="{legend_y - 4}" r="6" fill="white" stroke="#1c7ed6"/>',
        _text(128, legend_y, "not sampled", anchor="start", size=12),
        f'<circle cx="246" cy="{legend_y - 4}" r="10" fill="none" stroke="#e8590c" '
        'stroke-width="2.5"/>',
        _text(
            262,
            legend_y,
            f"in the observation returned by step {shown_step}",
            anchor="start",
            size=12,
        ),
        "</svg>",
    ]
    return "\n".join(parts)


def main() -> None:
    out = pathlib.Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    (out / "lifecycle.svg").write_text(lifecycle_svg(hook_trace()))
    (out / "observables_timeline.svg").write_text(timeline_svg(observation_timeline()))


if __name__ == "__main__":
    main()
