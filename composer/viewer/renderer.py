"""dm_control compatibility, not this project's API: what code written for dm_control
(MoMa's rendering observer) uses of `dm_control.viewer.renderer`.

`Viewport` is an image size, `NullRenderer` a black placeholder image, and
`OffScreenRenderer` draws an `mujoco.MjvScene` into an image in an OpenGL context of its own
(the `MUJOCO_GL` backend). `SceneCamera` is the free camera that `viewer.Viewer` renders
from: `camera.settings` is its `mujoco.MjvCamera` (`lookat`, `distance`, `azimuth`,
`elevation`, ...).
"""

from __future__ import annotations

import mujoco
import numpy as np

# dm_control's default: the free camera starts this many scene extents away.
_FULL_SCENE_ZOOM_FACTOR = 1.5
# What makes a camera's view, besides `lookat`.
_CAMERA_FIELDS = ("type", "fixedcamid", "trackbodyid", "distance", "azimuth", "elevation")


def copy_camera(source: mujoco.MjvCamera, target: mujoco.MjvCamera | None = None):
    """Copies `source`'s mode and pose into `target` (a new camera by default); returns it."""
    target = mujoco.MjvCamera() if target is None else target
    for field in _CAMERA_FIELDS:
        setattr(target, field, getattr(source, field))
    target.lookat[:] = source.lookat
    return target


class Viewport:
    """The size of the image a viewer renders, in pixels."""

    def __init__(self, width: int = 1, height: int = 1):
        self._rect = mujoco.MjrRect(0, 0, 1, 1)
        self.set_size(width, height)

    def set_size(self, width: int, height: int) -> None:
        """Changes the size; both must be positive integers."""
        for name, value in (("width", width), ("height", height)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"Viewport {name}: expected a positive integer, got {value!r}")
        self._rect.width = int(width)
        self._rect.height = int(height)

    def screen_to_viewport(self, screen_coordinates) -> np.ndarray:
        """Pixel coordinates -> fractions of the width and height, in [0, 1]."""
        x, y = screen_coordinates
        return np.array([x / self.width, y / self.height], np.float32)

    def screen_to_inverse_viewport(self, screen_coordinates) -> np.ndarray:
        """Like `screen_to_viewport`, with y measured from the bottom (1 at the top)."""
        x, y = screen_coordinates
        return np.array([x / self.width, 1.0 - y / self.height], np.float32)

    @property
    def width(self) -> int:
        return self._rect.width

    @property
    def height(self) -> int:
        return self._rect.height

    @property
    def aspect_ratio(self) -> float:
        return self.width / self.height

    @property
    def dimensions(self) -> np.ndarray:
        """(width, height)."""
        return np.array([self.width, self.height])

    @property
    def mujoco_rect(self) -> mujoco.MjrRect:
        """The viewport as the `mujoco.MjrRect` that `mjr_render` takes."""
        return self._rect


class NullRenderer:
    """Stands in for a renderer before there is a model to render: one black pixel."""

    def __init__(self):
        self._pixels = np.zeros((1, 1, 3), np.uint8)

    @property
    def pixels(self) -> np.ndarray:
        return self._pixels

    def release(self) -> None:
        """Nothing to release."""


