"""composer.viewer.gui.RenderWindow (dm_control compatibility): a window showing the images a
`viewer.Viewer` renders, on a virtual X display."""

import os
import pathlib
import subprocess
import sys
import textwrap

import numpy as np
import pytest

pytest.importorskip("glfw", reason="glfw (a mujoco dependency) cannot be imported")

_REPO = pathlib.Path(__file__).resolve().parents[3]

# MoMa's rendering observer, reduced to its calls: a window, a viewer on its input devices,
# an offscreen renderer, and one `update` per step that renders at the window's size.
_OBSERVER = """
import sys
import mjcf
from composer.viewer import gui, renderer, viewer

model = mjcf.RootElement(model="ball")
model.visual.headlight.ambient = [1, 1, 1]
model.visual.headlight.diffuse = [0, 0, 0]
model.worldbody.add("geom", type="sphere", size=[0.1], rgba=[1, 0, 0, 1])
physics = mjcf.Physics.from_mjcf_model(model)

window = gui.RenderWindow(80, 60, "observer")
viewport = renderer.Viewport(80, 60)
offscreen = renderer.OffScreenRenderer(physics.model, None)
view = viewer.Viewer(viewport, window.mouse, window.keyboard)
view.initialize(physics, offscreen, False)
view.camera.settings.lookat[:] = [0, 0, 0]
view.camera.settings.distance = 0.2

def render():
    viewport.set_size(*window.shape)
    view.render()
    return offscreen.pixels

for _ in range(3):
    window.update(render)
print(window.shape, flush=True)
sys.stdin.readline()
window.close()
window.close()
print("closed", flush=True)
"""


def _red_pixels(display):
    image_grab = pytest.importorskip("PIL.ImageGrab", reason="Pillow is not installed")
    screen = np.asarray(image_grab.grab(xdisplay=display).convert("RGB")).astype(int)
    return int(((screen[..., 0] > 200) & (screen[..., 1] < 50) & (screen[..., 2] < 50)).sum())


def test_window_shows_what_the_viewer_renders_and_closes(display):
    process = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(_OBSERVER)],
        cwd=_REPO,
        env=dict(os.environ, DISPLAY=display, MUJOCO_GL="glfw"),
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        shape = process.stdout.readline().strip()
        assert shape == "(80, 60)", process.stderr.read() if not shape else shape
        # The ball fills the middle of the 80x60 window: most of it, not more than all of it.
        assert 0.5 * 80 * 60 < _red_pixels(display) <= 80 * 60
        stdout, stderr = process.communicate("\n", timeout=30)
    finally:
        process.kill()
    assert process.returncode == 0, stderr
    assert stdout.strip() == "closed"


def test_window_without_a_display_is_a_clear_error():
    result = subprocess.run(
        [sys.executable, "-c", "from composer.viewer import gui; gui.RenderWindow(8, 8, 't')"],
        cwd=_REPO,
        env={k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")},
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 1
    assert "RuntimeError: RenderWindow: GLFW could not start" in result.stderr
