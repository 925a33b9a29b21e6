"""Pixel observations of the batched suite, as dm_control's `suite.wrappers.pixels` adds them.

`Wrapper(env)` adds to every `reset` and `step` of a `SuiteBatchEnvironment` each world's
frame under `observation_key`, (num_envs, height, width, 3) uint8, rendered as dm_control's
`pixels.Wrapper` renders one environment's: the physics' own `render(**render_kwargs)` (its
defaults 240x320 from the free camera; pixel-based agents pass `height=84, width=84,
camera_id=0`), on a physics into which the world's model and data are copied first
(`mujoco.batch.Batch.get_model`, `Batch.get_data`). So each frame is the CPU environment's
frame of that world's state, bit for bit.

Every world renders on one worker thread, which makes and keeps the render physics and its
OpenGL context (a missing OpenGL fails at construction, naming `MUJOCO_GL`) and releases
them at `close`: one thread, as `composer.batch.gl_cameras` renders the composer batch's
cameras (two threads rendering at once crashed Mesa's software EGL).

Under the "same_step" autoreset mode, `final_observation` carries no pixels: the frames are
rendered after the step, when the ended worlds have started their next episode.
"""

from __future__ import annotations

import collections
import concurrent.futures
import copy
import weakref
from collections.abc import Mapping

import numpy as np
from dm_env import specs

from composer.batch import BatchTimeStep
from mujoco_physics import engine
from suite_batch.environment import SuiteBatchEnvironment

__all__ = ["Wrapper"]


class _Renderer:
    """The render thread's state: a physics of its own. Made, used and closed there."""

    def __init__(self, physics, render_kwargs: Mapping):
        self._batch = physics.batch
        self._varies = bool(physics.batched_model_fields)
        self.physics = engine.Physics.from_model(copy.copy(physics.mj_model))
        self._render_kwargs = dict(render_kwargs)
        try:
            self.first = self.physics.render(**self._render_kwargs)
        except RuntimeError as error:
            raise RuntimeError(f"suite_batch pixels: {error}") from error

    def render(self, frames: np.ndarray) -> None:
        batch, physics = self._batch, self.physics
        model, data = physics.model.ptr, physics.data.ptr
        for world in range(frames.shape[0]):
            if self._varies:
                batch.get_model(world, model)
                physics.model_changed_in_place()
            batch.get_data(world, data)
            frames[world] = physics.render(**self._render_kwargs)

    def close(self) -> None:
        self.physics.free()


def _close(executor: concurrent.futures.ThreadPoolExecutor, renderers: list) -> None:
    try:
        future = executor.submit(renderers[0].close) if renderers else None
    except RuntimeError:  # the interpreter is exiting; the context goes with the process
        future = None
    try:
        if future is not None:
            future.result()
    finally:
        renderers.clear()
        executor.shutdown(wait=True)


class Wrapper:
    """`env` with each world's rendered frame in its observations, as dm_control's
    `pixels.Wrapper` gives one environment's.

    Args:
      env: the `SuiteBatchEnvironment` (dict observations).
      pixels_only: keep only the frames (dm_control's default); False keeps the state
        observations too, the frames added last.
      render_kwargs: the keyword arguments of `Physics.render` (`height`, `width`,
        `camera_id`, ...); None: its defaults.
      observation_key: the frames' key.

    Returns (`reset`, `step`): the env's `BatchTimeStep`s with the observations above; the
    frames are a new array at every call.

    Raises:
      TypeError: for an `env` that is not a `SuiteBatchEnvironment`.
      ValueError: with `pixels_only=False`, for an `observation_key` the env's observations
        have already.
      RuntimeError: where no OpenGL context can be made (see `MUJOCO_GL`).
    """

    def __init__(
        self,
        env: SuiteBatchEnvironment,
        pixels_only: bool = True,
        render_kwargs: Mapping | None = None,
        observation_key: str = "pixels",
    ):
        if not isinstance(env, SuiteBatchEnvironment):
            raise TypeError(f"env: expected a suite_batch.SuiteBatchEnvironment, got {env!r}")
        wrapped = env.observation_spec()
        if not pixels_only and observation_key in wrapped:
            raise ValueError(
                f"observation_key: {observation_key!r} is already an observation of the env "
                f"({list(wrapped)})"
            )
        self._env = env
        self._pixels_only = bool(pixels_only)
        self._observation_key = observation_key
        self._executor = concurrent.futures.ThreadPoolExecutor(
            1, thread_name_prefix="suite_batch_pixels"
        )
        self._renderer: list[_Renderer] = []
        self._close = weakref.finalize(self, _close, self._executor, self._renderer)
        made = self._executor.submit(_Renderer, env.physics, render_kwargs or {})
        try:
            self._renderer.append(made.result())
        except BaseException:
            self._close()
            raise
        first = self._renderer[0].first
        self._frame_shape, self._frame_dtype = first.shape, first.dtype
        spec = collections.OrderedDict() if pixels_only else collections.OrderedDict(wrapped)
        spec[observation_key] = specs.Array(first.shape, first.dtype, name=observation_key)
        self._observation_spec = spec

    @property
    def env(self) -> SuiteBatchEnvironment:
        """The wrapped environment."""
        return self._env

    def observation_spec(self) -> collections.OrderedDict:
        """One world's observation specs (dm_control's wrapper's)."""
        return self._observation_spec

    def action_spec(self):
        """One world's action spec (the env's)."""
        return self._env.action_spec()

    def reset(self) -> BatchTimeStep:
        """The env's `reset`, with every world's frame."""
        return self._with_pixels(self._env.reset())

    def step(self, action) -> BatchTimeStep:
        """The env's `step`, with every world's frame."""
        return self._with_pixels(self._env.step(action))

    def render(self) -> np.ndarray:
        """Every world's frame of its current state, (num_envs, *frame shape).

        Raises:
          RuntimeError: after `close`.
        """
        if not self._renderer:
            raise RuntimeError("suite_batch.pixels.Wrapper.render: closed (close())")
        frames = np.empty((self._env.num_envs, *self._frame_shape), self._frame_dtype)
        self._executor.submit(self._renderer[0].render, frames).result()
        return frames

    def _with_pixels(self, time_step: BatchTimeStep) -> BatchTimeStep:
        observation = collections.OrderedDict(() if self._pixels_only else time_step.observation)
        observation[self._observation_key] = self.render()
        return time_step._replace(observation=observation)

    def close(self) -> None:
        """Releases the OpenGL context on the render thread, ends it, and closes the env."""
        try:
            self._close()
        finally:
            self._env.close()

    def __getattr__(self, name: str):
        return getattr(self._env, name)