class OffScreenRenderer:
    """Renders scenes of `model` into `pixels`, (height, width, 3) uint8 rows bottom-up
    as OpenGL reads them.

    Args:
      model: The `mujoco.MjModel`, or a physics' model wrapper holding it as `ptr`.
      surface: dm_control's rendering context, accepted for its signature; this renderer
        makes an OpenGL context of its own, sized to the viewport.
    """

    def __init__(self, model, surface=None):
        del surface  # A context of our own: see the class docstring.
        self._model = getattr(model, "ptr", model)
        if not isinstance(self._model, mujoco.MjModel):
            raise TypeError(
                f"OffScreenRenderer: expected a mujoco.MjModel or a model wrapper with .ptr, "
                f"got {type(model).__name__}"
            )
        self._gl_context = None
        self._mjr_context = None
        self._size = None
        self._pixels = np.zeros((1, 1, 3), np.uint8)

    def render(self, viewport: Viewport, scene: mujoco.MjvScene) -> None:
        """Draws `scene` at the viewport's size; the image is then `pixels`."""
        size = (viewport.width, viewport.height)
        if size != self._size:
            self._make_contexts(*size)
        self._gl_context.make_current()
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._mjr_context)
        mujoco.mjr_render(viewport.mujoco_rect, scene, self._mjr_context)
        pixels = np.empty((viewport.height, viewport.width, 3), np.uint8)
        mujoco.mjr_readPixels(pixels, None, viewport.mujoco_rect, self._mjr_context)
        self._pixels = pixels

    def _make_contexts(self, width: int, height: int) -> None:
        self.release()
        # MuJoCo's offscreen framebuffer is sized from the model: make room for the viewport.
        buffer = self._model.vis.global_
        buffer.offwidth = max(buffer.offwidth, width)
        buffer.offheight = max(buffer.offheight, height)
        self._gl_context = mujoco.GLContext(buffer.offwidth, buffer.offheight)
        self._gl_context.make_current()
        self._mjr_context = mujoco.MjrContext(
            self._model, mujoco.mjtFontScale.mjFONTSCALE_150.value
        )
        self._size = (width, height)

    @property
    def pixels(self) -> np.ndarray:
        """The last image rendered (one black pixel before the first)."""
        return self._pixels

    def release(self) -> None:
        """Frees the OpenGL resources; the next `render` makes new ones."""
        if self._mjr_context is not None:
            self._gl_context.make_current()
            self._mjr_context.free()
            self._mjr_context = None
        if self._gl_context is not None:
            self._gl_context.free()
            self._gl_context = None
        self._size = None


class SceneCamera:
    """The free camera a `viewer.Viewer` renders from, and the scene it fills.

    Args:
      model, data: The `mujoco.MjModel` / `mujoco.MjData` (or wrappers with `ptr`).
      settings: A `mujoco.MjvCamera` to copy the pose from; by default the free camera
        looks at the model's centre from `zoom_factor` times its extent.
      zoom_factor: Distance of the default view and of `zoom_to_scene`, in scene extents.
      scene_callback: Called as `scene_callback(model, data, scene)` after each scene update.
    """

    def __init__(
        self,
        model,
        data,
        settings: mujoco.MjvCamera | None = None,
        zoom_factor: float = _FULL_SCENE_ZOOM_FACTOR,
        scene_callback=None,
    ):
        self._model = getattr(model, "ptr", model)
        self._data = getattr(data, "ptr", data)
        self._zoom_factor = zoom_factor
        self._scene_callback = scene_callback
        m = self._model
        self._scene = mujoco.MjvScene(m, maxgeom=2 * (m.ngeom + m.nsite + m.njnt + m.nbody) + 1000)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        mujoco.mjv_defaultFreeCamera(self._model, self._camera)
        if settings is not None:
            self.settings = settings
        else:
            self.zoom_to_scene()

    @property
    def settings(self) -> mujoco.MjvCamera:
        """The camera itself: its fields can be set in place."""
        return self._camera

    @settings.setter
    def settings(self, value: mujoco.MjvCamera) -> None:
        copy_camera(value, self._camera)

    def zoom_to_scene(self) -> None:
        """Looks at the model's centre from `zoom_factor` times its extent."""
        self._camera.lookat[:] = self._model.stat.center
        self._camera.distance = self._zoom_factor * self._model.stat.extent

    def render(self, perturbation=None) -> mujoco.MjvScene:
        """Updates the scene from the current state; returns it."""
        del perturbation  # Objects are not dragged with the mouse here.
        mujoco.mjv_updateScene(
            self._model,
            self._data,
            self._option,
            None,
            self._camera,
            mujoco.mjtCatBit.mjCAT_ALL.value,
            self._scene,
        )
        if self._scene_callback is not None:
            self._scene_callback(self._model, self._data, self._scene)
        return self._scene
