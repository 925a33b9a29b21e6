"""dm_control compatibility, not this project's API: `dm_control.viewer.gui.RenderWindow`, as
code written for dm_control (MoMa's rendering observer) uses it.

A `RenderWindow` is a GLFW window that shows the images a render function returns:
`update(render_func)` draws one and handles the window's events. It needs a display (on a
headless machine, run under Xvfb), and to render what it shows with
`renderer.OffScreenRenderer` set `MUJOCO_GL=glfw`: some drivers (Mesa's, under Xvfb) refuse
a GLX window and an EGL context in one process. Mouse and keyboard input are not handled:
`mouse` and `keyboard` are None (for an interactive window use `composer.viewer.launch`).
"""

from __future__ import annotations

from collections.abc import Callable

import glfw
import mujoco
import numpy as np


class RenderWindow:
    """A window showing images, (height, width, 3) uint8 with rows bottom-up as OpenGL
    reads them (what `renderer.OffScreenRenderer.pixels` holds).

    Raises:
      RuntimeError: If GLFW cannot start (no display) or cannot open the window.
    """

    def __init__(self, width: int, height: int, title: str):
        if not glfw.init():
            raise RuntimeError(
                "RenderWindow: GLFW could not start; it needs a display (set DISPLAY, or run "
                "under Xvfb)"
            )
        self._window = glfw.create_window(int(width), int(height), str(title), None, None)
        if not self._window:
            raise RuntimeError(f"RenderWindow: GLFW could not open a {width}x{height} window")
        glfw.make_context_current(self._window)
        # mjr_drawPixels needs a MuJoCo context in the window's OpenGL context; any model does.
        self._mjr_context = mujoco.MjrContext(
            mujoco.MjModel.from_xml_string("<mujoco/>"), mujoco.mjtFontScale.mjFONTSCALE_100.value
        )

    @property
    def shape(self) -> tuple[int, int]:
        """The framebuffer's (width, height) in pixels."""
        return tuple(glfw.get_framebuffer_size(self._window))

    @property
    def position(self) -> tuple[int, int]:
        """The window's top-left corner on the screen, (x, y)."""
        return tuple(glfw.get_window_pos(self._window))

    @property
    def mouse(self) -> None:
        """No input devices here: see the module docstring."""
        return None

    @property
    def keyboard(self) -> None:
        """No input devices here: see the module docstring."""
        return None

    @property
    def should_close(self) -> bool:
        """Whether the user asked to close the window (or it is closed)."""
        return self._window is None or bool(glfw.window_should_close(self._window))

    def set_title(self, title: str) -> None:
        glfw.set_window_title(self._window, str(title))

    def update(self, render_func: Callable[[], np.ndarray]) -> None:
        """Shows the image `render_func()` returns, at the bottom-left, and handles events."""
        if self._window is None:
            raise RuntimeError("RenderWindow.update: the window is closed")
        pixels = np.ascontiguousarray(render_func(), dtype=np.uint8)
        if pixels.ndim != 3 or pixels.shape[2] != 3:
            raise ValueError(
                f"RenderWindow.update: expected an image of shape (height, width, 3), "
                f"got shape {pixels.shape}"
            )
        glfw.make_context_current(self._window)
        width, height = self.shape
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_WINDOW, self._mjr_context)
        mujoco.mjr_rectangle(mujoco.MjrRect(0, 0, width, height), 0, 0, 0, 1)
        rect = mujoco.MjrRect(0, 0, pixels.shape[1], pixels.shape[0])
        mujoco.mjr_drawPixels(pixels.ravel(), None, rect, self._mjr_context)
        glfw.swap_buffers(self._window)
        glfw.poll_events()

    def event_loop(self, tick_func: Callable[[], np.ndarray]) -> None:
        """Calls `update(tick_func)` until the window is closed."""
        while not self.should_close:
            self.update(tick_func)

    def close(self) -> None:
        """Closes the window; idempotent."""
        if self._window is not None:
            glfw.make_context_current(self._window)
            self._mjr_context.free()
            glfw.destroy_window(self._window)
            self._window = None

    def free(self) -> None:
        """Same as `close` (dm_control's name)."""
        self.close()
