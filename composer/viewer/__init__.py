"""Interactive viewer: an environment in MuJoCo's passive viewer, acted on in real time.

`launch` takes dm_control's arguments (`launch(environment_loader, policy=None,
title="Explorer", width=1024, height=768)`, served as `dm_control.viewer` by
`composer.dm_control_compat`) for a `composer.Environment`, a Control Suite environment or
any dm_env environment whose `physics` has `model.ptr` / `data.ptr` (the raw
`mujoco.MjModel` / `mujoco.MjData`). It opens `mujoco.viewer.launch_passive` on that
physics and steps the environment itself, sleeping so that each control step lasts
`control_timestep / speed` seconds of wall-clock time (when stepping is slower than that,
it runs as fast as it can).

Keys, read through launch_passive's `key_callback`:

| key | action |
|---|---|
| space | pause / resume |
| right arrow | one step while paused |
| backspace | start a new episode |
| `+` / `-` | double / halve the speed (1/16x to 16x) |

The step in the episode, last reward, episode return and speed are drawn in the window's
top-left corner with `Handle.set_texts`. MuJoCo releases whose viewer lacks
`set_texts` get the same line logged (absl `logging.info`) at most once a second instead.

MuJoCo's viewer runs its own key handling as well; in particular its backspace resets the
MjData, which our reset then overwrites with the task's initial state.

Unlike dm_control's viewer, this one starts running rather than paused, and backspace resets
the environment instead of calling the loader again. The window's title and size are set
through X11 (`composer._x11_window`); elsewhere MuJoCo's own are kept, with a warning.

Needs a display and GLFW (the `glfw` package comes with `mujoco`); on a headless
machine run it under Xvfb. Closing the window ends `launch`.

The submodules `gui`, `renderer` and `viewer` are dm_control compatibility, not this
project's API: the parts of dm_control's viewer package that code written for it (MoMa's
rendering observer) uses, served under their dm_control names.
"""

from __future__ import annotations

import atexit
import math
import threading
import time
import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import glfw
import mujoco
import mujoco.viewer
import numpy as np
from absl import logging

from composer import _x11_window
from composer.episode_tally import EpisodeTally, Policy
from composer.utils import argument_checks

if TYPE_CHECKING:
    import dm_env

#: Chooses the action for the next step from the last TimeStep.
#: Makes the environment to show; called once, with no arguments.
EnvironmentLoader = Callable[[], "dm_env.Environment"]

MIN_SPEED = 1 / 16
MAX_SPEED = 16.0
# How often the window is refreshed while paused, in seconds.
_PAUSED_REFRESH = 1 / 60
# Further behind real time than this, the clock restarts instead of catching up.
_MAX_LAG = 0.1


class ViewerStatus(NamedTuple):
    """What the viewer shows after a refresh; `launch` returns the last one."""

    steps: int
    episodes: int
    episode_step: int
    reward: float | None
    episode_return: float
    speed: float
    paused: bool


class Controls:
    """Key presses (from the viewer's render thread) turned into requests for the loop."""

    def __init__(self, speed: float = 1.0):
        self._lock = threading.Lock()
        self.paused = False
        self.speed = _speed(speed)
        self._single_steps = 0
        self._reset = False

    def on_key(self, keycode: int) -> None:
        """Handles one GLFW key code; unknown keys are ignored."""
        with self._lock:
            if keycode == glfw.KEY_SPACE:
                self.paused = not self.paused
            elif keycode == glfw.KEY_RIGHT and self.paused:
                self._single_steps += 1
            elif keycode == glfw.KEY_BACKSPACE:
                self._reset = True
            elif keycode in (glfw.KEY_EQUAL, glfw.KEY_KP_ADD):
                self.speed = min(self.speed * 2, MAX_SPEED)
            elif keycode in (glfw.KEY_MINUS, glfw.KEY_KP_SUBTRACT):
                self.speed = max(self.speed / 2, MIN_SPEED)

    def take_reset(self) -> bool:
        """True once per backspace press."""
        with self._lock:
            requested, self._reset = self._reset, False
            return requested

    def take_step(self) -> bool:
        """True if the environment should step now: running, or a single step is pending."""
        with self._lock:
            if not self.paused:
                return True
            if self._single_steps:
                self._single_steps -= 1
                return True
            return False


def _speed(speed) -> float:
    return argument_checks.number(at_least=MIN_SPEED, at_most=MAX_SPEED, speed=speed)


class _WindowLook(NamedTuple):
    title: str
    width: int
    height: int


