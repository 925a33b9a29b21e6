"""Camera observables of the CPU batch, rendered for every world by MuJoCo's OpenGL renderer.

`GLBatchCameras` renders the enabled camera observables (`MJCFCamera`) of a
`composer.batch.mujoco_batch.MujocoBatchPhysics` in every world, through the code a CPU
`composer.Environment` renders them with: each observable's own render function
(`observation_callable`, hence `Physics.render` and its per-size `mujoco.Renderer`) on a
`mujoco_physics.Physics` into which the world's model and data are copied first
(`mujoco.batch.Batch.get_model`, `Batch.get_data`: the world's per-world model rows and
its whole MjData, as the batch's last call left them). So every image is the one the CPU
environment renders from that world's state, bit for bit, with the CPU observable's dtype
and shape behind a leading num_envs axis: RGB (height, width, 3) uint8, depth (height,
width, 1) float32 metres, segmentation (height, width, 2) int32; each observable's
`scene_option` and `render_flag_overrides` apply as on the CPU.

The render thread. Every world renders on one worker thread, which owns the rendering
state: a copy of the model, an MjData and the OpenGL contexts of its renderers, current on
that thread only. The state is made on the thread when the cameras are made (so a missing
OpenGL fails there, naming `MUJOCO_GL`), reused by every `render`, and released on the
thread by `close` (`BatchEnvironment.close` calls it), which then ends the thread. One
thread, not one per core: two threads rendering at once, each with its own contexts,
crashed (a segmentation fault in `mjr_render` and `mjr_readPixels`) under Mesa's software
EGL in CI (2026-12-07), where one thread was also the faster (it spreads each frame over
the cores itself).

What a render context copies from the model when it is made (meshes, textures, `vis`,
plane sizes, materials' texture mapping: `mujoco_physics.render_inputs`) is refreshed world
by world only where the batch has per-world rows of such a field (its shared model stays
as compiled: `MujocoBatchPhysics` writes changes as rows); everything else
(colours, poses, lights) is read at every frame.
"""

from __future__ import annotations

import concurrent.futures
import copy
import functools
import weakref
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from composer.batch.mujoco_batch import batch_model_fields
from composer.observation.observable.mjcf import MJCFCamera
from mujoco_physics import engine
from mujoco_physics.render_inputs import held_by_context

__all__ = ["GLBatchCameras"]

Render = Callable[[], np.ndarray]


@functools.cache
def _context_fields() -> tuple[str, ...]:
    """The model fields `mujoco.batch` can give per-world rows that a render context copies
    when made."""
    return tuple(name for name in batch_model_fields() if held_by_context(name))


class _Worker:
    """One worker thread's rendering state: a Physics of its own and each observable's
    render function on it. Made, used and closed on that thread only."""

    def __init__(self, physics, observables: Mapping[str, MJCFCamera]):
        self._batch = physics.batch
        self.physics = engine.Physics.from_model(copy.copy(physics.mj_model))
        self._model, self._data = self.physics.model.ptr, self.physics.data.ptr
        self._renders: dict[str, Render] = {}
        for name, observable in observables.items():
            render = observable.observation_callable(self.physics)
            try:
                render()  # makes the renderer and its OpenGL context, on this thread
            except RuntimeError as error:
                raise RuntimeError(
                    f"camera observable {name!r} (OpenGL renders it on the CPU batch): {error}"
                ) from error
            self._renders[name] = render

    def render(self, worlds: Sequence[int], outputs: dict[str, np.ndarray], refresh: bool):
        """Renders every observable of each world in `worlds` into its row of `outputs`;
        `refresh` says the contexts may hold another world's model inputs."""
        batch, model, data, physics = self._batch, self._model, self._data, self.physics
        for world in worlds:
            batch.get_model(world, model)
            batch.get_data(world, data)
            if refresh:
                physics.model_changed_in_place()
            for name, render in self._renders.items():
                outputs[name][world] = render()

    def close(self) -> None:
        self.physics.free()


def _close(executor: concurrent.futures.ThreadPoolExecutor, workers: list) -> None:
    """Closes the worker (if made) on the render thread, then ends the thread."""
    try:
        future = executor.submit(workers[0].close) if workers else None
    except RuntimeError:
        # The interpreter is exiting: the thread has stopped, and the contexts go with
        # the process.
        future = None
    try:
        if future is not None:
            future.result()
    finally:
        workers.clear()
        executor.shutdown(wait=True)


class GLBatchCameras:
    """The camera observables of a CPU batch, rendered with OpenGL once per observation.

    The interface of `composer.batch.cameras.BatchCameras`; the images are exactly the CPU
    observables' (see the module docstring).

    Args:
      observables: the enabled camera observables by key.
      physics: the `MujocoBatchPhysics` whose worlds they see.

    Raises:
      RuntimeError: where no OpenGL context can be made; the message names the camera
        observable and `MUJOCO_GL`, and the values to try.
    """

    def __init__(self, observables: Mapping[str, MJCFCamera], physics):
        self._physics = physics
        self._observables = dict(observables)
        self._camera_ids = tuple(
            dict.fromkeys(
                int(physics.host.bind(o.mjcf_element).element_id)
                for o in self._observables.values()
            )
        )
        specs = {name: o.array_spec for name, o in self._observables.items()}
        self._outputs = {
            name: np.zeros((physics.num_envs, *spec.shape), spec.dtype)
            for name, spec in specs.items()
        }
        self._worlds = list(range(physics.num_envs))
        # The render thread (see the module docstring), and its worker once made: empty
        # before and after close.
        self._executor = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="gl_cameras")
        self._worker: list[_Worker] = []
        self._close = weakref.finalize(self, _close, self._executor, self._worker)
        made = self._executor.submit(_Worker, physics, self._observables)
        try:
            self._worker.append(made.result())
        except BaseException:
            self.close()
            raise

    @property
    def camera_ids(self) -> tuple[int, ...]:
        """The model ids of the cameras rendered: those some observable uses, once each."""
        return self._camera_ids

    @property
    def names(self) -> list[str]:
        """The keys of the camera observables, in the order given."""
        return list(self._observables)

    @property
    def threads(self) -> int:
        """The number of render threads that hold rendering state: 1, 0 once closed."""
        return len(self._worker)

    def dtype(self, name: str) -> np.dtype:
        """The NumPy dtype of the observable `name`'s images."""
        return self._outputs[name].dtype

    def render(self) -> None:
        """Renders every camera observable in every world, from the worlds' current data.

        Raises:
          RuntimeError: after `close`.
        """
        if not self.threads:
            raise RuntimeError("GLBatchCameras.render: the cameras were closed (close())")
        refresh = self._contexts_vary()
        worker = self._worker[0]
        self._executor.submit(worker.render, self._worlds, self._outputs, refresh).result()

    def _contexts_vary(self) -> bool:
        """Whether the batch has per-world rows of a field render contexts copy when made
        (fields expand while the batch runs: `set_shared_model_field`)."""
        batch = self._physics.batch
        return any(batch.expanded(name) is not None for name in _context_fields())

    def readers(self) -> dict[str, Callable[[], Any]]:
        """A reader per observable: the images of the last `render`, a NumPy view."""
        return {name: (lambda view=view: view) for name, view in self._outputs.items()}

    def close(self) -> None:
        """Releases the OpenGL contexts, on the render thread, and ends the thread. Safe
        to call twice."""
        self._close()
