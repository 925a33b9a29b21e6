"""dm_control's cameras on a Physics: `Camera` (a fixed or free camera that renders, projects
and selects), `MovableCamera` (a free camera with a pose) and `TextOverlay`.

Each camera owns its scene (`mujoco.MjvScene`) and options, so its flags persist between
renders, as in dm_control; it draws with the Physics' `mujoco.Renderer` of its image size,
whose OpenGL context all cameras and `Physics.render` of that size share (as dm_control's
cameras share `physics.contexts`), so making a camera makes no context. `Physics.render`
uses a camera for what its per-size renderers cannot do (text overlays, scene callbacks).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, NamedTuple

import mujoco
import numpy as np

from mujoco_physics.rendering import (
    camera_index,
    check_render_request,
    frame_limit_error,
    overridden_flags,
)

if TYPE_CHECKING:
    from mujoco_physics.engine import Physics

SceneCallback = Callable[["Physics", mujoco.MjvScene], None]

_FONTS = {"normal": mujoco.mjtFont.mjFONT_NORMAL, "big": mujoco.mjtFont.mjFONT_BIG}
_POSITIONS = {
    name[len("mjGRID_") :]
    .lower()
    .replace("top", "top ")
    .replace("bottom", "bottom ")
    .strip(): value
    for name, value in mujoco.mjtGridPos.__members__.items()
}


class CameraMatrices(NamedTuple):
    """The factors of a camera's 3x4 projection `image @ focal @ rotation @ translation`,
    which maps homogeneous world points to homogeneous pixel coordinates (x right, y down).

    Attributes:
      image: (3, 3) moves the origin to the image centre.
      focal: (3, 4) scales by the focal length in pixels.
      rotation: (4, 4) world axes to camera axes.
      translation: (4, 4) moves the camera to the origin.
    """

    image: np.ndarray
    focal: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray


class Pose(NamedTuple):
    """A free camera's pose: the point it looks at, its distance from it (m), and its
    azimuth and elevation (degrees)."""

    lookat: np.ndarray
    distance: float
    azimuth: float
    elevation: float


class Selected(NamedTuple):
    """What is under a cursor: ids of the body, geom and skin (None where nothing), and the
    world position hit (None for the background)."""

    body: int | None
    geom: int | None
    skin: int | None
    world_position: np.ndarray | None


class TextOverlay:
    """A title and body of text drawn over a rendered image.

    Args:
      title, body: the two columns of text.
      style: 'normal' or 'big'.
      position: 'top left', 'top right', 'bottom left', 'bottom right', 'top', 'bottom',
        'left' or 'right'.

    Raises:
      ValueError: for an unknown style or position.
    """

    def __init__(
        self, title: str = "", body: str = "", style: str = "normal", position: str = "top left"
    ):
        if style not in _FONTS:
            raise ValueError(f"style: expected one of {sorted(_FONTS)}, got {style!r}")
        if position not in _POSITIONS:
            raise ValueError(f"position: expected one of {sorted(_POSITIONS)}, got {position!r}")
        self.title = title
        self.body = body
        self.style = _FONTS[style]
        self.position = _POSITIONS[position]

    def draw(self, context: mujoco.MjrContext, rect: mujoco.MjrRect) -> None:
        """Draws the text into `rect` of the current framebuffer."""
        mujoco.mjr_overlay(self.style, self.position, rect, self.title, self.body, context)


class Camera:
    """A camera of a Physics that renders images, projects points and selects objects.

    Args:
      physics: the Physics to look at.
      height, width: image size in pixels, at most the model's offscreen buffer.
      camera_id: a camera's index or name; -1 is the free camera.
      max_geom: how many geoms the scene holds (default: enough for the model).
      scene_callback: called as `scene_callback(physics, scene)` after each scene update,
        before rendering, e.g. to add geoms.

    Raises:
      ValueError: for an unknown camera or an image larger than the offscreen buffer.
    """

    def __init__(
        self,
        physics: Physics,
        height: int = 240,
        width: int = 320,
        camera_id: int | str = -1,
        max_geom: int | None = None,
        scene_callback: SceneCallback | None = None,
    ):
        model = physics.model.ptr
        buffer = model.vis.global_
        if height > buffer.offheight or width > buffer.offwidth:
            raise frame_limit_error(height, width, buffer)
        camera_id = camera_index(model, camera_id)
        self._physics = physics
        self._scene_callback = scene_callback
        self._height, self._width = int(height), int(width)
        geoms = max_geom or 2 * (model.ngeom + model.nsite + model.njnt + model.nbody) + 1000
        self._scene = mujoco.MjvScene(model, maxgeom=geoms)
        self._option = mujoco.MjvOption()
        self._perturb = mujoco.MjvPerturb()
        self._camera = mujoco.MjvCamera()
        if camera_id == -1:
            mujoco.mjv_defaultFreeCamera(model, self._camera)
        else:
            self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            self._camera.fixedcamid = camera_id

    @property
    def width(self) -> int:
        return self._width

    @property
    def height(self) -> int:
        return self._height

    @property
    def option(self) -> mujoco.MjvOption:
        """The visualisation options used at each update (frames, groups, flags)."""
        return self._option

    @property
    def scene(self) -> mujoco.MjvScene:
        """The scene; its `flags` (wireframe, shadows, ...) persist between renders."""
        return self._scene

    def update(self, scene_option: mujoco.MjvOption | None = None) -> None:
        """Updates the scene from the physics' current state."""
        physics = self._physics
        mujoco.mjv_updateScene(
            physics.model.ptr,
            physics.data.ptr,
            scene_option or self._option,
            self._perturb,
            self._camera,
            mujoco.mjtCatBit.mjCAT_ALL,
            self.scene,
        )
        if self._scene_callback is not None:
            self._scene_callback(physics, self.scene)

    def matrices(self) -> CameraMatrices:
        """The factors of the camera's projection at the current state (see
        `CameraMatrices`)."""
        self.update()
        eyes = self.scene.camera
        position = (eyes[0].pos + eyes[1].pos) / 2
        forward, up = eyes[0].forward, eyes[0].up
        rotation = np.eye(4)
        rotation[:3, :3] = [np.cross(forward, up), up, -forward]
        translation = np.eye(4)
        translation[:3, 3] = -position
        focal_length = 0.5 * self.height * eyes[0].frustum_near / eyes[0].frustum_top
        focal = np.diag([-focal_length, focal_length, 1.0, 0.0])[:3]
        image = np.eye(3)
        image[:2, 2] = (self.width - 1) / 2, (self.height - 1) / 2
        return CameraMatrices(image, focal, rotation, translation)

    @property
    def matrix(self) -> np.ndarray:
        """The (3, 4) projection of homogeneous world points to pixel coordinates."""
        image, focal, rotation, translation = self.matrices()
        return image @ focal @ rotation @ translation

    def render(
        self,
        overlays: Sequence[TextOverlay] = (),
        depth: bool = False,
        segmentation: bool = False,
        scene_option: mujoco.MjvOption | None = None,
        render_flag_overrides: dict | None = None,
    ) -> np.ndarray:
        """Renders the camera's view (see `Physics.render` for the arguments and shapes).

        Raises:
          ValueError: for depth with segmentation, or overlays or flag overrides with
            either.
        """
        check_render_request(depth, segmentation, bool(overlays), bool(render_flag_overrides))
        self.update(scene_option)
        renderer = self._physics._offscreen_renderer(self._height, self._width)
        if overlays:
            with overridden_flags(self.scene.flags, render_flag_overrides):
                return self._render_with_overlays(renderer, overlays)
        # The shared renderer draws this camera's scene: its own is put back afterwards.
        own_scene = renderer._scene
        renderer._scene = self._scene
        with overridden_flags(self.scene.flags, render_flag_overrides):
            if depth:
                renderer.enable_depth_rendering()
            elif segmentation:
                renderer.enable_segmentation_rendering()
            try:
                return renderer.render()
            finally:
                renderer.disable_depth_rendering()
                renderer.disable_segmentation_rendering()
                renderer._scene = own_scene

    def _render_with_overlays(
        self, renderer: mujoco.Renderer, overlays: Sequence[TextOverlay]
    ) -> np.ndarray:
        # mujoco.Renderer reads the pixels right after mjr_render: draw the text in between.
        renderer._gl_context.make_current()
        context = renderer._mjr_context
        rect = mujoco.MjrRect(0, 0, self.width, self.height)
        mujoco.mjr_render(rect, self.scene, context)
        for overlay in overlays:
            overlay.draw(context, rect)
        pixels = np.empty((self.height, self.width, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(pixels, None, rect, context)
        return np.flipud(pixels)

    def select(self, cursor_position: Sequence[float]) -> Selected:
        """What the ray through `cursor_position` hits first.

        Args:
          cursor_position: (x, y) in [0, 1], from the image's bottom-left corner.
        """
        self.update()
        physics = self._physics
        point = np.empty(3)
        geom, flex, skin = (np.full(1, -1, dtype=np.int32) for _ in range(3))
        body = mujoco.mjv_select(
            physics.model.ptr,
            physics.data.ptr,
            self._option,
            self.width / self.height,
            float(cursor_position[0]),
            float(cursor_position[1]),
            self.scene,
            point,
            geom,
            flex,
            skin,
        )

        def _id(value: int) -> int | None:
            return None if value < 0 else int(value)

        return Selected(_id(body), _id(geom[0]), _id(skin[0]), point if body >= 0 else None)

    def close(self) -> None:
        """Does nothing: the renderer and its OpenGL context belong to the Physics (released
        by `physics.free()`); kept for dm_control's API."""


class MovableCamera(Camera):
    """A free camera whose pose can be read and set (see `Pose`)."""

    def __init__(
        self, physics: Physics, height: int = 240, width: int = 320, max_geom: int | None = None
    ):
        super().__init__(physics, height, width, camera_id=-1, max_geom=max_geom)

    def get_pose(self) -> Pose:
        """The camera's current pose."""
        camera = self._camera
        return Pose(camera.lookat.copy(), camera.distance, camera.azimuth, camera.elevation)

    def set_pose(self, lookat, distance: float, azimuth: float, elevation: float) -> None:
        """Points the camera at `lookat` from `distance` m, at `azimuth` and
        `elevation` degrees."""
        camera = self._camera
        np.copyto(camera.lookat, lookat)
        camera.distance = distance
        camera.azimuth = azimuth
        camera.elevation = elevation


__all__ = ["Camera", "CameraMatrices", "MovableCamera", "Pose", "Selected", "TextOverlay"]