class _Window(NamedTuple):
    handle: mujoco.viewer.Handle
    thread: threading.Thread
    data: mujoco.MjData


def _check_display() -> None:
    """Raises RuntimeError if GLFW cannot start here; MuJoCo's viewer would instead end the
    process (its C error handler exits) when it cannot initialise GLFW."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        started = glfw.init()
    if not started:
        reasons = "; ".join(str(warning.message) for warning in caught) or "no reason given"
        raise RuntimeError(
            f"the viewer window cannot open: GLFW could not initialise ({reasons}). It needs "
            "a display: on a headless machine run under Xvfb (xvfb-run python ...)"
        )


def _open_window(physics, controls: Controls, show_ui: bool, look: _WindowLook) -> _Window:
    _check_display()
    # launch_passive runs the window in a thread it does not hand out; it is the one thread
    # it adds, and joining it after close() lets GLFW tear down before the process exits.
    before = set(threading.enumerate())
    data = physics.data.ptr
    handle = mujoco.viewer.launch_passive(
        physics.model.ptr,
        data,
        key_callback=controls.on_key,
        show_left_ui=show_ui,
        show_right_ui=show_ui,
    )
    (thread,) = [t for t in threading.enumerate() if t not in before]
    try:
        _x11_window.retitle_and_resize(*look)
    except OSError as error:
        logging.warning(
            "viewer: the window keeps MuJoCo's title and size (title=%r, width=%d, height=%d "
            "not applied): %s",
            *look,
            error,
        )
    return _Window(handle, thread, data)


def _close_window(window: _Window) -> None:
    window.handle.close()
    window.thread.join()


class PassiveWindow:
    """A viewer window that shows a physics stepped by someone else (`launch` steps its own).

    `handle_for(physics)` opens the window on its first call, and again on a new physics
    (after a recompile changed the model's structure); the caller draws with
    `handle_for(physics).sync()`. `close()` closes the window and joins its thread.

    One window per process: MuJoCo's passive viewer crashes the process (on Linux, a
    segmentation fault) when two run at once, each with its own GLFW thread. Opening a
    `PassiveWindow` therefore closes the one open before it, which reopens at its next
    `handle_for` (so two windows drawn in turn keep swapping). A window left open is
    closed when the interpreter exits (for the same reason).

    Args:
      title: the window's title.
      width: the window's width in screen pixels.
      height: the window's height in screen pixels.
      controls: the `Controls` its keys go to (a fresh one by default).
      show_ui: show MuJoCo's left and right settings panels.

    Raises:
      ValueError: naming `title`, `width` or `height` when bad.
    """

    def __init__(
        self,
        *,
        title: str = "Explorer",
        width: int = 1024,
        height: int = 768,
        controls: Controls | None = None,
        show_ui: bool = False,
    ):
        self._look = _window_look(title, width, height)
        self._controls = Controls() if controls is None else controls
        self._show_ui = show_ui
        self._window: _Window | None = None

    def handle_for(self, physics) -> mujoco.viewer.Handle:
        """The viewer handle showing `physics` (whose `data.ptr` is a `mujoco.MjData`)."""
        if self._window is not None and physics.data.ptr is not self._window.data:
            self.close()
        if self._window is None:
            global _open_passive_window
            if _open_passive_window is not None:
                _open_passive_window.close()
            self._window = _open_window(physics, self._controls, self._show_ui, self._look)
            _open_passive_window = self
            # A viewer thread still running when the interpreter exits crashes it.
            atexit.register(self.close)
        return self._window.handle

    def is_running(self) -> bool:
        """False once the window was closed (by the user or by `close`), or never opened."""
        return self._window is not None and self._window.handle.is_running()

    def close(self) -> None:
        """Closes the window, if open."""
        global _open_passive_window
        if self._window is not None:
            window, self._window = self._window, None
            atexit.unregister(self.close)
            _close_window(window)
        if _open_passive_window is self:
            _open_passive_window = None


# The one `PassiveWindow` whose window is open in this process, if any.
_open_passive_window: PassiveWindow | None = None


class _StatusDisplay:
    """Writes the status into the window, or logs it where the viewer cannot draw text."""

    def __init__(self):
        self._last_log = -math.inf

    def show(self, handle, status: ViewerStatus) -> None:
        reward = "-" if status.reward is None else f"{status.reward:.3f}"
        speed = f"{status.speed:g}x" + (" paused" if status.paused else "")
        labels = ("step", "reward", "return", "speed")
        values = (str(status.episode_step), reward, f"{status.episode_return:.3f}", speed)
        if hasattr(handle, "set_texts"):
            handle.set_texts(
                [
                    (None, mujoco.mjtGridPos.mjGRID_TOPLEFT, "\n".join(labels), "\n".join(values)),
                    (
                        None,
                        mujoco.mjtGridPos.mjGRID_BOTTOMLEFT,
                        "space\nright\nbackspace\n+ / -",
                        "pause\nstep (paused)\nreset\nspeed",
                    ),
                ]
            )
            return
        now = time.monotonic()
        if now - self._last_log >= 1.0:
            self._last_log = now
            logging.info(", ".join(f"{k} {v}" for k, v in zip(labels, values)))


def launch(
    environment_loader: dm_env.Environment | EnvironmentLoader,
    policy: Policy | None = None,
    title: str = "Explorer",
    width: int = 1024,
    height: int = 768,
    *,
    speed: float = 1.0,
    max_steps: int | None = None,
    on_refresh: Callable[[mujoco.viewer.Handle, ViewerStatus], None] | None = None,
    show_ui: bool = False,
) -> ViewerStatus:
    """Shows an environment in a window and runs `policy` on it in real time until closed.

    Resets the environment, then steps it with `policy`, starting a new episode after each
    LAST step or backspace. Blocks until the window is closed or `max_steps` steps were
    taken, then closes the window. The positional arguments are dm_control's
    `viewer.launch`'s.

    Args:
      environment_loader: the environment, or a callable taking no arguments that returns
        it (called once). A `composer.Environment`, a Control Suite environment, or any
        object with dm_env's `reset`, `step` and `action_spec` and a `physics` whose
        `model.ptr` / `data.ptr` are a `mujoco.MjModel` / `mujoco.MjData`.
      policy: a callable TimeStep -> action, or None for the action spec's resting action:
        the midpoint of a bounded range, the finite bound of a half-bounded one, else zero.
      title: the window's title.
      width: the window's width in screen pixels.
      height: the window's height in screen pixels.
      speed: initial playback speed, a multiple of real time in [1/16, 16]. One step lasts
        the environment's `control_timestep()` (its physics timestep if it has none).
      max_steps: stop after this many steps in all (None: only when the window closes).
      on_refresh: called with the viewer handle and the `ViewerStatus` after each window
        refresh, in the calling thread (for scripting and tests; calling
        `handle.close()` ends `launch` like closing the window).
      show_ui: show MuJoCo's left and right settings panels.

    Returns:
      The last `ViewerStatus` (total steps, episodes started, ...).

    Raises:
      ValueError: naming the argument for a bad `speed`, `max_steps`, `policy`, `title`,
        `width`, `height`, or for an `environment_loader` of None (as dm_control does).
      TypeError: `environment_loader` is neither an environment nor a callable returning
        one, or its environment's physics has no `model.ptr` / `data.ptr`.
      RuntimeError: calling `environment_loader` raised (the error is chained).
    """
    controls = Controls(speed)
    max_steps = argument_checks.integer(or_none=True, max_steps=max_steps)
    if policy is not None and not callable(policy):
        raise ValueError(f"policy: expected a callable TimeStep -> action or None, got {policy!r}")
    window = PassiveWindow(
        title=title, width=width, height=height, controls=controls, show_ui=show_ui
    )
    environment = _load_environment(environment_loader)
    display = _StatusDisplay()

    timestep = environment.reset()
    _check_physics(environment, environment_loader)
    control_timestep = _control_timestep(environment)
    default_action = _default_action(environment.action_spec())
    tally = EpisodeTally()
    tally.start_episode()
    status = ViewerStatus(0, 1, 0, None, 0.0, controls.speed, controls.paused)
    handle = window.handle_for(environment.physics)
    try:
        deadline = None
        while window.is_running() and (max_steps is None or tally.steps < max_steps):
            stepped = False
            if controls.take_reset() or timestep.last():
                timestep = environment.reset()
                default_action = _default_action(environment.action_spec())
                tally.start_episode()
                # A recompile that changed the model's structure reopens on the new Physics.
                handle = window.handle_for(environment.physics)
            elif controls.take_step():
                action = default_action if policy is None else policy(timestep)
                timestep = environment.step(action)
                tally.add_step(timestep.reward)
                stepped = True
            status = ViewerStatus(
                steps=tally.steps,
                episodes=tally.episodes,
                episode_step=tally.episode_steps,
                reward=tally.last_reward,
                episode_return=tally.episode_return,
                speed=controls.speed,
                paused=controls.paused,
            )
            display.show(handle, status)
            handle.sync()
            if on_refresh is not None:
                on_refresh(handle, status)
            if deadline is None:
                # Paced from the first frame shown: opening the window can take longer than
                # a step, and the steps after it would rush to catch up.
                deadline = time.perf_counter()
            period = control_timestep / controls.speed if stepped else _PAUSED_REFRESH
            deadline = _sleep_until(deadline + period)
    finally:
        window.close()
    return status


def _window_look(title, width, height) -> _WindowLook:
    if not isinstance(title, str):
        raise ValueError(f"title: expected a string, got {title!r}")
    width = argument_checks.integer(unit="screen pixels", width=width)
    height = argument_checks.integer(unit="screen pixels", height=height)
    return _WindowLook(title, width, height)


_EXPECTED_ENVIRONMENT = (
    "an environment (with reset, step, action_spec and a physics whose model.ptr and "
    "data.ptr are a mujoco.MjModel and a mujoco.MjData) or a callable returning one"
)


_ENVIRONMENT_METHODS = ("reset", "step", "action_spec")


def _is_environment(candidate) -> bool:
    # An environment class is a loader: calling it makes the environment.
    return not isinstance(candidate, type) and all(
        callable(getattr(candidate, name, None)) for name in _ENVIRONMENT_METHODS
    )


def _load_environment(environment_loader):
    """The environment itself, or what the loader returns when it is one."""
    if _is_environment(environment_loader):
        return environment_loader
    if environment_loader is None:
        # dm_control's launch documents a ValueError for None.
        raise ValueError(f"environment_loader: expected {_EXPECTED_ENVIRONMENT}, got None")
    if not callable(environment_loader):
        raise TypeError(
            f"environment_loader: expected {_EXPECTED_ENVIRONMENT}, got {environment_loader!r}"
        )
    try:
        environment = environment_loader()
    except Exception as error:
        raise RuntimeError(
            f"environment_loader: expected {_EXPECTED_ENVIRONMENT}; calling "
            f"{environment_loader!r} raised {type(error).__name__}: {error}"
        ) from error
    if not _is_environment(environment):
        raise TypeError(
            f"environment_loader: expected {_EXPECTED_ENVIRONMENT}, got {environment_loader!r}, "
            f"which returned {environment!r} (no reset, step and action_spec methods)"
        )
    return environment


def _check_physics(environment, environment_loader) -> None:
    """Raises TypeError unless the (reset) environment's physics exposes MuJoCo's structs."""
    physics = getattr(environment, "physics", None)
    model = getattr(getattr(physics, "model", None), "ptr", None)
    data = getattr(getattr(physics, "data", None), "ptr", None)
    if isinstance(model, mujoco.MjModel) and isinstance(data, mujoco.MjData):
        return
    if physics is None:
        problem = "has no physics"
    else:
        problem = f"has a physics {physics!r} whose model.ptr / data.ptr are {model!r} / {data!r}"
    source = "" if environment is environment_loader else f"{environment_loader!r} returned "
    raise TypeError(
        f"environment_loader: expected {_EXPECTED_ENVIRONMENT}, got {source}{environment!r}, "
        f"which {problem}"
    )


def _control_timestep(environment) -> float:
    control_timestep = getattr(environment, "control_timestep", None)
    if callable(control_timestep):
        return float(control_timestep())
    return float(environment.physics.model.ptr.opt.timestep)


def _default_action(spec):
    """The action taken without a policy: what a spec's bounds suggest, per element."""
    if isinstance(spec, (list, tuple)):
        return type(spec)(_default_action(s) for s in spec)
    if isinstance(spec, dict):
        return {key: _default_action(value) for key, value in spec.items()}
    action = np.zeros(spec.shape, spec.dtype)
    if not hasattr(spec, "minimum"):
        return action
    minimum = np.broadcast_to(np.asarray(spec.minimum, float), spec.shape)
    maximum = np.broadcast_to(np.asarray(spec.maximum, float), spec.shape)
    low, high = np.isfinite(minimum), np.isfinite(maximum)
    with np.errstate(invalid="ignore"):
        resting = np.where(
            low & high, (minimum + maximum) / 2, np.where(low, minimum, np.where(high, maximum, 0))
        )
    return resting.astype(spec.dtype)


def _sleep_until(deadline: float) -> float:
    """Sleeps until `deadline` (perf_counter seconds); returns the deadline to count from."""
    now = time.perf_counter()
    if now > deadline + _MAX_LAG:
        return now
    if deadline > now:
        time.sleep(deadline - now)
    return deadline
