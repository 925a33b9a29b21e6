"""Off-screen rendering for `Physics.render`: one `mujoco.Renderer` per image size."""

import contextlib
from collections.abc import Callable, Iterator
from typing import NamedTuple

import mujoco
import numpy as np

from mujoco_physics import _gl_backend
from mujoco_physics.render_inputs import RenderInputs, upload_asset_family

_RENDER_FLAG_PREFIX = "mjRND_"

# Messages of the render-request checks, under the names dm_control's tests read them from.
BOTH_SEGMENTATION_AND_DEPTH_ENABLED = "depth and segmentation cannot both be requested"
OVERLAYS_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION = (
    "overlays only apply to RGB images, not to depth or segmentation"
)
RENDER_FLAG_OVERRIDES_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION = (
    "render_flag_overrides only apply to RGB images"
)


def check_render_request(
    depth: bool, segmentation: bool, overlays: bool, render_flag_overrides: bool
) -> None:
    """Raises ValueError for an image kind combined with what it cannot have."""
    if depth and segmentation:
        raise ValueError(BOTH_SEGMENTATION_AND_DEPTH_ENABLED)
    if overlays and (depth or segmentation):
        raise ValueError(OVERLAYS_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION)
    if render_flag_overrides and (depth or segmentation):
        raise ValueError(RENDER_FLAG_OVERRIDES_NOT_SUPPORTED_FOR_DEPTH_OR_SEGMENTATION)


def camera_index(model: mujoco.MjModel, camera_id) -> int:
    """A camera index from a camera name or index; -1 is the free camera.

    Raises:
      ValueError: for an unknown name or an index outside [-1, ncam).
    """
    if isinstance(camera_id, str):
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera_id)
        if index < 0:
            raise ValueError(f"camera_id {camera_id!r}: the model has no camera of that name")
        return index
    index = int(camera_id)
    if not -1 <= index < model.ncam:
        raise ValueError(
            f"camera_id {camera_id}: expected -1 (free camera) or a camera index below {model.ncam}"
        )
    return index


def frame_limit_error(height: int, width: int, buffer) -> ValueError:
    """The error for an image larger than the model's offscreen buffer (`vis.global_`)."""
    return ValueError(
        f"image of height {height} and width {width} exceeds the model's "
        f"offscreen buffer ({buffer.offheight} by {buffer.offwidth}); raise "
        "<visual><global offheight=... offwidth=.../></visual> in the model"
    )


@contextlib.contextmanager
def overridden_flags(flags: np.ndarray, overrides: dict | None) -> Iterator[None]:
    """Sets scene render `flags` from `overrides` ({name or mjtRndFlag: bool}) inside
    the block and restores them after."""
    saved = flags.copy()
    try:
        for flag, value in (overrides or {}).items():
            flags[render_flag(flag)] = bool(value)
        yield
    finally:
        flags[:] = saved


def render_flag(flag) -> int:
    """An `mjtRndFlag` index from a flag name ('wireframe') or value."""
    if isinstance(flag, str):
        member = f"{_RENDER_FLAG_PREFIX}{flag.upper()}"
        if member not in mujoco.mjtRndFlag.__members__:
            known = sorted(
                name[len(_RENDER_FLAG_PREFIX) :].lower()
                for name in mujoco.mjtRndFlag.__members__
                if name.startswith(_RENDER_FLAG_PREFIX)
            )
            raise ValueError(f"unknown render flag {flag!r}; expected one of {known}")
        return int(mujoco.mjtRndFlag.__members__[member])
    return int(flag)


