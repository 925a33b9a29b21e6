"""dm_control compatibility, not this project's API: `dm_control.viewer.viewer.Viewer`, as
code written for dm_control (MoMa's rendering observer) uses it.

A `Viewer` renders a physics from its free camera into a renderer: `initialize(physics,
renderer, touchpad)` binds them, `render()` draws the current state (the image is then
`renderer.pixels`), `deinitialize()` unbinds them and keeps the camera pose for the next
`initialize`. The camera moves through `viewer.camera.settings` (a `mujoco.MjvCamera`);
mouse and keyboard input are not handled (for an interactive window use
`composer.viewer.launch`).
"""

from __future__ import annotations

import mujoco

from composer.viewer import renderer


class Viewer:
    """Renders a physics from a free camera into a renderer, at the viewport's size.

    Args:
      viewport: A `renderer.Viewport`: the size of the images.
      mouse, keyboard: A window's input devices, accepted for dm_control's signature and
        not used.
      camera_settings: A `mujoco.MjvCamera` whose pose the camera starts from.
      zoom_factor: Distance of the default view, in scene extents.
      scene_callback: Called as `scene_callback(model, data, scene)` before each render.
    """

    def __init__(
        self,
        viewport: renderer.Viewport,
        mouse=None,
        keyboard=None,
        camera_settings: mujoco.MjvCamera | None = None,
        zoom_factor: float = renderer._FULL_SCENE_ZOOM_FACTOR,
        scene_callback=None,
    ):
        del mouse, keyboard  # See the class docstring.
        self._viewport = viewport
        self._camera_settings = camera_settings
        self._zoom_factor = zoom_factor
        self._scene_callback = scene_callback
        self._camera = None
        self._renderer = None

    def initialize(self, physics, renderer_instance, touchpad: bool = False) -> None:
        """Renders `physics` into `renderer_instance` from now on."""
        del touchpad  # No input handling: see the class docstring.
        self._camera = renderer.SceneCamera(
            physics.model,
            physics.data,
            settings=self._camera_settings,
            zoom_factor=self._zoom_factor,
            scene_callback=self._scene_callback,
        )
        self._renderer = renderer_instance

    def deinitialize(self) -> None:
        """Lets go of the physics and renderer; the camera pose is kept for the next one."""
        if self._camera is not None:
            self._camera_settings = renderer.copy_camera(self._camera.settings)
        self._camera = None
        self._renderer = None

    def render(self) -> None:
        """Draws the physics' current state into the renderer (nothing before `initialize`)."""
        if self._camera is not None and self._renderer is not None:
            self._renderer.render(self._viewport, self._camera.render())

    def zoom_to_scene(self) -> None:
        """Points the camera at the whole model."""
        if self._camera is not None:
            self._camera.zoom_to_scene()

    @property
    def camera(self) -> renderer.SceneCamera | None:
        """The camera, between `initialize` and `deinitialize`; None otherwise."""
        return self._camera