class Renderers:
    """Renders one model's scenes, keeping a `mujoco.Renderer` per (height, width).

    A renderer's context holds what it read from the model when it was made
    (`mujoco_physics.render_inputs`). After `model_changed()`, the next use compares the
    model with what the contexts hold: changed meshes, height fields or textures are
    uploaded again into every context; any other change of what a context holds (`vis`,
    the extent, planes, materials' texture mapping, skins) closes the renderers, so that
    new ones are made from the model as it is. Anything else (colours, poses) costs
    nothing: images always equal those of renderers made afresh from the model.
    """

    def __init__(self, model: mujoco.MjModel):
        self._model = model
        self._renderers = {}
        # What the contexts read from the model; None while there are no renderers.
        self._inputs: RenderInputs | None = None
        self._model_changed = False

    def model_changed(self) -> None:
        """Says the model may have changed in place: the next use refreshes the contexts
        where what they hold differs from the model."""
        self._model_changed = True

    def _refresh(self) -> None:
        if not self._model_changed:
            return
        self._model_changed = False
        if self._inputs is None:
            return
        if self._inputs.context_is_stale(self._model):
            self.close()
            return
        stale = self._inputs.stale_assets(self._model)
        if not stale:
            return
        for renderer in self._renderers.values():
            renderer._gl_context.make_current()
            for prefix in stale:
                upload_asset_family(self._model, renderer._mjr_context, prefix)
        self._inputs = RenderInputs.of(self._model)

    def camera_id(self, camera_id) -> int:
        """A camera index from a camera name or index (see `camera_index`)."""
        return camera_index(self._model, camera_id)

    def render(
        self,
        data: mujoco.MjData,
        height: int,
        width: int,
        camera_id,
        depth: bool,
        segmentation: bool,
        scene_option,
        render_flag_overrides,
    ) -> np.ndarray:
        """RGB (H, W, 3) uint8, depth (H, W) float32 in metres, or segmentation (H, W, 2).

        Segmentation pixels hold (object id, `mjtObj` type); background is (-1, -1).
        """
        check_render_request(depth, segmentation, False, bool(render_flag_overrides))
        camera = self.camera_id(camera_id)
        renderer = self.renderer(height, width)
        renderer.update_scene(data, camera=camera, scene_option=scene_option)
        if depth:
            renderer.enable_depth_rendering()
        elif segmentation:
            renderer.enable_segmentation_rendering()
        try:
            with overridden_flags(renderer.scene.flags, render_flag_overrides):
                return renderer.render()
        finally:
            if depth:
                renderer.disable_depth_rendering()
            elif segmentation:
                renderer.disable_segmentation_rendering()

    def contexts(self) -> "Contexts | None":
        """dm_control's `physics.contexts` over these renderers, or None before the first
        render (a renderer made later uploads the model's current assets itself)."""
        self._refresh()
        if not self._renderers:
            return None
        return Contexts(gl=_AllGLContexts(list(self._renderers.values())), mujoco=MJR_CONTEXT)

    def close(self) -> None:
        """Releases every renderer and its OpenGL context."""
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers.clear()
        self._inputs = None

    def renderer(self, height: int, width: int) -> mujoco.Renderer:
        """The renderer of images of (`height`, `width`), made on first use.

        Raises:
          ValueError: for an image larger than the model's offscreen buffer.
        """
        self._refresh()
        key = (int(height), int(width))
        renderer = self._renderers.get(key)
        if renderer is None:
            # Checked here, not left to mujoco.Renderer: before mujoco 3.8 its own check
            # left a half-built Renderer whose finaliser raised.
            buffer = self._model.vis.global_
            if key[0] > buffer.offheight or key[1] > buffer.offwidth:
                raise frame_limit_error(key[0], key[1], buffer)
            renderer = _gl_backend.new_renderer(self._model, height=key[0], width=key[1])
            if self._inputs is None:
                self._inputs = RenderInputs.of(self._model)
            self._renderers[key] = renderer
        return renderer


class _MjrContextPlaceholder:
    """Stands for "each renderer's `MjrContext`" in the arguments of `_Caller.call`."""

    @property
    def ptr(self) -> "_MjrContextPlaceholder":
        return self


MJR_CONTEXT = _MjrContextPlaceholder()


class Contexts(NamedTuple):
    """What dm_control code reaches through `physics.contexts` to re-upload changed assets:
    `with contexts.gl.make_current() as ctx: ctx.call(mujoco.mjr_uploadHField,
    model, contexts.mujoco.ptr, hfield_id)` runs the upload in every renderer's context."""

    gl: "_AllGLContexts"
    mujoco: _MjrContextPlaceholder


class _Caller(NamedTuple):
    renderers: list

    def call(self, function: Callable, *args):
        """Calls `function` once per renderer, with its GL context current and
        `contexts.mujoco.ptr` replaced by its `MjrContext`; returns the last result."""
        result = None
        for renderer in self.renderers:
            renderer._gl_context.make_current()
            result = function(
                *(renderer._mjr_context if arg is MJR_CONTEXT else arg for arg in args)
            )
        return result


class _AllGLContexts(NamedTuple):
    renderers: list

    @contextlib.contextmanager
    def make_current(self) -> Iterator[_Caller]:
        yield _Caller(self.renderers)
